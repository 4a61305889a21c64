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
  } catch (const std::exception& e) {
    std::fprintf(stderr, "carenav: failure: %s\n", e.what());
    return kExitRuntime;
  }
  return kExitOk;
}
