// Subcommands of the carenav executable. Each file adds one command to the
// CLI11 app; all logic lives in the modules.
#pragma once

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace carenav::app {

/** Options every command shares. */
struct GlobalOptions {
  bool quiet = false;  ///< no progress, no chatter on stderr
};

/** Each returns the subcommand it added; its callback runs the command and
 *  throws carenav::InputError (exit 2) or std::exception (exit 1). */
CLI::App* addProfileCommand(CLI::App& app, const GlobalOptions& g);
CLI::App* addRawlogCommand(CLI::App& app, const GlobalOptions& g);
CLI::App* addDemoCommand(CLI::App& app, const GlobalOptions& g);

/** Where MRPT's datasets are: $CARENAV_MRPT_DATASETS, else the build-time path. */
std::string mrptDatasetsDir();

}  // namespace carenav::app
