// carenav navigate --scenario S.yaml | --suite DIR  [--profile P] [--plugin NAME[,NAME...]]
//                  [--out DIR] [--json]
// The live app: carenav navigate [--world W.yaml | --scenario S.yaml] --intent SRC | --goal G
//                  [--speed F]    (the built-in simulator)
//               carenav navigate --bridge HOST:PORT --profile P --intent SRC | --goal G --map M
//                  --start x,y,deg   (a real robot)
#include <carenav/common/data_dir.h>
#include <carenav/common/errors.h>
#include <carenav/common/profile.h>
#include <carenav/navigation/bridge.h>
#include <carenav/navigation/intent.h>
#include <carenav/navigation/local_planner.h>
#include <carenav/navigation/scenario.h>

#include <csignal>
#include <limits>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <sstream>
#include <stdexcept>

#include "commands.h"

namespace carenav::app {

namespace {

namespace fs = std::filesystem;

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

std::string cell(double v, int prec = 2) {
  if (std::isnan(v)) return "-";
  char b[32];
  std::snprintf(b, sizeof b, "%.*f", prec, v);
  return b;
}

/** RunMetrics as "key<TAB>value" lines (outputs repeated), and back. */
std::string serialize(const navigation::RunMetrics& m) {
  std::ostringstream o;
  o.precision(17);
  auto line = [&](const char* k, const auto& v) { o << k << '\t' << v << '\n'; };
  line("scenario", m.scenario);
  line("plugin", m.plugin);
  line("goal_name", m.goal_name);
  line("success", m.success);
  line("outcome", m.outcome);
  line("collisions", m.collisions);
  line("min_clearance_m", m.min_clearance_m);
  line("mean_clearance_m", m.mean_clearance_m);
  line("duration_s", m.duration_s);
  line("path_length_m", m.path_length_m);
  line("mean_speed_mps", m.mean_speed_mps);
  line("intent_fidelity", m.intent_fidelity);
  line("cycles", m.cycles);
  line("stops", m.stops);
  line("slowed", m.slowed);
  line("cycle_ms_mean", m.cycle_ms_mean);
  line("cycle_ms_max", m.cycle_ms_max);
  line("depth_frames", m.depth_frames);
  line("perception_ms_mean", m.perception_ms_mean);
  line("final_goal_error_m", m.final_goal_error_m);
  line("wall_seconds", m.wall_seconds);
  line("entered_forbidden", m.entered_forbidden);
  line("left_map", m.left_map);
  line("recoveries", m.recoveries);
  line("recovery_cycles", m.recovery_cycles);
  for (const auto& f : m.outputs) line("output", f);
  return o.str();
}

navigation::RunMetrics deserialize(const std::string& text) {
  navigation::RunMetrics m;
  std::istringstream in(text);
  std::string l;
  while (std::getline(in, l)) {
    const auto tab = l.find('\t');
    if (tab == std::string::npos) continue;
    const std::string k = l.substr(0, tab), v = l.substr(tab + 1);
    const double d = std::strtod(v.c_str(), nullptr);
    const auto n = static_cast<size_t>(d);
    if (k == "scenario")
      m.scenario = v;
    else if (k == "plugin")
      m.plugin = v;
    else if (k == "goal_name")
      m.goal_name = v;
    else if (k == "success")
      m.success = v == "1";
    else if (k == "outcome")
      m.outcome = v;
    else if (k == "collisions")
      m.collisions = n;
    else if (k == "min_clearance_m")
      m.min_clearance_m = d;
    else if (k == "mean_clearance_m")
      m.mean_clearance_m = d;
    else if (k == "duration_s")
      m.duration_s = d;
    else if (k == "path_length_m")
      m.path_length_m = d;
    else if (k == "mean_speed_mps")
      m.mean_speed_mps = d;
    else if (k == "intent_fidelity")
      m.intent_fidelity = d;
    else if (k == "cycles")
      m.cycles = n;
    else if (k == "stops")
      m.stops = n;
    else if (k == "slowed")
      m.slowed = n;
    else if (k == "cycle_ms_mean")
      m.cycle_ms_mean = d;
    else if (k == "cycle_ms_max")
      m.cycle_ms_max = d;
    else if (k == "depth_frames")
      m.depth_frames = n;
    else if (k == "perception_ms_mean")
      m.perception_ms_mean = d;
    else if (k == "final_goal_error_m")
      m.final_goal_error_m = d;
    else if (k == "wall_seconds")
      m.wall_seconds = d;
    else if (k == "entered_forbidden")
      m.entered_forbidden = v == "1";
    else if (k == "left_map")
      m.left_map = v == "1";
    else if (k == "recoveries")
      m.recoveries = n;
    else if (k == "recovery_cycles")
      m.recovery_cycles = n;
    else if (k == "output")
      m.outputs.push_back(v);
  }
  return m;
}

/** Runs one scenario of a suite in a child process: every run starts from a
 *  fresh process, so nothing one run leaves behind (caches, global random
 *  generators, here or in MRPT) changes the next, and a crash ends one run,
 *  not the suite. */
navigation::RunMetrics runInChild(const navigation::Scenario& s, const navigation::RunOptions& o) {
  int fd[2];
  if (pipe(fd) != 0) throw std::runtime_error("navigate: cannot create a pipe");
  std::cout.flush();
  std::cerr.flush();
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("navigate: cannot fork");
  if (pid == 0) {
    close(fd[0]);
    std::string out;
    try {
      out = "OK\n" + serialize(navigation::runScenario(s, o));
    } catch (const InputError& e) {
      out = std::string("INPUT\n") + e.what();
    } catch (const std::exception& e) {
      out = std::string("ERROR\n") + e.what();
    }
    size_t done = 0;
    while (done < out.size()) {
      const ssize_t w = write(fd[1], out.data() + done, out.size() - done);
      if (w <= 0) break;
      done += static_cast<size_t>(w);
    }
    close(fd[1]);
    _exit(0);
  }
  close(fd[1]);
  std::string text;
  char buf[4096];
  ssize_t r;
  while ((r = read(fd[0], buf, sizeof buf)) > 0) text.append(buf, static_cast<size_t>(r));
  close(fd[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  const auto nl = text.find('\n');
  const std::string tag = text.substr(0, nl),
                    body = nl == std::string::npos ? "" : text.substr(nl + 1);
  if (tag == "OK") return deserialize(body);
  if (tag == "INPUT") throw InputError(body);
  if (tag == "ERROR") throw std::runtime_error(body);
  navigation::RunMetrics m;
  m.scenario = s.name;
  m.plugin = o.plugin;
  m.outcome = WIFSIGNALED(status) ? "crashed (signal " + std::to_string(WTERMSIG(status)) + ")"
                                  : "ended without a result";
  return m;
}

void addNavigateCommand(CLI::App& app, const GlobalOptions& g) {
  auto a = std::make_shared<NavigateArgs>();
  std::string plugin_help = "Local method(s), comma-separated, run side by side:";
  for (const auto& [n, d] : navigation::PlannerRegistry::instance().list())
    plugin_help += " " + n + " (" + d + ");";
  plugin_help += " default: the scenario's, else the profile's [navigation] plugin";
  auto* cmd = app.add_subcommand(
      "navigate",
      "Run navigation scenarios headless in the built-in simulator, faster than real time: a "
      "walker pushed by a scripted user (user-intent-dwa) or a robot sent to a goal (goal-dwa, "
      "A* route, localisation on the world's map), with the safety supervisor around the "
      "plugin. Reports success, collisions, clearance, duration, path length, speed and the "
      "walker's intent fidelity; with --out, a PNG of each run, its navigation log (CSV) and "
      "summary.json.");
  auto* sc = cmd->add_option("--scenario", a->scenario, "One scenario file (docs/navigate.md)");
  auto* su = cmd->add_option("--suite", a->suite, "A folder: every *.yaml scenario in it");
  sc->excludes(su);
  cmd->add_option("--profile", a->profile,
                  "Robot profile (default: the scenario's 'profile:'); its [robot], sensors, "
                  "[navigation], [localization] and [sim] sections");
  cmd->add_option("--plugin", a->plugins, plugin_help);
  cmd->add_option("--goal", a->goal,
                  "Goal instead of the scenario's: x,y,deg, or a place or room of the places "
                  "file (\"kitchen/table\", \"kitchen\": its default place, else its most "
                  "central free cell)");
  cmd->add_option("--set", a->sets, "Override a profile value: section.key=value (repeatable)");
  cmd->add_option("--out", a->out,
                  "Output folder: one subfolder per run (run.png, navlog.csv, "
                  "summary.json)");
  cmd->add_option("--rate", a->rate, "Control rate, Hz (default 10)")
      ->check(CLI::Range(1.0, 100.0));
  cmd->add_flag("--json", a->json, "Print the metrics of every run as JSON");
  cmd->add_flag("--continue-after-collision", a->continue_after_collision,
                "Scenario runs: go on after a collision (counting them all) instead of ending the "
                "run at the first (it fails either way)");
  auto* live = cmd->add_option_group(
      "live",
      "The live app: a user (or a goal) drives the robot in the simulator or, through the "
      "bridge, a real robot (docs/navigate.md)");
  live->add_option("--intent", a->intent,
                   "The walker's user: csv:FILE (timed t,v,w rows, or a navlog.csv to replay a "
                   "run), keyboard (w/s a/d or arrows, space stop, q quit), joystick[:DEV] "
                   "(default /dev/input/js0), tcp:[HOST:]PORT (lines 'v w')");
  auto* world =
      live->add_option("--world", a->world,
                       "Simulator world YAML (docs/simulate.md); default "
                       "maps/worlds/apartment.yaml of carenav's data folder (share/carenav, or "
                       "$CARENAV_DATA_DIR)");
  live->add_option("--start", a->start,
                   "Start pose x,y,deg (simulator, or on --map with --bridge)");
  live->add_option("--speed", a->speed,
                   "Simulated seconds per wall second: 1 real time (the live default), 0 as fast "
                   "as possible (the scenario default)")
      ->check(CLI::Range(0.0, 1000.0));
  live->add_option("--duration", a->duration,
                   "Seconds to run (default: the scenario's; live: "
                   "until the intent source ends, q or Ctrl-C)")
      ->check(CLI::Range(0.0, 1e6));
  auto* bridge = live->add_option(
      "--bridge", a->bridge,
      "HOST:PORT of a real robot's bridge (line-based TCP: odom/scan/intent in, cmd out; "
      "docs/navigate.md) instead of the simulator");
  live->add_option("--connect-timeout", a->connect_timeout,
                   "Seconds to keep trying to reach the bridge (default 10)")
      ->check(CLI::Range(0.0, 3600.0));
  live->add_option("--silence-timeout", a->silence_timeout,
                   "--bridge: seconds without any line from the robot before the run ends "
                   "with 'stop error', exit 2 (default 5; 0: never)")
      ->check(CLI::Range(0.0, 3600.0));
  live->add_option("--map", a->map,
                   "Static map for goal navigation with --bridge (any map carenav reads)");
  bridge->excludes(world);
  bridge->excludes(su);
  bridge->excludes(sc);
  cmd->callback([a, &g] {
    if (!a->out.empty()) prepareOutputFolder(a->out);
    auto report = [a, &g](const std::vector<navigation::RunMetrics>& runs) {
      if (a->json) {
        std::cout << "[\n";
        for (size_t i = 0; i < runs.size(); ++i)
          std::cout << runs[i].toJson() << (i + 1 < runs.size() ? ",\n" : "\n");
        std::cout << "]\n";
      } else {
        std::printf("%-24s %-16s %-7s %5s %7s %7s %7s %7s %6s %8s %7s  %s\n", "scenario", "plugin",
                    "success", "coll", "minclr", "meanclr", "time_s", "path_m", "v_mps", "fidelity",
                    "cyc_ms", "outcome");
        for (const auto& r : runs)
          std::printf("%-24s %-16s %-7s %5zu %7s %7s %7s %7s %6s %8s %7s  %s\n", r.scenario.c_str(),
                      r.plugin.c_str(), r.success ? "yes" : "NO", r.collisions,
                      cell(r.min_clearance_m).c_str(), cell(r.mean_clearance_m).c_str(),
                      cell(r.duration_s, 1).c_str(), cell(r.path_length_m).c_str(),
                      cell(r.mean_speed_mps).c_str(), cell(r.intent_fidelity, 3).c_str(),
                      cell(r.cycle_ms_mean, 2).c_str(), r.outcome.c_str());
        size_t ok = 0;
        for (const auto& r : runs) ok += r.success;
        std::printf("%zu of %zu runs succeeded\n", ok, runs.size());
      }
      if (!g.quiet)
        for (const auto& r : runs)
          for (const auto& f : r.outputs) std::cerr << "[navigate] wrote " << f << "\n";
    };
    const auto plugins_live = splitComma(a->plugins);
    if (plugins_live.size() > 1 && (!a->intent.empty() || !a->bridge.empty() || !a->world.empty()))
      throw InputError("navigate: the live app runs one plugin at a time");
    // Ctrl-C ends a live run cleanly: the robot stops, the outputs are written.
    if (!a->intent.empty() || !a->bridge.empty() || !a->world.empty())
      std::signal(SIGINT, onSigint);

    if (!a->bridge.empty()) {
      if (a->profile.empty()) throw InputError("--bridge: give the robot's --profile");
      navigation::BridgeOptions b;
      b.address = a->bridge;
      b.profile = a->profile;
      b.sets = a->sets;
      b.plugin = plugins_live.empty() ? "" : plugins_live.front();
      b.map = a->map;
      if (!a->start.empty()) b.start = parsePose(a->start, "--start");
      b.goal = a->goal;
      b.control_rate = a->rate;
      b.duration = a->duration.value_or(0);
      b.connect_timeout = a->connect_timeout;
      b.silence_timeout = a->silence_timeout;
      b.out_dir = a->out;
      b.stop = &g_stop;
      b.progress = !g.quiet;
      if (!a->intent.empty()) {
        Profile prof = Profile::load(a->profile);
        prof.applyOverrides(a->sets);
        b.intent = navigation::makeIntentSource(a->intent, prof.section<RobotParams>("robot"));
      }
      report({navigation::runBridge(b)});
      return;
    }
    if (!a->map.empty())
      throw InputError("--map goes with --bridge (a simulated world has its map)");
    if (!a->intent.empty() || !a->world.empty()) {
      // The live app in the built-in simulator.
      navigation::Scenario s;
      if (!a->scenario.empty()) {
        s = navigation::readScenario(a->scenario);
      } else {
        s.name = "live";
        s.file = "navigate";
        s.world = !a->world.empty()
                      ? a->world
                      : dataFile("maps/worlds/apartment.yaml", "the default world (--world)");
        if (!fs::exists(s.world)) throw InputError(s.world + ": no such world file (--world)");
        s.profile = dataFile("ini/isr-aiwalker.ini", "the default profile (--profile)");
        s.start = parsePose(a->start.empty() ? "1.0,4.0,0" : a->start, "--start");
        s.duration = std::numeric_limits<double>::infinity();
      }
      if (!a->start.empty()) s.start = parsePose(a->start, "--start");
      s.intent.clear();
      navigation::RunOptions o;
      o.plugin = plugins_live.empty() ? "" : plugins_live.front();
      o.profile = a->profile;
      o.sets = a->sets;
      o.goal = a->goal;
      o.control_rate = a->rate;
      o.progress = !g.quiet;
      o.out_dir = a->out;
      o.speed = a->speed.value_or(1.0);
      o.duration = a->duration;
      o.stop = &g_stop;
      // a live user's session goes on after a bump (it is counted)
      o.continue_after_collision = true;
      if (!a->intent.empty()) {
        Profile prof = Profile::load(!a->profile.empty() ? a->profile : s.profile);
        prof.applyOverrides(a->sets);
        o.intent = navigation::makeIntentSource(a->intent, prof.section<RobotParams>("robot"));
      } else if (!s.goal && a->goal.empty()) {
        throw InputError("navigate: give --intent SRC (a walker's user) or --goal G");
      }
      report({navigation::runScenario(s, o)});
      return;
    }
    std::vector<std::string> files;
    if (!a->scenario.empty()) {
      files.push_back(a->scenario);
    } else if (!a->suite.empty()) {
      if (!fs::is_directory(a->suite)) throw InputError(a->suite + ": not a folder");
      for (const auto& e : fs::directory_iterator(a->suite))
        if (e.path().extension() == ".yaml" &&
            e.path().string().find(".places.") == std::string::npos)
          files.push_back(e.path().string());
      std::sort(files.begin(), files.end());
      if (files.empty()) throw InputError(a->suite + ": no *.yaml scenario in it");
    } else {
      throw InputError(
          "navigate: give --scenario FILE or --suite DIR, or for the live app --intent SRC, "
          "--world W.yaml or --bridge HOST:PORT (see --help)");
    }
    std::vector<navigation::Scenario> scenarios;
    for (const auto& f : files) scenarios.push_back(navigation::readScenario(f));
    const auto plugins = splitComma(a->plugins);
    const bool single = scenarios.size() == 1 && plugins.size() <= 1;

    std::vector<navigation::RunMetrics> runs;
    if (a->speed && *a->speed > 0 && !single)
      throw InputError("navigate: --speed paces one run; a suite runs as fast as it can");
    for (const auto& s : scenarios) {
      std::vector<std::string> ps = plugins.empty() ? std::vector<std::string>{""} : plugins;
      for (const auto& p : ps) {
        navigation::RunOptions o;
        o.plugin = p;
        o.profile = a->profile;
        o.sets = a->sets;
        o.goal = a->goal;
        o.control_rate = a->rate;
        o.progress = !g.quiet;
        o.speed = a->speed.value_or(0.0);
        o.duration = a->duration;
        o.continue_after_collision = a->continue_after_collision;
        if (!a->out.empty())
          o.out_dir = (fs::path(a->out) / (s.name + (p.empty() ? "" : "-" + p))).string();
        try {
          runs.push_back(single ? navigation::runScenario(s, o) : runInChild(s, o));
        } catch (const InputError& e) {
          // A plugin that does not fit the scenario (walker vs goal) is
          // skipped in a side-by-side run; alone it is an error.
          const std::string w = e.what();
          if (single || w.find("this scenario") == std::string::npos) throw;
          if (!g.quiet) std::cerr << "[navigate] skipped: " << w << "\n";
        }
      }
    }
    report(runs);
  });
}

}  // namespace

CARENAV_COMMAND(60, addNavigateCommand);

}  // namespace carenav::app
