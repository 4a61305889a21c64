// carenav navigate --scenario S.yaml | --suite DIR  [--profile P] [--plugin NAME[,NAME...]]
//                  [--out DIR] [--json]
// The live app: carenav navigate [--world W.yaml | --scenario S.yaml] --intent SRC | --goal G
//                  [--speed F]    (the built-in simulator)
//               carenav navigate --bridge HOST:PORT --profile P --intent SRC | --goal G --map M
//                  --start x,y,deg   (a real robot)
#include <carenav/common/errors.h>
#include <carenav/common/profile.h>
#include <carenav/navigation/local_planner.h>
#include <carenav/runtime/bridge.h>
#include <carenav/runtime/intent.h>
#include <carenav/runtime/suite.h>

#include <atomic>
#include <csignal>
#include <iostream>
#include <optional>
#include <sstream>

#include "commands.h"

namespace carenav::app {

namespace {

struct NavigateArgs {
  std::string scenario, suite, profile, plugins, out, goal;
  std::vector<std::string> sets;
  bool json = false;
  bool continue_after_collision = false;
  double rate = 10;
  // the live app
  std::string world, start, intent, bridge, map;
  std::optional<double> speed, duration;
  double connect_timeout = 10;
  double silence_timeout = 5;
  bool live() const { return !intent.empty() || !bridge.empty() || !world.empty(); }
};

std::atomic<bool> g_stop{false};
void onSigint(int) { g_stop = true; }

/** "x,y,deg" to a pose; throws InputError naming the option. */
navigation::TPose2D parsePose(const std::string& s, const char* option) {
  if (const auto p = navigation::parsePoseText(s)) return *p;
  throw InputError(std::string(option) + " '" + s + "': expected x,y,deg");
}

std::vector<std::string> splitComma(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

void report(const NavigateArgs& a, const GlobalOptions& g,
            const std::vector<navigation::RunMetrics>& runs) {
  std::cout << (a.json ? navigation::runsJson(runs) : navigation::runsTable(runs)) << std::flush;
  if (!g.quiet)
    for (const auto& r : runs)
      for (const auto& f : r.outputs) std::cerr << "[navigate] wrote " << f << "\n";
}

/** The user's commands of the live app from --intent, for the profile's robot. */
std::shared_ptr<navigation::IntentSource> intentSource(const NavigateArgs& a,
                                                       const std::string& profile) {
  Profile prof = Profile::load(profile);
  prof.applyOverrides(a.sets);
  return navigation::makeIntentSource(a.intent, prof.section<RobotParams>("robot"));
}

/** The options every kind of run shares. */
navigation::RunOptions runOptions(const NavigateArgs& a, const GlobalOptions& g) {
  navigation::RunOptions o;
  o.profile = a.profile;
  o.sets = a.sets;
  o.goal = a.goal;
  o.control_rate = a.rate;
  o.progress = !g.quiet;
  o.duration = a.duration;
  return o;
}

/** A real robot through the TCP bridge. */
navigation::RunMetrics runOnBridge(const NavigateArgs& a, const GlobalOptions& g,
                                   const std::string& plugin) {
  if (a.profile.empty()) throw InputError("--bridge: give the robot's --profile");
  navigation::BridgeOptions b;
  b.address = a.bridge;
  b.profile = a.profile;
  b.sets = a.sets;
  b.plugin = plugin;
  b.map = a.map;
  if (!a.start.empty()) b.start = parsePose(a.start, "--start");
  b.goal = a.goal;
  b.control_rate = a.rate;
  b.duration = a.duration.value_or(0);
  b.connect_timeout = a.connect_timeout;
  b.silence_timeout = a.silence_timeout;
  b.out_dir = a.out;
  b.stop = &g_stop;
  b.progress = !g.quiet;
  if (!a.intent.empty()) b.intent = intentSource(a, a.profile);
  return navigation::runBridge(b);
}

/** The live app in the built-in simulator. */
navigation::RunMetrics runLive(const NavigateArgs& a, const GlobalOptions& g,
                               const std::string& plugin) {
  navigation::Scenario s = !a.scenario.empty() ? navigation::readScenario(a.scenario)
                                               : navigation::liveScenario(a.world);
  if (!a.start.empty()) s.start = parsePose(a.start, "--start");
  s.intent.clear();
  navigation::RunOptions o = runOptions(a, g);
  o.plugin = plugin;
  o.out_dir = a.out;
  o.speed = a.speed.value_or(1.0);
  o.stop = &g_stop;
  o.continue_after_collision = true;  // a live user's session goes on after a bump (counted)
  if (!a.intent.empty())
    o.intent = intentSource(a, !a.profile.empty() ? a.profile : s.profile);
  else if (!s.goal && a.goal.empty())
    throw InputError("navigate: give --intent SRC (a walker's user) or --goal G");
  return navigation::runScenario(s, o);
}

/** Scenario files: one, or a suite's, each with every --plugin. */
std::vector<navigation::RunMetrics> runScenarios(const NavigateArgs& a, const GlobalOptions& g) {
  if (a.scenario.empty() && a.suite.empty())
    throw InputError(
        "navigate: give --scenario FILE or --suite DIR, or for the live app --intent SRC, "
        "--world W.yaml or --bridge HOST:PORT (see --help)");
  const auto files =
      !a.scenario.empty() ? std::vector<std::string>{a.scenario} : navigation::suiteFiles(a.suite);
  std::vector<navigation::Scenario> scenarios;
  for (const auto& f : files) scenarios.push_back(navigation::readScenario(f));
  if (!a.start.empty()) {  // one scenario from elsewhere (it was ignored before)
    if (a.scenario.empty())
      throw InputError("navigate: --start goes with one --scenario, not with a --suite");
    scenarios.front().start = parsePose(a.start, "--start");
  }
  navigation::RunOptions base = runOptions(a, g);
  base.out_dir = a.out;
  base.speed = a.speed.value_or(0.0);
  base.continue_after_collision = a.continue_after_collision;
  return navigation::runSuite(scenarios, splitComma(a.plugins), base);
}

void run(const NavigateArgs& a, const GlobalOptions& g) {
  if (!a.out.empty()) prepareOutputFolder(a.out);
  const auto plugins = splitComma(a.plugins);
  if (plugins.size() > 1 && a.live())
    throw InputError("navigate: the live app runs one plugin at a time");
  // Ctrl-C ends a live run cleanly: the robot stops, the outputs are written.
  if (a.live()) std::signal(SIGINT, onSigint);
  const std::string plugin = plugins.empty() ? "" : plugins.front();
  if (!a.bridge.empty()) return report(a, g, {runOnBridge(a, g, plugin)});
  if (!a.map.empty()) throw InputError("--map goes with --bridge (a simulated world has its map)");
  if (!a.intent.empty() || !a.world.empty()) return report(a, g, {runLive(a, g, plugin)});
  report(a, g, runScenarios(a, g));
}

void addOptions(CLI::App* cmd, NavigateArgs& a);

void addNavigateCommand(CLI::App& app, const GlobalOptions& g) {
  auto a = std::make_shared<NavigateArgs>();
  auto* cmd = app.add_subcommand(
      "navigate",
      "Run navigation scenarios headless in the built-in simulator, faster than real time: a "
      "walker pushed by a scripted user (user-intent-dwa) or a robot sent to a goal (goal-dwa, "
      "A* route, localisation on the world's map), with the safety supervisor around the "
      "plugin. Reports success, collisions, clearance, duration, path length, speed and the "
      "walker's intent fidelity; with --out, a PNG of each run, its navigation log (CSV) and "
      "summary.json.");
  addOptions(cmd, *a);
  cmd->callback([a, &g] { run(*a, g); });
}

/** The options, in --help order. */
void addOptions(CLI::App* cmd, NavigateArgs& a) {
  std::string plugin_help = "Local method(s), comma-separated, run side by side:";
  for (const auto& [n, d] : navigation::PlannerRegistry::instance().list())
    plugin_help += " " + n + " (" + d + ");";
  plugin_help += " default: the scenario's, else the profile's [navigation] plugin";
  auto* sc = cmd->add_option("--scenario", a.scenario, "One scenario file (docs/navigate.md)");
  auto* su = cmd->add_option("--suite", a.suite,
                             "A folder: every *.yaml scenario in it (world files and *.places.yaml "
                             "beside them are skipped)");
  sc->excludes(su);
  cmd->add_option("--profile", a.profile,
                  "Robot profile (default: the scenario's 'profile:'); its [robot], sensors, "
                  "[navigation], [localization] and [sim] sections");
  cmd->add_option("--plugin", a.plugins, plugin_help);
  cmd->add_option("--goal", a.goal,
                  "Goal instead of the scenario's: x,y,deg, x,y (any heading), "
                  "or a place or room of the places file "
                  "(\"kitchen/table\", \"kitchen\": its default place, else its most central "
                  "free cell)");
  cmd->add_option("--set", a.sets, "Override a profile value: section.key=value (repeatable)");
  cmd->add_option("--out", a.out,
                  "Output folder: one subfolder per run (run.png, navlog.csv, "
                  "summary.json)");
  cmd->add_option("--rate", a.rate, "Control rate, Hz (default 10)")->check(CLI::Range(1.0, 100.0));
  cmd->add_flag("--json", a.json, "Print the metrics of every run as JSON");
  cmd->add_flag("--continue-after-collision", a.continue_after_collision,
                "Scenario runs: go on after a collision (counting them all) instead of ending the "
                "run at the first (it fails either way)");
  auto* live = cmd->add_option_group(
      "live",
      "The live app: a user (or a goal) drives the robot in the simulator or, through the "
      "bridge, a real robot (docs/navigate.md)");
  live->add_option("--intent", a.intent,
                   "The walker's user: csv:FILE (timed t,v,w rows, or a navlog.csv to replay a "
                   "run), keyboard (w/s a/d or arrows, space stop, q quit), joystick[:DEV] "
                   "(default /dev/input/js0), tcp:[HOST:]PORT (lines 'v w')");
  auto* world =
      live->add_option("--world", a.world,
                       "Simulator world YAML (docs/simulate.md); default "
                       "maps/worlds/apartment.yaml of carenav's data folder (share/carenav, or "
                       "$CARENAV_DATA_DIR)");
  live->add_option("--start", a.start,
                   "Start pose x,y,deg (simulator, a --scenario's instead of its own, or on --map "
                   "with --bridge)");
  live->add_option("--speed", a.speed,
                   "Simulated seconds per wall second: 1 real time (the live default), 0 as fast "
                   "as possible (the scenario default)")
      ->check(CLI::Range(0.0, 1000.0));
  live->add_option("--duration", a.duration,
                   "Seconds to run (default: the scenario's; live: "
                   "until the intent source ends, q or Ctrl-C)")
      ->check(CLI::Range(0.0, 1e6));
  auto* bridge = live->add_option(
      "--bridge", a.bridge,
      "HOST:PORT of a real robot's bridge (line-based TCP: odom/scan/intent in, cmd out; "
      "docs/navigate.md) instead of the simulator");
  live->add_option("--connect-timeout", a.connect_timeout,
                   "Seconds to keep trying to reach the bridge (default 10)")
      ->check(CLI::Range(0.0, 3600.0));
  live->add_option("--silence-timeout", a.silence_timeout,
                   "--bridge: seconds without any line from the robot before the run ends "
                   "with 'stop error', exit 2 (default 5; 0: never)")
      ->check(CLI::Range(0.0, 3600.0));
  live->add_option("--map", a.map,
                   "Static map for goal navigation with --bridge (any map carenav reads)");
  bridge->excludes(world);
  bridge->excludes(su);
  bridge->excludes(sc);
}

}  // namespace

CARENAV_COMMAND(60, addNavigateCommand);

}  // namespace carenav::app
