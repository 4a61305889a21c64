// The navigation loop of one robot, fed step by step: sensor data and
// odometry in, a supervised velocity command out. Used by `carenav
// navigate` with the simulator or a real robot's bridge.
#pragma once

#include <carenav/common/robot.h>
#include <carenav/navigation/local_map.h>
#include <carenav/navigation/local_planner.h>
#include <carenav/navigation/moving_tracker.h>
#include <carenav/navigation/navigation_params.h>
#include <carenav/navigation/recovery.h>
#include <carenav/navigation/safety.h>

#include <mrpt/obs/CObservation.h>

#include <memory>
#include <optional>
#include <vector>

namespace carenav::navigation {

/** Frames: the local cost map, the obstacle memory and the robot's pose are
 *  in the odometry frame (smooth, drifts); the route and the goal are in
 *  the map frame and are brought into the odometry frame with the latest
 *  localisation (setMapPose). Without localisation the two frames are the
 *  same (a walker needs no map). */
class Navigator {
 public:
  Navigator(const NavigationParams& p, const RobotParams& robot);

  /** Odometry: the robot's pose in the odometry frame and its measured velocity. */
  void setOdometry(const TPose2D& odom_pose, const Twist& measured, double t);
  /** Where localisation puts the robot in the map frame, now. */
  void setMapPose(const TPose2D& map_pose);
  /** The user's command (walker). */
  void setUserIntent(const Twist& user, double t);
  /** Adds a sensor observation taken at time t when the robot was at
   *  `odom_pose`: 2D range scans (CObservation2DRangeScan) and range
   *  arrays (CObservationRange) become obstacles with ray clearing; other
   *  kinds are ignored (returns false). */
  bool addObservation(const mrpt::obs::CObservation& obs, const TPose2D& odom_pose, double t);
  /** Obstacle points in the odometry frame seen at time t (e.g. from the
   *  perception module's local grid); counts as fresh sensor data. */
  void addObstaclePoints(const std::vector<TPoint2D>& points, double t);
  /** The obstacles of a perception grid (odometry frame) seen at time t,
   *  replacing the previous set: the grid keeps its own memory (log-odds
   *  fusion), so these are not aged by the obstacle memory. Counts as fresh
   *  sensor data. */
  void setPerceivedObstacles(std::vector<TPoint2D> points, double t);
  /** One depth frame's own evidence (odometry frame): the cells where it
   *  saw floor and the cells where it saw an obstacle. Feeds the
   *  moving-obstacle detection (a person walking onto floor seen a moment
   *  before), as a lidar's rays do; no-op without prediction. */
  void addPerceivedFrame(const std::vector<TPoint2D>& free_cells,
                         const std::vector<TPoint2D>& hit_cells, double t);

  /** Localisation asks the robot to turn in place to relocalise (HOBBIT,
   *  [Puente14, App. Fig. 8]; localization::Localizer::needsRotateInPlace). While set, a
   *  goal robot's cycle turns on the spot, towards the side where the
   *  footprint can turn freely, instead of following the route; a walker
   *  (its user drives) ignores it. */
  void setRotateRequest(bool on) { rotate_request_ = on; }
  bool rotateRequested() const { return rotate_request_; }

  /** The recovery behaviours of a goal robot ([nav.recovery], its maneuvers
   *  [nav.maneuver]; defaults
   *  otherwise). A walker's user drives: no recovery. */
  void setRecoveryParams(const RecoveryParams& p, const ManeuverParams& mp = {});
  const Recovery& recovery() const { return recovery_; }

  /** Goal navigation: a route (map frame) ending at the goal. */
  void setRoute(const std::vector<TPoint2D>& waypoints, const TPose2D& goal);
  void clearRoute();
  bool hasRoute() const { return !route_.empty(); }

  /** One control cycle at time `now`. */
  struct Cycle {
    PlannerOutput plan;
    SafetyDecision decision;
    double clearance = 0;       ///< m, footprint clearance now (capped at 2 m)
    bool goal_reached = false;  ///< within the goal tolerances and stopped by the planner
    size_t obstacles = 0;       ///< remembered obstacle cells
    std::string recovery;       ///< the recovery under way ("back out", "turn", "wait"), or ""
    bool gave_up = false;       ///< the recoveries did not help: the robot stops for good
    bool replan = false;        ///< a recovery ended: plan the route again now
    /** Map frame: where the recovery that ended began. */
    std::optional<TPoint2D> stuck_at;
  };
  Cycle cycle(double now);

  /** The walker's intent fidelity term of one cycle ([Conceicao16, Sec. 6.1]):
   *  |cmd - user| in (m/s, rad/s) when the user's own command (within the
   *  robot's limits, above the deadband) is free of collisions over the
   *  horizon on the current cost map; nullopt otherwise (then deviating is
   *  the point). */
  std::optional<double> intentDeviation(const Twist& user, const Twist& cmd) const;

  const LocalCostmap& costmap() const { return map_; }
  const LocalPlanner& planner() const { return *planner_; }
  const ObstacleMemory& memory() const { return memory_; }
  const std::vector<TPoint2D>& perceived() const { return perceived_; }
  /** The obstacle cells taken as moving in the last cycle (odometry frame). */
  const std::vector<TPoint2D>& moving() const { return moving_; }
  /** Where the tracked moving obstacles go within predict_horizon (odometry frame). */
  const std::vector<TPoint2D>& predicted() const { return predicted_; }
  const MovingTracker& tracker() const { return tracker_; }
  TPose2D odomPose() const { return odom_; }
  /** Pose of the robot in the map frame (odometry pose corrected by the latest localisation). */
  TPose2D mapPose() const;
  /** The remembered obstacles in the map frame (for replanning the route around them). */
  std::vector<TPoint2D> obstaclesInMap() const;

 private:
  PlannerOutput turnInPlace(const PlannerInput& in) const;
  /** The robot's dynamics this cycle: measured velocity, last command,
   *  command_latency and the control period. */
  MotionState motionState() const;
  /** The robot's pose (odometry frame) at the cycle's time `now`: the
   *  latest odometry is read at its own time stamp, up to a control period
   *  earlier (the sensors' last frame), and the robot kept moving at its
   *  measured velocity meanwhile (0.2 m in 0.1 s at 2 m/s). At most
   *  odom_timeout seconds ahead (older odometry: the supervisor stops).
   *  A goal robot's cycle (planner, recoveries, supervisor, which judges
   *  its commands from the robot's dynamics) starts from it; a walker's
   *  user-intent-dwa, which takes a command at once, from the odometry. */
  TPose2D poseAt(double now) const;
  TPoint2D mapToOdom(const TPoint2D& p) const;
  TPose2D mapToOdom(const TPose2D& p) const;

  NavigationParams p_;
  RobotParams robot_;
  std::unique_ptr<LocalPlanner> planner_;
  SafetySupervisor supervisor_;
  Footprint footprint_;
  LocalCostmap map_;
  ObstacleMemory memory_;
  FreeSpaceHistory free_history_;
  std::vector<TPoint2D> moving_;
  std::vector<TPoint2D> predicted_;
  MovingTracker tracker_;
  std::vector<TPoint2D> fresh_hits_;        // lidar hits since the last cycle (odometry frame)
  std::vector<TPoint2D> fresh_depth_hits_;  // depth frames' obstacle cells since the last cycle
  TPose2D odom_;
  TPose2D cycle_pose_;  // poseAt() of the last cycle
  Twist measured_;
  std::optional<double> odom_t_, scan_t_, intent_t_;
  std::optional<Twist> user_;
  // map -> odometry: odom = T (*) map, from the latest setMapPose
  TPose2D map_to_odom_{0, 0, 0};
  std::vector<TPoint2D> perceived_;
  std::vector<TPoint2D> route_;
  std::optional<TPose2D> goal_;
  bool rotate_request_ = false;
  Recovery recovery_;
  bool blocked_ = false;  // the last cycle held the robot (no plan, or stopped)
  Twist last_cmd_;        // the command of the last cycle (still driving for the latency)
  std::optional<double> last_cycle_;  // s, time of the last cycle (the control period)
  double period_ = 0;                 // s, between the last two cycles
};

}  // namespace carenav::navigation
