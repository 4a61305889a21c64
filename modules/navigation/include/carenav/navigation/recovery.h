// Recovery behaviours around every goal plugin: when the robot is boxed in
// (no admissible trajectory, or the supervisor keeps stopping it) or makes
// no progress along its route, it maneuvers its footprint to the route
// further on (maneuver.h), else backs out along the way it came (the
// recent path is known free), else turns on the spot where the footprint
// can, else waits; then the planner resumes on a fresh route. After
// `max_attempts` recoveries without progress it gives up, with the reason.
// Nav2's behaviour-tree recoveries (back up, spin, wait, replan) are the
// model; the order is the supervisor's order of safety.
#pragma once

#include <carenav/common/params.h>
#include <carenav/common/robot.h>
#include <carenav/navigation/local_map.h>
#include <carenav/navigation/local_planner.h>
#include <carenav/navigation/maneuver.h>

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace carenav::navigation {

/** [nav.recovery]: when a goal robot counts as stuck and how it recovers. */
struct RecoveryParams {
  bool enabled = true;             ///< off: the planner alone (a stuck robot stays stuck)
  double stuck_time = 1.0;         ///< s, blocked (no admissible trajectory, stopped) this long
  double progress_time = 10.0;     ///< s, ... or the route left has not shrunk for this long
  double progress_distance = 0.3;  ///< m, ... by this much
  /** s, ... or the robot has stood still this long: moved less than
   *  still_distance and turned less than still_deg (a planner turning left
   *  and right on the spot, never blocked, waited out the whole
   *  progress_time); 0: off. */
  double still_time = 3.0;
  double still_distance = 0.05;  ///< m
  double still_deg = 30;         ///< deg
  double backup_distance = 0.4;  ///< m, backed out along the recent path per attempt
  double backup_speed = 0.2;     ///< m/s, reversing speed (at most the robot's -v_min)
  double backup_margin = 0.03;  ///< m, the supervisor's margin for these crawls (not safe_distance)
  double path_corridor = 0.1;   ///< m, reversing stays this close to the recorded path
  double spin_deg = 90;         ///< deg, most a spin turns per attempt
  double wait_time = 1.0;       ///< s, waiting when neither backing out nor turning is free
  int max_attempts = 6;         ///< recoveries without progress before giving up
  double path_memory = 3.0;     ///< m, of the robot's own recent path kept
  /** Recoveries that began within 2 x avoid_radius of the first at one
   *  place: once avoid_after of them have, the route is planned around a
   *  disk of avoid_radius there (RouteReplanner); 0: never. */
  int avoid_after = 2;
  double avoid_radius = 0.2;  ///< m
  /** The odometry's error bound, per metre travelled (m/m), per radian
   *  turned (rad/rad) and per metre travelled in heading (rad/m): a
   *  recorded pose is known free only while the error since it was
   *  recorded, at the footprint's corners, is at most backup_margin. */
  double odom_error_d = 0.02;
  double odom_error_w = 0.02;
  double odom_error_wd = 0.01;
  /** s, a maneuver may also reverse where a sensor saw free space this
   *  recently (and the odometry error since is within backup_margin): a
   *  270 deg lidar's blind rear was in view before; 0: over the recorded
   *  path only. */
  double seen_keep = 30;
  static const ParamTable<RecoveryParams>& table();
};

/** The recovery state machine (odometry frame). Tested alone in
 *  tests/unit/navigation/test_recovery.cpp. */
class Recovery {
 public:
  enum class Phase { Idle, Maneuver, BackUp, Spin, Wait, GaveUp };
  Recovery(const RecoveryParams& p, const RobotParams& robot, const NavigationParams& nav,
           const ManeuverParams& mp = {});

  /** The robot's pose each cycle (its recent path: known free). */
  void recordPose(const TPose2D& pose);
  /** A scan in the odometry frame at time `t`: the space its rays crossed
   *  was free (a maneuver may reverse over it; seen_keep). */
  void addSeen(const WorldScan& scan, double t);
  /** One cycle: `plan` is the planner's answer, `blocked` whether the
   *  robot was held (planner found nothing or the supervisor stopped it),
   *  `route_left` the route length still to go (m). Returns the command to
   *  use instead of the plan while a recovery runs (or after giving up). */
  std::optional<PlannerOutput> step(double now, const PlannerInput& in, const PlannerOutput& plan,
                                    bool blocked, double route_left);
  /** A fresh route (replanned): progress is measured on it from now, what
   *  was gained since the last progress kept; the time since the last
   *  progress keeps running (a robot whose route is replanned every few
   *  seconds while it goes nowhere is still caught). */
  void routeChanged(double now);
  /** A new goal: whatever happened on the way to the last one (attempts,
   *  giving up) is forgotten; the recorded path is kept (still known free). */
  void newGoal(double now);

  /** The command that backs out along the recorded path from `pose`
   *  (reversing when the way back lies behind, forwards when the robot has
   *  turned to face it), when it is admissible: the supervisor passes it
   *  unchanged (brakingScale 1: braking at the robot's limits ends
   *  safe_distance before any obstacle of `map`) and the poses it sweeps
   *  until it could stop stay within path_corridor of the recorded path. */
  std::optional<Twist> backOutCommand(const LocalCostmap& map, const TPose2D& pose) const;
  /** True when moving at `cmd` (v != 0) from `pose` is admissible (see above). */
  bool reverseAdmissible(const LocalCostmap& map, const TPose2D& pose, const Twist& cmd) const;

  Phase phase() const { return phase_; }
  static const char* phaseName(Phase p);
  size_t recoveries() const { return recoveries_; }
  bool gaveUp() const { return phase_ == Phase::GaveUp; }
  const std::string& reason() const { return reason_; }
  /** Where the last recovery began (odometry frame). */
  const TPose2D& startedAt() const { return start_pose_; }
  /** True once after each recovery: the route should be planned again. */
  bool takeReplanRequest() {
    const bool r = replan_;
    replan_ = false;
    return r;
  }
  const std::vector<TPose2D>& path() const { return path_; }
  /** The maneuver under way (Phase::Maneuver), for pictures and tests. */
  const std::optional<Maneuver>& maneuver() const { return man_; }

 private:
  void start(double now, const PlannerInput& in, const std::string& why);
  void finish(double now);
  /** Ends a back-out: the part of the recorded path it retraced is behind
   *  the robot no more. */
  void cutRetraced();
  PlannerOutput command(const Twist& cmd, const std::string& note) const;
  /** A turn on the spot towards the route where the footprint's sweep is
   *  free, else the other way unless `toward_only`. */
  std::optional<Twist> spinCommand(const PlannerInput& in, bool toward_only = false) const;
  /** rad, the turn from the robot's heading to the way the route goes on
   *  (to its look-ahead point; to the goal without a route). */
  double routeError(const PlannerInput& in) const;
  /** True when the robot faces the route within kFacing, or its footprint
   *  can turn on the spot to within kFacing of it. */
  bool canFaceRoute(const PlannerInput& in) const;
  size_t nearestIndex(const TPose2D& pose) const;
  /** A footprint maneuver from the robot to the route `reach` m further on
   *  (ManeuverPlanner; reversing only over the way the robot came). */
  std::optional<Maneuver> planManeuver(const PlannerInput& in) const;
  /** The pose the maneuver aims at: on the route, facing its way, where the
   *  footprint touches nothing (the first such from `reach` on). */
  std::optional<TPose2D> maneuverGoal(const PlannerInput& in) const;
  /** The command of the maneuver's current step; none when every step is
   *  driven (man_step_ past the last) or none is admissible any more. */
  std::optional<Twist> maneuverCommand(const PlannerInput& in);
  /** The admissible command of step `s` with `remaining` m or rad of it
   *  left (slowed when the supervisor's rule needs it); none when none is. */
  std::optional<Twist> stepCommand(const PlannerInput& in, const ManeuverStep& s,
                                   double remaining) const;
  /** Plans the maneuver again from the robot's pose (kManeuverReplans
   *  times at most); false when that is used up or none is found. */
  bool replanManeuver(const PlannerInput& in);
  /** m/s of a maneuver's straights and arcs (`dir` 1 forward, -1 reverse):
   *  backup_speed within the robot's limits; rad/s of its turns on the spot. */
  double maneuverSpeed(int dir) const;
  double maneuverTurnRate() const;
  /** s, the maneuver at those speeds. */
  double maneuverDuration(const Maneuver& m) const;
  /** The back-out, turn or wait that begins a recovery without a maneuver. */
  void startFallback(double now, const PlannerInput& in);

  RecoveryParams p_;
  RobotParams r_;
  NavigationParams nav_;
  ManeuverPlanner planner_;
  std::optional<Maneuver> man_;
  size_t man_step_ = 0;        // the step under way
  double man_done_ = 0;        // m or rad of it done
  double man_limit_ = 0;       // s, the maneuver is abandoned after this
  int man_replans_ = 0;        // maneuvers planned again after a step ended off its pose
  std::vector<TPose2D> path_;  // oldest first
  /** The odometry travelled and turned (m, rad) when each pose of path_ was
   *  recorded, and since the start. */
  std::vector<std::pair<double, double>> path_odo_;
  double travel_ = 0, turned_ = 0;
  std::optional<TPose2D> odo_last_;
  double lever_ = 0;  // m, the footprint's farthest corner from the centre
  SeenFree seen_;
  /** m, the error at the footprint's corners of what the odometry measured
   *  after it had travelled `travel` m and turned `turned` rad. */
  double odomError(double travel, double turned) const;
  /** A sighting still trusted at `now` (seen_keep, odometry error). */
  bool fresh(const SeenFree::Sight& s, double now) const;
  /** m, around the robot: where a maneuver's footprint can reach. */
  double knownRadius() const;
  /** Adds the motion since the last recorded cycle, and forgets the oldest
   *  poses whose odometry error since may exceed backup_margin. */
  void trackOdometry(const TPose2D& pose);
  Phase phase_ = Phase::Idle;
  std::string reason_;
  size_t recoveries_ = 0;
  int attempts_ = 0;  // since the last progress
  bool replan_ = false;
  std::optional<double> blocked_since_;
  double best_left_ = 0, best_t_ = 0;
  bool have_best_ = false;
  std::optional<std::pair<TPose2D, double>> still_;  // where and when the robot stood still from
  /** Whether the robot has stood still for still_time (and starts the
   *  window again when it moved or turned, or is at the goal). */
  bool standingStill(double now, const TPose2D& pose, bool at_goal);
  bool rebase_ = false;   // a new route: best_left_ is measured on it from the next cycle
  double last_left_ = 0;  // the route left at the last cycle
  // current recovery
  double phase_t0_ = 0;
  TPose2D phase_pose_;
  double backed_ = 0, spun_ = 0, spin_dir_ = 0;
  bool facing_ = false;  // the spin turns to face the route after a back-out
  TPose2D last_pose_;
  TPose2D start_pose_;  // where it began
  // the robot's dynamics of the cycle under way (PlannerInput::motion): the
  // supervisor judges a recovery's command from it, so the recovery does too
  std::optional<MotionState> motion_;
};

}  // namespace carenav::navigation
