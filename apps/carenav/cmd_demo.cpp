// carenav demo: the main job on embedded defaults.
#include "commands.h"

#include <carenav/common/errors.h>
#include <carenav/io/rawlog_info.h>

#include <filesystem>
#include <iostream>

namespace carenav::app {

namespace {
void addDemoCommand(CLI::App& app, const GlobalOptions& g) {
  auto* cmd = app.add_subcommand(
      "demo",
      "Run the main job on embedded defaults, on MRPT's real SENA rawlog (a loop through the "
      "Telecom faculty of the University of Malaga, laser + odometry). For now: summarise the "
      "rawlog; later stages (map, rooms, navigation) join as they land.");
  auto rawlog = std::make_shared<std::string>();
  cmd->add_option("--rawlog", *rawlog, "Rawlog to use instead of MRPT's SENA dataset");
  cmd->callback([rawlog, &g] {
    std::string path = *rawlog;
    if (path.empty()) {
      path = mrptDatasetsDir() + "/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog";
      if (!std::filesystem::exists(path))
        throw InputError(path +
                         ": MRPT's dataset is missing; install Debian's mrpt-common "
                         "(scripts/setup.sh does) or set CARENAV_MRPT_DATASETS");
    }
    if (!g.quiet) std::cerr << "[demo] step 1/1: rawlog summary of " << path << "\n";
    const io::RawlogInfo ri = io::summarizeRawlog(path, !g.quiet);
    std::cout << ri.toText() << std::flush;
    if (ri.error) throw InputError(*ri.error);
  });
}
}  // namespace

CARENAV_COMMAND(200, addDemoCommand);

}  // namespace carenav::app
