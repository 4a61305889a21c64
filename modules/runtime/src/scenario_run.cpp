// The simulator adapter of the navigation session: a scenario's world and
// user drive the session in closed loop, faster than real time; metrics
// from the simulator's truth (scenario_judge.h).
#include "scenario_judge.h"

#include <carenav/common/errors.h>
#include <carenav/common/text.h>
#include <carenav/runtime/session.h>
#include <carenav/places/places.h>
#include <carenav/sim/simulator.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <thread>

namespace carenav::navigation {

namespace {

/** The scenario with the run's --goal in place of its own. */
Scenario withGoalOverride(const Scenario& scenario, const RunOptions& o) {
  Scenario sc = scenario;
  if (o.goal.empty()) return sc;
  if (!sc.intent.empty())
    throw InputError(sc.file + ": --goal given for a scenario that scripts a user (intent)");
  sc.goal = parseGoalText(o.goal);
  sc.goal_name = sc.goal ? "" : o.goal;
  sc.patrol.clear();
  return sc;
}

/** Profile: --profile, else the scenario's (which must exist, as its world). */
std::string profilePath(const Scenario& sc, const RunOptions& o) {
  const std::string path = !o.profile.empty() ? o.profile : sc.profile;
  if (path.empty())
    throw InputError(sc.file + ": no robot profile: give --profile or 'profile:' in the scenario");
  auto mustExist = [&](const std::string& p, const char* key) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(p, ec))
      throw InputError(sc.file + ": '" + key + ":' " + p + ": no such file");
  };
  if (o.profile.empty()) mustExist(path, "profile");
  mustExist(sc.world, "world");
  return path;
}

/** The scenario's goals, by pose or by name (a place, a room's default
 *  place or its most central free cell), each on the world's map. */
std::vector<SessionGoal> resolveGoals(const Scenario& sc, const sim::World& world) {
  std::optional<places::PlacesFile> places_file;
  auto resolve = [&](const GoalRef& ref) -> SessionGoal {
    if (ref.pose) return {*ref.pose, ""};
    if (!places_file)
      places_file = places::readPlacesFile(sc.places.empty() ? places::placesPathForMap(sc.world)
                                                             : sc.places);
    const places::Goal g = places::resolveGoal(*places_file, world.grid(), ref.name);
    return {TPose2D{g.x, g.y, mrpt::DEG2RAD(g.heading_deg)},
            g.room + (g.place.empty() ? "" : "/" + g.place)};
  };
  std::vector<SessionGoal> goals;
  for (const auto& ref : sc.patrol) goals.push_back(resolve(ref));
  if (goals.empty() && (sc.goal || !sc.goal_name.empty()))
    goals.push_back(resolve(GoalRef{sc.goal, sc.goal_name}));
  return goals;
}

/** A plugin, a user and a goal that do not go together are refused. */
void checkModes(const Scenario& sc, const RunOptions& o, const NavigationSession& s, bool goal) {
  const std::string& plugin = s.setup().nav.plugin;
  if (o.intent && !s.walker())
    throw InputError("--intent " + o.intent->describe() + ": plugin " + plugin +
                     " drives to a goal; a user's commands need a walker plugin "
                     "(user-intent-dwa)");
  if (o.intent && goal)
    throw InputError("--intent " + o.intent->describe() +
                     ": the user drives the walker; give no goal with it");
  if (!s.walker() && !goal)
    throw PluginMismatchError(sc.file + ": plugin " + plugin +
                              " drives to a goal; this scenario scripts a user (use "
                              "user-intent-dwa)");
}

void checkPatrolGoals(const Scenario& sc, const std::vector<SessionGoal>& goals,
                      const sim::World& world) {
  if (sc.patrol.empty()) return;
  for (const auto& g : goals)
    if (!world.inside(world.cellX(g.pose.x), world.cellY(g.pose.y)))
      throw InputError(sc.file + ": patrol goal " + (g.label.empty() ? "" : g.label + " ") +
                       "at (" + formatFixed(g.pose.x, 2) + ", " + formatFixed(g.pose.y, 2) +
                       ") is off the world's map");
}

}  // namespace

RunMetrics runScenario(const Scenario& scenario, const RunOptions& o) {
  const Scenario sc = withGoalOverride(scenario, o);
  SessionSetup setup =
      sessionSetup(profilePath(sc, o), o.sets, !o.plugin.empty() ? o.plugin : sc.plugin);
  auto simp = setup.profile.section<sim::SimParams>("sim");
  simp.seed = sc.seed;
  auto world = std::make_shared<const sim::World>(sim::loadWorld(sc.world, simp.wall_height));
  // 2D lidars and range arrays go to the obstacle memory, depth cameras
  // through perception (NavigationSession::observation).
  std::vector<SensorParams> used;
  for (const auto& s : setup.sensors)
    if (s.type == "lidar2d" || s.type == "range-array" || s.type == "depth-camera")
      used.push_back(s);
  sim::Simulator sim(world, setup.robot, used, simp);
  sim.reset({sc.start.x, sc.start.y, sc.start.phi});
  if (sim.footprintBlocked({sc.start.x, sc.start.y, sc.start.phi}, 0))
    throw InputError(sc.file + ": the start pose puts the robot on an obstacle of the world");

  const bool goal_mode = sc.goal || !sc.goal_name.empty();
  const double duration = o.duration ? *o.duration : sc.duration;
  setup.name = sc.name;
  setup.origin = sc.file;
  setup.map = &world->grid();
  setup.localise = goal_mode;  // on the world's map, from the first 2D lidar
  setup.start = sc.start;
  setup.control_rate = o.control_rate;
  setup.out_dir = o.out_dir;
  setup.progress = o.progress;
  setup.progress_every = o.speed > 0 ? 2 : 20;
  setup.duration = duration;
  setup.continue_after_collision = o.continue_after_collision;
  if (!o.out_dir.empty()) std::filesystem::create_directories(o.out_dir);
  NavigationSession session(setup);
  const auto goals = resolveGoals(sc, *world);
  checkModes(sc, o, session, goal_mode);
  checkPatrolGoals(sc, goals, *world);
  if (goal_mode)
    session.setGoals(goals, !sc.patrol.empty(), sc.leg_timeout, {sc.start.x, sc.start.y});
  const auto& odo0 = sim.odometry();
  session.odometry({odo0.x, odo0.y, odo0.yaw}, {0, 0}, 0);
  return runSimulated(sc, o, *world, sim, session, duration);
}

}  // namespace carenav::navigation
