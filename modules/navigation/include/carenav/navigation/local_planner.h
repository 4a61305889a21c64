// Local planners ("plugins", chosen by name in the profile): one control
// cycle turns the robot's state, the local cost map and the user's command
// or the route into a velocity command.
#pragma once

#include <carenav/common/robot.h>
#include <carenav/navigation/local_map.h>
#include <carenav/navigation/navigation_params.h>

#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace carenav::navigation {

/** A velocity command of a differential drive. */
struct Twist {
  double v = 0;  ///< m/s, forward
  double w = 0;  ///< rad/s, counter-clockwise
};

/** Pose after moving for `t` seconds at constant (v, w) from `p` (exact arc). */
TPose2D integrateArc(const TPose2D& p, double v, double w, double t);

/** rad, a - b wrapped to [-pi, pi]. */
inline double angleDiff(double a, double b) { return std::atan2(std::sin(a - b), std::cos(a - b)); }

/** Where a new command starts from: the robot does not take it at once.
 *  The command sent now takes effect `latency` seconds later (until then
 *  the last one sent still drives), and each of v and w then moves towards
 *  its target at the robot's acceleration (acc_v, acc_w), as the simulator
 *  and a velocity-controlled base do. The next command (a stop) can be sent
 *  `period` seconds later (the control cycle). The trajectory generators of
 *  ROS's base_local_planner start from the measured velocity likewise. */
struct MotionState {
  Twist current;       ///< measured velocity now
  Twist commanded;     ///< the last command sent: it drives for `latency`
  double latency = 0;  ///< s, between a command and its effect
  double period = 0;   ///< s, until the next command can be sent
};

/** The motion of the robot given `cmd` now from `state` (MotionState): v
 *  and w go towards state.commanded for the latency, then towards `cmd`,
 *  and from `brake_at` seconds on (when finite) towards 0, each at the
 *  robot's acceleration. Integrated every 10 ms until the velocity settles,
 *  then exact arcs. */
class CommandMotion {
 public:
  CommandMotion(const TPose2D& start, const MotionState& state, const Twist& cmd,
                const RobotParams& robot,
                double brake_at = std::numeric_limits<double>::infinity());
  /** Pose after t seconds (heading wrapped to [-pi, pi]). */
  TPose2D pose(double t) const;
  /** rad, the heading change after t seconds, not wrapped. */
  double turned(double t) const;
  /** s from which the velocity is constant (cmd, or 0 once braked). */
  double settled() const { return settle_t_; }
  /** The velocity from settled() on. */
  const Twist& final() const { return final_; }

 private:
  struct Knot {
    TPose2D pose;
    double turned = 0;
  };
  double dt_ = 0.01;
  std::vector<Knot> knots_;  // every dt_ from 0 to settle_t_
  double settle_t_ = 0;
  Twist final_;
};

/** One sampled trajectory of the dynamic window, rolled out on the cost map. */
struct Trajectory {
  Twist cmd;
  bool collides = false;         ///< the footprint hits an obstacle within the horizon
  bool leaves_map = false;       ///< the footprint leaves the local grid within the horizon
  double time_to_collision = 0;  ///< s, along the arc (the horizon when none)
  double clearance = 0;          ///< m, smallest footprint clearance along the path (capped)
  /** m, dist(v, w) of [Rosa17, Eq. 4.1]: how far the footprint sweeps along
   *  the arc before the first contact (path length plus the turn times the
   *  circumscribed radius); infinity when it reaches the horizon free. */
  double free_distance = 0;
  /** s until that contact at this command (also beyond the horizon, as far
   *  as the check went); infinity when none. */
  double contact_time = 0;
  double occupancy = 0;  ///< summed cell cost (0..100 per step) along the path
  TPose2D end;           ///< pose at the end of the horizon (or of the last safe step)
  double cost = 0;       ///< the planner's score, lower is better
  bool admissible() const { return !collides && !leaves_map; }
};

/** Rolls (v, w) out from `start` for `horizon` seconds at `step`, checking
 *  the footprint at every step; clearance capped at `clearance_cap`. When
 *  the arc covers less than `check_distance` metres in the horizon, the
 *  collision check (only) goes on until it does, so that a slow trajectory
 *  is not taken for a free one because it stops short of the obstacle; an
 *  arc that has closed its circle there is not followed further (the rest
 *  repeats it, at the sampling resolution). */
Trajectory rollout(const LocalCostmap& map, const TPose2D& start, const Twist& cmd, double horizon,
                   double step, double clearance_cap, double check_distance = 0);
/** The same along `motion` (the robot's motion given `cmd`, CommandMotion)
 *  instead of the arc of `cmd` from the start: what the robot will
 *  actually do when `cmd` is sent now. */
Trajectory rollout(const LocalCostmap& map, const CommandMotion& motion, const Twist& cmd,
                   double horizon, double step, double clearance_cap, double check_distance = 0);

/** True when the footprint at `pose`, turned on the spot by `turn` rad
 *  (either sign), touches nothing on `map` (samples every 0.1 rad). */
bool turnFree(const LocalCostmap& map, const TPose2D& pose, double turn);

/** s of `cmd` that cover `margin` metres: of path when it moves; of a
 *  corner's travel (the turn times `sweep_radius`, the footprint's
 *  circumscribed radius) when it turns on the spot; 0 for a turn without a
 *  radius given. */
double marginTime(const Twist& cmd, double margin, double sweep_radius = 0);

/** True when, braking at the robot's limits along the same arc from `cmd`,
 *  the robot stops at least `margin` metres (of path; of a corner's travel
 *  on the spot, with `sweep_radius`: marginTime) before the first contact
 *  `time_to_collision` seconds ahead at that command ([Rosa17] Eq. 4.1 with
 *  proportional braking of v and w). */
bool canBrake(const Twist& cmd, double time_to_collision, const RobotParams& robot, double margin,
              double sweep_radius = 0);

/** What a planner gets each cycle. Poses are in the cost map's frame. */
struct PlannerInput {
  double t = 0;
  TPose2D pose;
  Twist current;  ///< measured velocity
  /** The robot's dynamics for this cycle (the Navigator sets it): planners
   *  roll candidates out from it (CommandMotion) and judge them with the
   *  supervisor's stopRoom. Unset: a command is taken at once. */
  std::optional<MotionState> motion;
  const LocalCostmap* map = nullptr;
  std::optional<Twist> user;    ///< the user's command (walker)
  std::vector<TPoint2D> path;   ///< global route ahead (goal navigation)
  std::optional<TPose2D> goal;  ///< final goal (goal navigation)
};

/** The heading of a goal that may be reached facing any way (`goal: [x, y]`,
 *  `--goal x,y`). Navigator::setRoute takes it; the planners never see it:
 *  their goal then has the robot's own heading, so none turns at the goal. */
inline constexpr double kAnyHeading = std::numeric_limits<double>::quiet_NaN();

/** What a plan came to: the navigator and the recovery behaviours read
 *  this, people read PlannerOutput::note. */
enum class PlanStatus {
  Moving,         ///< a command along the route, or as the user asks
  TurnInPlace,    ///< turning on the spot towards the route or the goal heading
  GoalReached,    ///< at the goal with its heading: stop
  NoRoute,        ///< no map, or neither route nor goal
  NoAdmissible,   ///< no admissible trajectory (the supervisor stops)
  NoUserCommand,  ///< walker: the user gave no command yet
  UserStopped,    ///< walker: the user's command is a stop
};
/** "goal reached", "no route", ...: the note of a status. */
const char* planStatusText(PlanStatus s);

/** What a planner answers. */
struct PlannerOutput {
  bool ok = false;  ///< false: no admissible trajectory (the supervisor stops)
  Twist cmd;
  PlanStatus status = PlanStatus::Moving;
  std::string note;  ///< why not ok, or what it did ("turn in place")
  /** Sets the status and the note: `text`, or the status's own text. */
  void mark(PlanStatus s, const std::string& text = "") {
    status = s;
    note = text.empty() ? planStatusText(s) : text;
  }
  /** m, the margin the supervisor keeps before a contact for this command
   *  (its braking rule); negative: the robot's safe_distance. A recovery's
   *  crawl out of a wedge asks for its smaller backup_margin. */
  double margin = -1;
  /** The robot can neither go on nor turn on the spot to face the way the
   *  route goes on (goal-dwa): held, as when nothing is admissible, so the
   *  recoveries back it out instead of a dither of small turns. */
  bool wedged = false;
  size_t evaluated = 0, admissible = 0;
  std::vector<Trajectory> trajectories;  ///< every candidate (for pictures and tests)
};

/** The dynamic window ([Rosa17, Eqs. 4.4-4.7]): reachable velocities within
 *  window_time at the robot's accelerations, inside its limits. */
struct Window {
  double v_lo = 0, v_hi = 0, w_lo = 0, w_hi = 0;
};
Window dynamicWindow(const Twist& current, const RobotParams& robot, const DwaParams& p);
/** Samples of the window: v_samples forward and v_samples backward (when
 *  the window reaches below zero), w_samples across, always 0 and the
 *  window's bounds; plus `extra` (clamped into the window). */
std::vector<Twist> sampleWindow(const Window& w, const DwaParams& p,
                                const std::vector<Twist>& extra = {});

/** A local method. */
class LocalPlanner {
 public:
  virtual ~LocalPlanner() = default;
  virtual std::string name() const = 0;
  virtual PlannerOutput plan(const PlannerInput& in) = 0;
  /** Walker-style planners need the user's command; goal planners a path. */
  virtual bool needsUserIntent() const = 0;
  /** True when the planner rolls its candidates out from the robot's state
   *  (PlannerInput::motion, goal-dwa): the Navigator then gives it that
   *  state and the supervisor judges its commands from the same state. The
   *  others' commands are judged as taken at once, as they plan them, so
   *  that planner and supervisor never judge different motions. */
  virtual bool usesMotionState() const { return false; }
};

using PlannerFactory =
    std::function<std::unique_ptr<LocalPlanner>(const NavigationParams&, const RobotParams&)>;

/** Local planners by name. The built-in ones (user-intent-dwa, goal-dwa)
 *  are registered on first use. */
class PlannerRegistry {
 public:
  static PlannerRegistry& instance();
  void add(const std::string& name, const std::string& description, PlannerFactory f);
  /** Throws InputError naming the known plugins for an unknown name. */
  std::unique_ptr<LocalPlanner> create(const std::string& name, const NavigationParams& p,
                                       const RobotParams& robot) const;
  std::vector<std::pair<std::string, std::string>> list() const;  ///< name, description

 private:
  PlannerRegistry();
  std::map<std::string, std::pair<std::string, PlannerFactory>> entries_;
};

/** The point `lookahead` metres along the polyline after the point of it
 *  nearest to (x, y); its last point when the rest is shorter. With
 *  `corner` (rad) below pi the look-ahead stops at a vertex where the
 *  polyline turns by more than that, until (x, y) is within `reached` of
 *  it or abeam of it (its nearest point on the polyline less than `reached`
 *  before it): the robot goes to the corner instead of cutting it (the approach
 *  point of a narrow passage is such a corner: it enters on the axis).
 *  A one-point path gives its point, an empty one (x, y). */
TPoint2D lookaheadPoint(const std::vector<TPoint2D>& path, double x, double y, double lookahead,
                        double corner = M_PI, double reached = 0.15);

/** What a goal planner follows: the route ahead (the goal alone when the
 *  route is empty) and the distance from the robot to its end. */
struct RouteAhead {
  std::vector<TPoint2D> path;  ///< never empty
  double to_end = 0;           ///< m, robot to path.back()
};
/** The route of `in`; nothing when there is no map, or neither route nor
 *  goal (the plan is then PlanStatus::NoRoute). */
std::optional<RouteAhead> routeAhead(const PlannerInput& in);

/** [Rosa17]'s shared control for a walker (Alg. 4, Eq. 4.10). */
std::unique_ptr<LocalPlanner> makeUserIntentDwa(const NavigationParams& p, const RobotParams& r);
/** Goal-directed DWA: heading to the next waypoint, clearance, speed,
 *  distance to the route; turns in place when the waypoint is far off. */
std::unique_ptr<LocalPlanner> makeGoalDwa(const NavigationParams& p, const RobotParams& r);
/** MRPT's TP-space reactive navigation (PTGs + a holonomic method) towards
 *  the route, with the default [nav.mrpt_ptg] parameters (see mrpt_ptg.h for
 *  the parameters and configureMrptPtg). Goal-only: it ignores user intent. */
std::unique_ptr<LocalPlanner> makeMrptPtg(const NavigationParams& p, const RobotParams& r);

}  // namespace carenav::navigation
