// The safety supervisor around every local planner: the rules that stop or
// slow the robot whatever the planner says. Each rule is a tested invariant
// (tests/unit/navigation/test_safety.cpp).
#pragma once

#include <carenav/common/robot.h>
#include <carenav/navigation/local_planner.h>

#include <optional>
#include <string>

namespace carenav::navigation {

/** The supervisor's braking rule as a number (rule 5), shared with the
 *  planners and the recovery behaviours so that what they propose is what
 *  the supervisor passes: the factor s in [0, 1] by which (v, w) must be
 *  scaled, keeping the curvature, so that braking at the robot's limits
 *  along the arc ends `safe_distance` before the first contact (or the
 *  edge of the map) on `map` (`margin` instead of safe_distance when given), with contacts found
 * every `step` / 2 seconds and known to one such step. 1: passes unchanged; 0: must stop. */
double brakingScale(const LocalCostmap& map, const TPose2D& pose, const Twist& cmd,
                    const RobotParams& robot, double step, double margin);
/** True when sending `cmd` now from `state` leaves the robot able to stop
 *  `margin` before any contact: it follows `cmd` (CommandMotion: the last
 *  command for the latency, then ramps at its accelerations) until a stop
 *  sent at the next cycle takes effect (state.period + state.latency from
 *  now), and for the time `cmd` needs to cover `margin` (marginTime) more,
 *  then brakes at its limits; the footprint touches nothing and stays on
 *  the map all along (checked every cell of sweep: path plus a corner's
 *  travel, and where it stops). */
bool canStopFrom(const LocalCostmap& map, const TPose2D& pose, const MotionState& state,
                 const Twist& cmd, const RobotParams& robot, double margin);
/** brakingScale from the robot's dynamics (`state`; nullptr: the command
 *  at once, as above): the largest s in [0, 1] (to 1/64) for which
 *  canStopFrom holds for (s v, s w); a robot already in contact gets
 *  brakingScale's move-away rule. */
double brakingScale(const LocalCostmap& map, const TPose2D& pose, const Twist& cmd,
                    const RobotParams& robot, double step, double margin, const MotionState* state);
/** The same with the robot's safe_distance as the margin. */
inline double brakingScale(const LocalCostmap& map, const TPose2D& pose, const Twist& cmd,
                           const RobotParams& robot, double step) {
  return brakingScale(map, pose, cmd, robot, step, robot.safe_distance);
}

struct SafetyInput {
  double now = 0;                        ///< s
  std::optional<double> last_scan_time;  ///< s, newest obstacle data (none yet: stale)
  std::optional<double> last_odom_time;  ///< s, newest odometry (none yet: stale)
  bool needs_intent = false;             ///< walker: the user's command drives
  std::optional<double> last_intent_time;
  std::optional<Twist> user;
  PlannerOutput plan;
  TPose2D pose;
  /** The robot's dynamics (the Navigator sets it): the braking rule then
   *  judges the motion the robot will make (canStopFrom), as goal-dwa does. */
  std::optional<MotionState> motion;
  const LocalCostmap* map = nullptr;
};

/** What the supervisor did. */
enum class SafetyAction {
  Pass,  ///< the planner's command, unchanged
  Slow,  ///< scaled down (same curvature) so the robot can brake in time
  Stop,  ///< (0, 0)
};
const char* safetyActionName(SafetyAction a);

/** The rule that stopped or changed the command (numbers of apply's list). */
enum class SafetyRule {
  None,           ///< passed unchanged
  StaleSensor,    ///< 1
  StaleOdometry,  ///< 2
  StaleIntent,    ///< 3: the user's command is too old
  UserStopped,    ///< 3: below the deadband
  NoPlan,         ///< 4: reason is the planner's note
  NoLocalMap,
  CannotBrake,  ///< 5: stop
  Braking,      ///< 5: slowed
  Limits,       ///< 6: clamped to the velocity limits
};

struct SafetyDecision {
  Twist cmd;
  SafetyAction action = SafetyAction::Stop;
  SafetyRule rule = SafetyRule::None;
  std::string reason;  ///< for Slow and Stop: the rule in words (the navlog's column)
};

/** Rules, in order:
 *  1. stop when there is no scan newer than sensor_timeout;
 *  2. stop when there is no odometry newer than odom_timeout;
 *  3. walker: stop when the user's command is older than intent_timeout or
 *     below intent_deadband (the user let go);
 *  4. stop when the planner found no admissible trajectory;
 *  5. scale (v, w) down, keeping the curvature, so that braking at the
 *     robot's limits along the arc ends safe_distance before the first
 *     obstacle on it (canBrake holds for the output);
 *     a footprint that already touches an obstacle gets (0, 0);
 *  6. never exceed the robot's velocity limits. */
class SafetySupervisor {
 public:
  /** `rollout`: the step of the braking checks (sim_step). */
  SafetySupervisor(const SafetyParams& p, const DwaParams& rollout, const RobotParams& robot)
      : p_(p), sim_step_(rollout.sim_step), r_(robot) {}
  SafetySupervisor(const NavigationParams& p, const RobotParams& robot)
      : SafetySupervisor(p, p, robot) {}
  SafetyDecision apply(const SafetyInput& in) const;
  /** s along the arc of `cmd` from `pose` until the footprint touches an
   *  obstacle (or leaves the map), looking `horizon` seconds ahead;
   *  infinity when none. */
  double timeToCollision(const LocalCostmap& map, const TPose2D& pose, const Twist& cmd,
                         double horizon) const;

 private:
  SafetyParams p_;
  double sim_step_;
  RobotParams r_;
};

}  // namespace carenav::navigation
