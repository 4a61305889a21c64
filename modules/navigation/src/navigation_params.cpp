#include <carenav/common/profile.h>
#include <carenav/navigation/maneuver.h>
#include <carenav/navigation/mrpt_ptg.h>
#include <carenav/navigation/navigation_params.h>
#include <carenav/navigation/recovery.h>

#include <set>

namespace carenav::navigation {

const ParamTable<NavigationParams>& NavigationParams::table() {
  using P = NavigationParams;
  static const auto t =
      ParamTable<P>()
          .choice("plugin", &P::plugin, {"user-intent-dwa", "goal-dwa", "mrpt-ptg"},
                  "local method: user-intent-dwa (walker shared control), goal-dwa or mrpt-ptg "
                  "(MRPT's TP-space navigation, [nav.mrpt_ptg])")
          .real("sim_time", &P::sim_time, "s", 0.1, 30,
                "horizon of each sampled trajectory ([Rosa17, Table 5.1]: 7.0)")
          .real("sim_step", &P::sim_step, "s", 0.01, 1, "rollout step ([Rosa17]: 0.1)")
          .real("window_time", &P::window_time, "s", 0.01, 5,
                "dynamic window: velocities reachable in this time ([Rosa17] time constant 0.5)")
          .integer("v_samples", &P::v_samples, "", 2, 100,
                   "samples of v per direction ([Rosa17]: 12 forward, 12 backward)")
          .integer("w_samples", &P::w_samples, "", 2, 100, "samples of w across the window")
          .real("clearance_influence", &P::clearance_influence, "m", 0.01, 10,
                "lateral clearance beyond this is not told apart")
          .real("obstacle_distance_cap", &P::obstacle_distance_cap, "m", 0.1, 100,
                "arcs are checked at least this far, even slow ones; farther obstacles "
                "do not count (dynamic window planners)")
          .real("plan_clearance", &P::plan_clearance, "m", 0, 5,
                "global route: extra clearance beyond the robot's inscribed radius (less where "
                "no way has it: the widest way's)")
          .real("plan_cost_weight", &P::plan_cost_weight, "", 0, 100,
                "global route: extra cost near obstacles (keeps routes central)")
          .real("passage_margin", &P::passage_margin, "m", 0, 5,
                "global route: cells closer than the robot's radius plus this to an obstacle "
                "form a narrow passage (a doorway), crossed straight")
          .real("passage_approach", &P::passage_approach, "m", 0.1, 5,
                "global route: waypoints this far before and after a passage, on its axis")
          .flag("route_footprint", &P::route_footprint,
                "global route: one the footprint can drive forward (each segment at its "
                "heading, turning on the spot at its corners); where the inscribed circle's "
                "route is not, a search over poses finds one that is (off by default: no "
                "better on the clutter benchmark, docs/BENCHMARKS.md)")
          .real("route_footprint_margin", &P::route_footprint_margin, "m", 0, 1,
                "... keeping the footprint's outline this far from anything not free")
          .integer("route_footprint_nodes", &P::route_footprint_nodes, "", 1000, 10000000,
                   "... expanding at most this many (cell, heading) states (bounds its time; "
                   "none found: the circle's route)")
          .flag("replan_new_only", &P::replan_new_only,
                "global route: replanning drops the route only for what the map does not "
                "show, ahead of the robot (hits on or beside the map's obstacles are those "
                "seen again; where the map leaves the route less than its clearance, that is "
                "enough)")
          .real("goal_tolerance", &P::goal_tolerance, "m", 0.01, 10,
                "goal reached within this distance ([Conceicao16]: 0.5)")
          .real("goal_tolerance_deg", &P::goal_tolerance_deg, "deg", 0.1, 180,
                "heading tolerance at the goal ([Conceicao16]: 0.05 rad)");
  return t;
}

const ParamTable<UserIntentDwaParams>& UserIntentDwaParams::table() {
  using P = UserIntentDwaParams;
  static const auto t =
      ParamTable<P>()
          .real("k_s", &P::k_s, "", 0, 100, "weight of the summed cell cost")
          .real("k_0", &P::k_0, "m", 0, 100,
                "weight of 1 / dist(v, w), the free distance along the arc")
          .real("k_1", &P::k_1, "", 0, 100, "penalty for driving against the user's direction")
          .real("k_2", &P::k_2, "", 0, 100, "weight of the end-pose distance");
  return t;
}

const ParamTable<GoalDwaParams>& GoalDwaParams::table() {
  using P = GoalDwaParams;
  static const auto t =
      ParamTable<P>()
          .real("k_heading", &P::k_heading, "1/rad", 0, 100, "heading error weight")
          .real("k_path", &P::k_path, "1/m", 0, 100, "distance-to-route weight")
          .real("k_speed", &P::k_speed, "", 0, 100, "slowness weight")
          .real("k_goal_obs", &P::k_goal_obs, "s", 0, 100,
                "weight of 1 / the time to the nearest obstacle on the arc")
          .real("turn_in_place_deg", &P::turn_in_place_deg, "deg", 0, 180,
                "turn on the spot when the waypoint is further off")
          .real("score_time", &P::score_time, "s", 0.1, 30,
                "critics are taken at the pose reached after this time")
          .real("lookahead", &P::lookahead, "m", 0.1, 10,
                "the waypoint is this far along the route")
          .real("corner_deg", &P::corner_deg, "deg", 0, 180,
                "the look-ahead does not cut a route vertex turning more than this "
                "(the approach point of a doorway: the robot enters on its axis); 0: cut every "
                "corner")
          .real("align_deg", &P::align_deg, "deg", 0, 180,
                "a candidate ends facing the route's way on within this, or where its footprint "
                "can turn on the spot to it, or no worse than now (180: no such rule)");
  return t;
}

const ParamTable<CommitmentParams>& CommitmentParams::table() {
  using P = CommitmentParams;
  static const auto t =
      ParamTable<P>()
          .real("k_switch", &P::k_switch, "", 0, 100,
                "goal-dwa: extra cost of backing up after a command forward; margin (over "
                "k_heading, rad) by which the other side must be shorter for a turn on the "
                "spot to change direction (0: no commitment)")
          .flag("reverse", &P::reverse,
                "goal-dwa may back up (off: forward only; the recoveries back out along the "
                "way the robot came)");
  return t;
}

const ParamTable<LocalMapParams>& LocalMapParams::table() {
  using P = LocalMapParams;
  static const auto t =
      ParamTable<P>()
          .real("local_size", &P::local_size, "m", 1, 50, "side of the robot-centred local grid")
          .real("resolution", &P::resolution, "m", 0.01, 0.5, "cell size of the local grid")
          .real("obstacle_persistence", &P::obstacle_persistence, "s", 0, 600,
                "seen obstacles are remembered this long where a sensor looks ([Puente14, App. "
                "Table I]: "
                "5); out of every sensor's view, until seen again or beyond memory_radius")
          .real("memory_radius", &P::memory_radius, "m", 0.5, 50,
                "remembered obstacles farther from the robot are dropped")
          .real("cost_decay", &P::cost_decay, "m", 0.01, 5,
                "cell cost falls from 100 to 0 over this distance to an obstacle")
          .real("footprint_padding", &P::footprint_padding, "m", 0, 1,
                "closer than this to an obstacle counts as contact (sensing and control error)");
  return t;
}

const ParamTable<PeopleParams>& PeopleParams::table() {
  using P = PeopleParams;
  static const auto t =
      ParamTable<P>()
          .real("predict_speed", &P::predict_speed, "m/s", 0, 3,
                "moving obstacles (people) are grown by predict_speed x predict_time; 0: off")
          .real("predict_time", &P::predict_time, "s", 0, 5,
                "look-ahead of the growth of moving obstacles")
          .real("dynamic_window", &P::dynamic_window, "s", 0.1, 10,
                "an obstacle in a cell seen free this recently counts as moving")
          .real("dynamic_min_free", &P::dynamic_min_free, "s", 0, 10,
                "... when the cell had been seen free for at least this long")
          .real("static_memory", &P::static_memory, "s", 0, 600,
                "... and had not been hit for this long before that (rays graze the edge cells "
                "of a thin post from one side and hit them from another: static, not moving); "
                "0: off (at 2-10 s a person crossing the robot's way is no longer seen moving)")
          .real("predict_horizon", &P::predict_horizon, "s", 0, 10,
                "tracked moving obstacles are swept along their estimated velocity this far "
                "ahead (a person walking towards the robot blocks the lane it walks in); 0: no "
                "lanes, no hidden regions")
          .real("route_predict_horizon", &P::route_predict_horizon, "s", 0, 60,
                "replanned routes keep out of a tracked person's lane this far ahead (a robot "
                "meeting "
                "a person head-on moves aside early instead of when they are close)")
          .real("track_radius", &P::track_radius, "m", 0.5, 50,
                "moving obstacles are told apart from walls this far from a lidar (beyond the "
                "local map: a person is tracked before it gets close)")
          .real("track_depth_range", &P::track_depth_range, "m", 0, 20,
                "depth-camera obstacle cells farther than this never count as moving (depth noise "
                "grows with the square of the range)")
          .integer("track_depth_min_cells", &P::track_depth_min_cells, "", 1, 1000,
                   "depth: at least this many neighbouring cells must move in together (a body "
                   "stepping in, not a flickering edge)")
          .real("track_gate", &P::track_gate, "m", 0.05, 5,
                "a moving cluster continues the track whose predicted centroid is this close")
          .integer("track_min_cells", &P::track_min_cells, "", 1, 1000,
                   "a moving cluster must cover this many cells to start a track (a body moving "
                   "in, not the edge cell of a post that grazing rays saw free); smaller ones "
                   "continue a track, or stay plain obstacles");
  return t;
}

const ParamTable<SafetyParams>& SafetyParams::table() {
  using P = SafetyParams;
  static const auto t = ParamTable<P>()
                            .real("sensor_timeout", &P::sensor_timeout, "s", 0.01, 10,
                                  "stop when the newest scan is older")
                            .real("odom_timeout", &P::odom_timeout, "s", 0.01, 10,
                                  "stop when the newest odometry is older")
                            .real("intent_timeout", &P::intent_timeout, "s", 0.01, 10,
                                  "walker: stop when the user's command is older")
                            .real("intent_deadband", &P::intent_deadband, "", 0, 1,
                                  "walker: user commands below this (m/s, rad/s) mean stop");
  return t;
}

namespace {
/** The keys of T's section: each was a key of [navigation] under the same name. */
template <class T>
std::vector<std::string> keysOf() {
  // Keys added after [navigation] was split never had an old name.
  static const std::set<std::string> kNewer = {"static_memory"};
  std::vector<std::string> keys;
  for (const auto& spec : T::table().specs())
    if (!kNewer.count(spec.key)) keys.push_back(spec.key);
  return keys;
}
}  // namespace

NavigationParams NavigationParams::fromProfile(const Profile& profile) {
  NavigationParams p = profile.section<NavigationParams>("navigation");
  static_cast<UserIntentDwaParams&>(p) =
      profile.section<UserIntentDwaParams>("nav.user_intent_dwa");
  static_cast<GoalDwaParams&>(p) = profile.section<GoalDwaParams>("nav.goal_dwa");
  static_cast<LocalMapParams&>(p) = profile.section<LocalMapParams>("nav.local_map");
  static_cast<PeopleParams&>(p) = profile.section<PeopleParams>("nav.people");
  static_cast<SafetyParams&>(p) = profile.section<SafetyParams>("nav.safety");
  static_cast<CommitmentParams&>(p) = profile.section<CommitmentParams>("nav.commitment");
  return p;
}

void registerProfileSections() {
  auto& reg = ProfileSchemas::instance();
  reg.add(SectionSchema::of(
      NavigationParams::table(), "navigation",
      "navigation: local planner plugin, trajectory rollout and dynamic window, global route, "
      "goal tolerance"));
  reg.add(SectionSchema::of(UserIntentDwaParams::table(), "nav.user_intent_dwa",
                            "user-intent-dwa local planner: cost weights of [Rosa17, Eq. 4.10]"));
  reg.add(SectionSchema::of(GoalDwaParams::table(), "nav.goal_dwa",
                            "goal-dwa local planner: critics, look-ahead and corners"));
  reg.add(SectionSchema::of(LocalMapParams::table(), "nav.local_map",
                            "local cost map and obstacle memory"));
  reg.add(SectionSchema::of(PeopleParams::table(), "nav.people",
                            "moving obstacles (people): growth, tracking, predicted lanes"));
  reg.add(SectionSchema::of(SafetyParams::table(), "nav.safety",
                            "safety supervisor: stale data and user-command timeouts"));
  reg.addRenames("navigation", "nav.user_intent_dwa", keysOf<UserIntentDwaParams>());
  reg.addRenames("navigation", "nav.goal_dwa", keysOf<GoalDwaParams>());
  reg.addRenames("navigation", "nav.local_map", keysOf<LocalMapParams>());
  reg.addRenames("navigation", "nav.people", keysOf<PeopleParams>());
  reg.addRenames("navigation", "nav.safety", keysOf<SafetyParams>());
  reg.add(SectionSchema::of(CommitmentParams::table(), "nav.commitment",
                            "committing to a way through clutter: goal-dwa keeps its turn and "
                            "drives forward"));
  reg.add(SectionSchema::of(
      MrptPtgParams::table(), "nav.mrpt_ptg",
      "mrpt-ptg local planner: MRPT's TP-space reactive navigation (PTGs, holonomic method)"));
  reg.add(SectionSchema::of(
      ManeuverParams::table(), "nav.maneuver",
      "footprint maneuvers of the recoveries: forward and reverse arcs and turns on the spot "
      "to the route further on (Hybrid A* on the local cost map)"));
  reg.add(SectionSchema::of(
      RecoveryParams::table(), "nav.recovery",
      "recovery behaviours of goal robots: back out along the recent path, turn, wait, "
      "replan, give up"));
}

}  // namespace carenav::navigation
