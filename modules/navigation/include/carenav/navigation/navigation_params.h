// Parameters of the navigation module: the profile's [navigation] section and
// one [nav.*] section per class that reads them.
#pragma once

#include <carenav/common/params.h>
#include <carenav/common/profile.h>

#include <string>

namespace carenav::navigation {

/** Dynamic window and trajectory rollout ([Rosa17, Alg. 4, Table 5.1]),
 *  shared by both DWA planners (and the rollouts of mrpt-ptg, the safety
 *  supervisor and the Navigator): general keys of [navigation], listed by
 *  NavigationParams::table().
 */
struct DwaParams {
  double sim_time = 3.0;     ///< s, horizon of each sampled trajectory (walker: 7.0)
  double sim_step = 0.1;     ///< s, rollout step
  double window_time = 0.5;  ///< s, time constant of the dynamic window (v +- acc_v * this)
  int v_samples = 12;        ///< samples of v per direction (forward, and backward when allowed)
  int w_samples = 11;        ///< samples of w across the window
  double clearance_influence = 0.3;    ///< m, lateral clearance beyond this is not told apart
  double obstacle_distance_cap = 2.0;  ///< m, arcs are checked at least this far; farther is free
};

/** [nav.user_intent_dwa]: the cost of [Rosa17, Eq. 4.10], read by the
 *  user-intent DWA (walker shared control); the k values are not in the thesis.
 *  ```ini
 *  [nav.user_intent_dwa]
 *  k_0 = 1.0   ; m, weight of 1 / free distance along the arc
 *  ```
 */
struct UserIntentDwaParams {
  double k_s = 0.01;  ///< weight of the summed cell cost along the path
  double k_0 = 1.0;   ///< m, weight of 1 / dist(v, w) (free distance along the arc)
  double k_1 = 0.5;   ///< penalty when the direction differs from the user's
  double k_2 = 0.05;  ///< weight of the end-pose distance term
  static const ParamTable<UserIntentDwaParams>& table();
};

/** [nav.goal_dwa]: the critics of the goal DWA ([Fox97], [Conceicao16, Ch. 3]).
 *  `lookahead` is also where the simulated walker user steers.
 *  ```ini
 *  [nav.goal_dwa]
 *  k_heading = 1.0   ; 1/rad
 *  ```
 */
struct GoalDwaParams {
  double k_heading = 1.0;         ///< weight of the heading error to the next waypoint (rad)
  double k_path = 0.5;            ///< weight of the end-pose distance to the global path (m)
  double k_speed = 0.5;           ///< weight of (v_max - v) / v_max
  double k_goal_obs = 0.3;        ///< s, weight of 1 / time to the nearest obstacle on the arc
  double turn_in_place_deg = 60;  ///< turn on the spot when the waypoint is further off
  double score_time = 1.5;        ///< s, critics are taken at the pose reached then
  double lookahead = 1.0;         ///< m, waypoint distance along the path ahead of the robot
  double corner_deg = 10;         ///< deg, goes to route vertices turning more (0: cuts all)
  double align_deg = 20;  ///< deg, facing the route within this, or able to turn to it (180: off)
  static const ParamTable<GoalDwaParams>& table();
};

/** [nav.commitment]: committing to a way through clutter, read by goal-dwa.
 *  ```ini
 *  [nav.commitment]
 *  k_switch = 0.3
 *  reverse = false
 *  ```
 */
struct CommitmentParams {
  /** goal-dwa, hysteresis (as the oscillation critic of ROS's DWB local
   *  planner): extra cost of a candidate that backs up after a command
   *  forward, and the margin (over k_heading, in rad) by which the other
   *  side must be shorter for a turn on the spot to change direction
   *  (0: chosen afresh every cycle). */
  double k_switch = 0.3;
  /** goal-dwa: backward candidates in the planner's own window. Off: it
   *  drives forward (slowing down when it moves backward); backing up is
   *  left to the recoveries, which retrace the way the robot came (known
   *  free), while the planner's memory of what lies behind may have aged
   *  out. */
  bool reverse = false;
  static const ParamTable<CommitmentParams>& table();
};

/** [nav.local_map]: robot-centred local cost map and obstacle memory
 *  (HOBBIT, [Puente14, App. Sec. IV-C, Table I]); read by LocalCostmap and
 *  the Navigator's obstacle memory.
 *  ```ini
 *  [nav.local_map]
 *  obstacle_persistence = 5.0   ; s
 *  ```
 */
struct LocalMapParams {
  double local_size = 8.0;            ///< m, side of the robot-centred local grid
  double resolution = 0.05;           ///< m, cell size of the local grid
  double obstacle_persistence = 5.0;  ///< s, remembered this long where a sensor looks
  double memory_radius = 3.0;         ///< m, remembered obstacles farther away are dropped
  double cost_decay = 0.3;            ///< m, cell cost falls from 100 to 0 over this clearance
  double footprint_padding = 0.02;    ///< m, closer than this to an obstacle counts as contact
  static const ParamTable<LocalMapParams>& table();
};

/** [nav.people]: moving obstacles (people), read by the Navigator and its
 *  MovingTracker. An obstacle in a cell seen free just before is taken to be
 *  moving and grown by how far a person walks meanwhile; tracked ones are
 *  swept along their velocity.
 *  ```ini
 *  [nav.people]
 *  predict_horizon = 2.0   ; s, 0: tracks sweep no lanes
 *  ```
 */
struct PeopleParams {
  double predict_speed = 0.5;     ///< m/s, assumed speed of a moving obstacle (0: no prediction)
  double predict_time = 1.0;      ///< s, look-ahead of that growth (inflation = speed x time)
  double dynamic_window = 1.5;    ///< s, a cell seen free this recently and now occupied is moving
  double dynamic_min_free = 0.3;  ///< s, ... after being seen free for at least this long
  /** s, a cell hit less than this before its latest stretch of being seen
   *  free began is the edge of something static (rays graze a thin post's
   *  edge cells from one side and hit them from another), not moved in.
   *  0 (off) by default: at 2-10 s a person crossing the robot's way is no
   *  longer seen moving (docs/BENCHMARKS.md, "Navigation in clutter"). */
  double static_memory = 0.0;
  double predict_horizon = 2.0;  ///< s, tracked moving obstacles are swept along their velocity
                                 ///< this far (0: no lanes, no hidden regions)
  double route_predict_horizon = 8.0;  ///< s, the route avoids a tracked person's lane this far
  double track_radius = 8.0;           ///< m, moving obstacles are told apart from walls this far
  double track_depth_range = 3.0;      ///< m, depth-camera cells farther away never count as moving
  int track_depth_min_cells = 3;       ///< depth: cells moving in together (a body, not noise)
  double track_gate = 0.6;  ///< m, a moving cluster continues the track predicted this close
  int track_min_cells = 3;  ///< cells a moving cluster covers to start a track (a body)
  static const ParamTable<PeopleParams>& table();
};

/** [nav.safety]: the safety supervisor's stale-data and stop rules.
 *  ```ini
 *  [nav.safety]
 *  sensor_timeout = 0.5   ; s
 *  ```
 */
struct SafetyParams {
  double sensor_timeout = 0.5;    ///< s, stop when the newest scan is older
  double odom_timeout = 0.5;      ///< s, stop when the newest odometry is older
  double intent_timeout = 0.5;    ///< s, walker: stop when the user's command is older
  double intent_deadband = 0.01;  ///< m/s and rad/s, user commands below count as "stop"
  static const ParamTable<SafetyParams>& table();
};

/** Every navigation parameter: the general keys of [navigation] (plugin,
 *  trajectory rollout and dynamic window shared by the local planners, global
 *  route; DwaParams) and, as bases, the structs of the sections above, each read from
 *  its own section by fromProfile(). The robot's limits (v_max, v_min, w_max,
 *  acc_v, acc_w, footprint, safe_distance) come from [robot].
 *  ```ini
 *  [navigation]
 *  plugin = user-intent-dwa   ; user-intent-dwa | goal-dwa | mrpt-ptg
 *  sim_time = 7.0             ; s ([Rosa17, Table 5.1])
 *  ```
 *  Profiles of the previous version set every key in [navigation]; those
 *  keys are still read under their old names (registerProfileSections()
 *  declares them renamed).
 */
struct NavigationParams : DwaParams,
                          UserIntentDwaParams,
                          GoalDwaParams,
                          LocalMapParams,
                          PeopleParams,
                          SafetyParams,
                          CommitmentParams {
  std::string plugin = "goal-dwa";  ///< local method, by name (LocalPlannerRegistry)
  // Global route (A* on the inflated static map) and goal
  double plan_clearance = 0.1;  ///< m, extra clearance kept by the route beyond the footprint
  double plan_cost_weight = 2;  ///< extra route cost per metre near obstacles (keeps paths central)
  double passage_margin = 0.25;   ///< m, route cells closer than radius + this are a narrow passage
  double passage_approach = 0.6;  ///< m, waypoints before and after a passage, on its axis
  /** The route must be one the footprint can drive forward (each segment at
   *  its heading, turning on the spot at its vertices), keeping
   *  route_footprint_margin; where the inscribed circle's route is not, a
   *  search over poses (at most route_footprint_nodes expansions) finds one
   *  that is; replanning then also leaves the map's own obstacles unmarked
   *  and checks the route ahead of the robot only. Off (the default: on
   *  the clutter benchmark it was no better, docs/BENCHMARKS.md): the
   *  circle's route. */
  bool route_footprint = false;
  double route_footprint_margin = 0.03;  ///< m
  int route_footprint_nodes = 60000;
  /** Replanning drops the route only for what the map does not show,
   *  ahead of the robot: lidar hits on or beside the map's own obstacle
   *  cells are those obstacles seen again (a pose known to a few cm puts
   *  them a cell off) and are not marked; the route is checked from the
   *  robot's nearest point on it on; and where the map itself leaves the
   *  route less than its clearance (the line through a tight gap), the
   *  map's clearance is enough. Off: every replanning found the route
   *  through a tight gap blocked by the map itself or by its own posts
   *  seen again, and planned anew, the way flipping between near-equal
   *  ones (docs/BENCHMARKS.md, clutter). */
  bool replan_new_only = true;
  double goal_tolerance = 0.5;    ///< m, goal reached ([Conceicao16])
  double goal_tolerance_deg = 3;  ///< deg, heading at the goal ([Conceicao16]: 0.05 rad)
  /** The keys of [navigation] only (the general ones). */
  static const ParamTable<NavigationParams>& table();
  /** [navigation], [nav.user_intent_dwa], [nav.goal_dwa], [nav.local_map],
   *  [nav.people], [nav.safety] and [nav.commitment] of `profile`, old keys
   *  included. */
  static NavigationParams fromProfile(const Profile& profile);
};

/** Registers [navigation] and the [nav.*] sections with the profile schemas,
 *  and the keys that moved from [navigation] to them. */
void registerProfileSections();

}  // namespace carenav::navigation
