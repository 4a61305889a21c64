// Navigation scenarios run in the simulator, and their metrics ([Conceicao16]
// sec. 6.1): `carenav navigate --scenario S.yaml` and `--suite DIR`.
#pragma once

#include <carenav/common/errors.h>
#include <carenav/common/json_fwd.h>
#include <carenav/common/robot.h>
#include <carenav/navigation/navigation_params.h>
#include <carenav/runtime/intent.h>

#include <mrpt/math/TPoint2D.h>
#include <mrpt/math/TPose2D.h>

#include <atomic>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace carenav::navigation {

using mrpt::math::TPoint2D;
using mrpt::math::TPose2D;

/** One timed user command: from time t on (until the next entry) the user
 *  pushes with v and either a turn rate w or, when `heading` is set, steers
 *  towards that heading (map frame) like a person walking a direction. */
struct IntentEntry {
  double t = 0;
  double v = 0, w = 0;
  std::optional<double> heading;  ///< rad
};

/** A goal of a scenario: a pose, or the name of a place or room. */
struct GoalRef {
  std::optional<TPose2D> pose;  ///< map frame
  std::string name;             ///< "room/place", "room" or "place" of the places file
};

/** A scenario file (docs/navigate.md). */
struct Scenario {
  std::string name;     ///< `name:` or the file's stem
  std::string file;     ///< where it was read from
  std::string world;    ///< simulator world YAML (absolute or relative to the scenario)
  std::string profile;  ///< robot profile (may be empty: --profile)
  std::string plugin;   ///< local planner (may be empty: the profile's)
  TPose2D start;
  std::optional<TPose2D> goal;  ///< goal scenario (map frame; phi kAnyHeading: any)
  std::string goal_name;        ///< "room/place", "room" or "place" of the places file
  std::string places;           ///< places file for goal_name (default: WORLD.places.yaml)
  /** Goals visited in turn, from the first again after the last, until
   *  `duration` (soak runs); the first is also `goal`/`goal_name`. */
  std::vector<GoalRef> patrol;
  double leg_timeout = 300;  ///< s, patrol: a goal not reached by then is given up for the next
  std::vector<IntentEntry> intent;  ///< walker scenario
  double heading_gain = 1.5;        ///< rad/s per rad of heading error for heading intents
  /** m/s, a walker scenario with a goal: the scripted user walks the route
   *  to it at this speed. */
  double user_speed = 0.25;
  double duration = 60;                              ///< s, simulated
  std::optional<std::pair<TPoint2D, double>> reach;  ///< success needs the centre within r
  std::vector<std::vector<TPoint2D>> forbidden;      ///< no part of the footprint may enter these
  bool path_exists = true;  ///< goal scenarios: the world has a route to the goal
  int seed = 1;
  /** The user's (v, w) at time t for a robot heading `yaw`; nullopt before
   *  the first entry. Each entry holds until the next; the last to the end. */
  std::optional<std::pair<double, double>> userAt(double t, double yaw) const;
};

/** Reads a scenario. Throws InputError "FILE:LINE: what" for an empty,
 *  truncated or malformed file, unknown keys, bad numbers, neither or both
 *  of goal and intent. */
Scenario readScenario(const std::string& path);
Scenario parseScenario(const std::string& text, const std::string& origin,
                       const std::string& base_dir);

/** "x,y,deg" (metres, degrees) as a pose; nullopt for any other text (a
 *  typo the caller reports). */
std::optional<TPose2D> parsePoseText(const std::string& text);

/** A goal: "x,y,deg" as parsePoseText, or "x,y" (any heading: kAnyHeading);
 *  nullopt for any other text (a goal given by place name, or a typo). */
std::optional<TPose2D> parseGoalText(const std::string& text);

/** runScenario's refusal of a plugin that does not fit the scenario (a
 *  plugin that drives to a goal on a scenario that scripts a user): alone it
 *  is bad input, in a side-by-side run of several plugins the pair is skipped. */
class PluginMismatchError : public InputError {
 public:
  using InputError::InputError;
};

/** Metrics of one run ([Conceicao16, Sec. 6.1]). */
struct RunMetrics {
  std::string scenario, plugin;
  std::string goal_name;  ///< the resolved room/place when the goal was given by name
  bool success = false;
  std::string outcome;  ///< why it failed, or "goal reached" / "ok"
  size_t collisions = 0;
  double min_clearance_m = 0, mean_clearance_m = 0;  ///< truth footprint to obstacles
  double duration_s = 0, path_length_m = 0, mean_speed_mps = 0;
  /** Walker: mean |(v, w)_robot - (v, w)_user| over the cycles where the
   *  user's own command was collision-free (NaN when never). */
  double intent_fidelity = 0;
  size_t cycles = 0, stops = 0, slowed = 0;
  double cycle_ms_mean = 0, cycle_ms_max = 0;  ///< wall time of Navigator::cycle
  size_t depth_frames = 0;                     ///< depth frames through perception
  /** Localiser scans with too few returns in range to weigh (min_returns):
   *  the estimate followed odometry alone there. */
  size_t dead_reckoning_scans = 0;
  double perception_ms_mean = 0;  ///< wall time per depth frame
  double final_goal_error_m = 0;  ///< goal scenarios
  double wall_seconds = 0;
  bool entered_forbidden = false;
  bool left_map = false;       ///< the true centre went off the world's map (or onto unknown)
  size_t recoveries = 0;       ///< recovery behaviours started (goal robots)
  size_t recovery_cycles = 0;  ///< control cycles spent in them
  size_t avoided_places = 0;   ///< places where recoveries kept beginning, routed around
  size_t legs_completed = 0;   ///< patrol: goals reached (in truth)
  size_t legs_failed = 0;      ///< patrol: goals given up or timed out
  /** Patrol: goals the robot reported reached while its true centre was
   *  farther than goal_tolerance (its localisation was off), and the worst. */
  size_t legs_missed = 0;
  double leg_miss_max_m = 0;
  /** The robot's work per control period, as CPU time of the thread
   *  (sensor processing, localisation, the navigator, replanning; not the
   *  simulator): 99th percentile and
   *  maximum over the run, and the 99th percentile of each 10 minutes. */
  double work_ms_p99 = 0, work_ms_max = 0;
  std::vector<double> work_ms_p99_windows;
  /** Resident memory (MiB) at the start and every simulated minute, and at the end. */
  std::vector<double> rss_mb;
  std::vector<std::string> outputs;
  std::string toJson() const;
  /** toJson() as a value (summary.json, `--json`: a non-finite
   *  min_clearance_m is written 0, a NaN null); `complete` adds
   *  entered_forbidden and outputs and keeps an infinite min_clearance_m
   *  (null), for passing a run between processes. */
  Json toJsonValue(bool complete = false) const;
  /** Reads toJsonValue(true) back (null min_clearance_m: infinity, other
   *  nulls: NaN); missing keys keep their defaults. Throws InputError on a
   *  value of the wrong type. */
  static RunMetrics fromJson(const Json& j);
  /** Lists run.png (`png`, written by the caller) and navlog.csv of
   *  `out_dir` as outputs, writes summary.json there (listed too). */
  void writeSummary(const std::string& out_dir, const std::string& png);
  /** A run that ended on bad input: names what was written, then throws it. */
  [[noreturn]] void failWith(const InputError& error) const;
};

struct RunOptions {
  std::string out_dir;            ///< PNG of the run and the navigation log; empty: none
  std::string plugin;             ///< overrides the scenario's and the profile's
  std::string profile;            ///< overrides the scenario's
  std::vector<std::string> sets;  ///< profile overrides
  /** Overrides the scenario's goal: "x,y,deg" or a place/room name
   *  ("kitchen/table", "kitchen") of the places file. */
  std::string goal;
  double control_rate = 10;  ///< Hz
  bool progress = false;
  /** The live app: the user's commands come from this source (keyboard,
   *  joystick, TCP, a CSV script) instead of the scenario's script; the run
   *  ends when the source is finished and the walker has stopped. */
  std::shared_ptr<IntentSource> intent;
  /** Pace: simulated seconds per wall second (1: real time); 0 runs as
   *  fast as the computer can. */
  double speed = 0;
  /** Overrides the scenario's duration (s); infinity runs until the intent
   *  source finishes or `stop` is set. */
  std::optional<double> duration;
  /** The first collision ends the run (the bumper's contact); true: the
   *  run goes on and counts them all (it fails either way). */
  bool continue_after_collision = false;
  /** Set (e.g. by SIGINT) to end the run early; outputs are still written. */
  const std::atomic<bool>* stop = nullptr;
};

/** Runs the scenario in the simulator: the profile's robot and sensors, its
 *  [navigation] (and [localization] for goal scenarios, which localise on
 *  the world's map from the simulated lidar and odometry), the chosen
 *  plugin. Throws InputError for bad files. */
RunMetrics runScenario(const Scenario& s, const RunOptions& o);

}  // namespace carenav::navigation
