// carenav: mapping, localisation and navigation for assistive indoor robots.
#include "commands.h"

#include <carenav/common/crash_guard.h>
#include <carenav/common/errors.h>
#include <carenav/localization/localization_params.h>
#include <carenav/navigation/navigation_params.h>
#include <carenav/perception/perception_params.h>
#include <carenav/sim/sim_params.h>
#include <carenav/slam/slam_params.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <iostream>

#ifndef CARENAV_VERSION
#define CARENAV_VERSION "dev"
#endif
#ifndef CARENAV_DEFAULT_DATASETS
#define CARENAV_DEFAULT_DATASETS "/usr/share/mrpt/datasets"
#endif

namespace carenav::app {
std::vector<std::pair<int, CommandAdder>>& commandRegistry() {
  static std::vector<std::pair<int, CommandAdder>> r;
  return r;
}
std::vector<CommandAdder>& importRegistry() {
  static std::vector<CommandAdder> r;
  return r;
}
std::string mrptDatasetsDir() {
  if (const char* e = std::getenv("CARENAV_MRPT_DATASETS"); e && *e) return e;
  return CARENAV_DEFAULT_DATASETS;
}
}  // namespace carenav::app

namespace {
/** "unknown command 'x' ..." when the first word that is not an option names
 *  no command (CLI11 would only say that a subcommand is required); empty
 *  otherwise. */
std::string unknownCommand(const CLI::App& app, int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (!a.empty() && a[0] == '-') continue;
    std::string names;
    for (const auto* c : app.get_subcommands({})) {
      if (c->get_name() == a) return {};
      names += (names.empty() ? "" : ", ") + c->get_name();
    }
    return "unknown command '" + a + "' (commands: " + names + "; carenav --help)";
  }
  return {};
}
}  // namespace

int main(int argc, char** argv) {
  using namespace carenav;
  installCrashGuard();
  limitAddressSpace(defaultMemoryLimitMB());
  // Every module's profile sections, so `profile check` knows all keys.
  slam::registerProfileSections();
  localization::registerProfileSections();
  navigation::registerProfileSections();
  perception::registerProfileSections();
  sim::registerProfileSections();
  CLI::App app{
      "carenav: mapping, localisation and navigation for assistive indoor robots "
      "(walkers, social and care robots), on MRPT.\n"
      "Exit codes: 0 ok, 1 runtime failure, 2 bad usage or bad input."};
  app.set_version_flag("--version", std::string(CARENAV_VERSION));
  app.require_subcommand(1);
  app::GlobalOptions g;
  app.add_flag("-q,--quiet", g.quiet, "No progress display and no chatter on stderr");
  auto& cmds = app::commandRegistry();
  std::stable_sort(cmds.begin(), cmds.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& [order, add] : cmds) add(app, g);
  if (const std::string unknown = unknownCommand(app, argc, argv); !unknown.empty()) {
    std::fprintf(stderr, "carenav: error: %s\n", unknown.c_str());
    return kExitInput;
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);  // prints the message and a hint
    return kExitInput;
  } catch (const InputError& e) {
    std::fprintf(stderr, "carenav: error: %s\n", e.what());
    return kExitInput;
  } catch (const std::filesystem::filesystem_error& e) {
    // Paths come from the user (--out folders, files to write): their input.
    std::fprintf(stderr, "carenav: error: %s: %s (%s)\n", e.path1().c_str(),
                 e.code().message().c_str(), e.what());
    return kExitInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "carenav: failure: %s\n", e.what());
    return kExitRuntime;
  }
  return kExitOk;
}
