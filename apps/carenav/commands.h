// Subcommands of the carenav executable. Each cmd_*.cpp file adds one command
// to the CLI11 app and registers itself here; all logic lives in the modules.
#pragma once

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace carenav::app {

/** Options every command shares. */
struct GlobalOptions {
  bool quiet = false;  ///< no progress, no chatter on stderr
};

/** Adds a command to the app. Its callback runs the command and throws
 *  carenav::InputError (exit 2) or std::exception (exit 1). */
using CommandAdder = void (*)(CLI::App& app, const GlobalOptions& g);

/** Registered commands, in help order. */
std::vector<std::pair<int, CommandAdder>>& commandRegistry();
/** Registered `carenav import <format>` subcommands. */
std::vector<CommandAdder>& importRegistry();

struct CommandRegistrar {
  CommandRegistrar(int order, CommandAdder f) { commandRegistry().emplace_back(order, f); }
};
struct ImportRegistrar {
  explicit ImportRegistrar(CommandAdder f) { importRegistry().push_back(f); }
};

/** In a cmd_*.cpp: CARENAV_COMMAND(30, addSlamCommand); the order sorts --help.
 *  Orders: profile 10, rawlog 20, slam 30, localize 40, perceive 50,
 *  navigate 60, places 70, import 80, eval 90, simulate 100, demo 200. */
#define CARENAV_COMMAND(order, fn) \
  static const ::carenav::app::CommandRegistrar carenav_cmd_registrar_##fn(order, fn)
/** In a cmd_import_*.cpp: CARENAV_IMPORT(addImportCarmen); `fn` receives the
 *  `import` subcommand as its app. */
#define CARENAV_IMPORT(fn) \
  static const ::carenav::app::ImportRegistrar carenav_import_registrar_##fn(fn)

/** An output folder given by the user (`--out DIR`), made ready before any
 *  work: created with its parents and tried with a file. Throws InputError
 *  (exit 2) naming the option, the folder and why ("/x is a file, not a
 *  folder", "cannot create it in /proc: No such file or directory", "cannot
 *  write in it: Permission denied"). */
void prepareOutputFolder(const std::string& dir, const std::string& option = "--out");
/** An output file given by the user: its folder must exist and take a file,
 *  and the path must not be a folder. Throws InputError like the above. */
void prepareOutputFile(const std::string& path, const std::string& option = "--out");

/** Where MRPT's datasets are: $CARENAV_MRPT_DATASETS, else the build-time path. */
std::string mrptDatasetsDir();

/** The rooms and places of maps/sena.places.yaml, embedded at build time
 *  (the demo annotates its map of the SENA rawlog with them). */
const char* senaPlacesYaml();
/** ini/defaults.ini and ini/isr-aiwalker.ini, embedded at build time (the
 *  demo's walker run). */
const char* defaultsIni();
const char* walkerIni();

}  // namespace carenav::app
