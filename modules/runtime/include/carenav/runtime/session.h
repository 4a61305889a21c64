// A navigation session: everything one run of the robot needs (the
// Navigator, the localiser fed from a lidar, depth frames through the
// perception pipeline, the route to a goal or a patrol's goals and its
// replanning, the navigation log, the run's metrics and its picture),
// whatever the robot is. An adapter feeds it the robot's sensor data and
// time and takes its commands: the simulator (scenario_run.cpp), the TCP
// bridge (bridge_run.cpp), later a ROS node. docs/design.md.
#pragma once

#include <carenav/common/profile.h>
#include <carenav/common/robot.h>
#include <carenav/common/run_health.h>
#include <carenav/io/map_render.h>
#include <carenav/navigation/global_planner.h>
#include <carenav/navigation/navigator.h>
#include <carenav/runtime/intent.h>
#include <carenav/runtime/scenario.h>
#include <carenav/runtime/unknown_ahead.h>

#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/obs/CObservation.h>

#include <chrono>
#include <fstream>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace carenav::localization {
class Localizer;
}
namespace carenav::perception {
class Pipeline;
}

namespace carenav::navigation {

/** What a session is built from: the robot profile's sections and the run. */
struct SessionSetup {
  std::string name;    ///< the run's name: the scenario's, or "bridge"
  std::string origin;  ///< what errors about goals and routes name (the scenario, the map)
  RobotParams robot;
  NavigationParams nav;  ///< with the plugin chosen for the run
  std::vector<SensorParams> sensors;
  Profile profile;  ///< [nav.recovery], [localization], [perception] are read from it
  /** Static map for routes and localisation (owned by the adapter; null: none). */
  const mrpt::maps::COccupancyGridMap2D* map = nullptr;
  /** Localise on `map` from the first lidar2d, starting at `start`. */
  bool localise = false;
  std::optional<TPose2D> start;
  double control_rate = 10;  ///< Hz
  std::string out_dir;       ///< navlog.csv, run.png, summary.json; empty: none
  bool progress = false;     ///< a status line on a terminal
  int progress_every = 20;   ///< cycles between updates of the status line
  double duration = std::numeric_limits<double>::infinity();  ///< s, for the status line
  /** The first collision the truth reports ends the run (unless this). */
  bool continue_after_collision = false;
};

/** Reads a session's setup from a profile (--set overrides applied, the
 *  mrpt-ptg plugin configured); `plugin` overrides the profile's if set. */
SessionSetup sessionSetup(const std::string& profile_path, const std::vector<std::string>& sets,
                          const std::string& plugin);

/** What only a simulator knows about a cycle: where the robot truly is.
 *  Metrics then come from it; without it, from the robot's own estimate. */
struct Truth {
  TPose2D pose;
  double clearance = 0;    ///< m, true footprint to the nearest obstacle
  bool collided = false;   ///< in contact now
  size_t collisions = 0;   ///< so far
  bool forbidden = false;  ///< the centre is in a forbidden region now
  bool off_map = false;    ///< the centre is off the world's map now
};

/** A goal with the name it was given by (room/place; empty for a pose). */
struct SessionGoal {
  TPose2D pose;
  std::string label;
};

/** Why the session ended the run in a cycle. */
enum class SessionEnd { None, GoalReached, Collision, GaveUp };

class NavigationSession {
 public:
  explicit NavigationSession(SessionSetup setup);
  ~NavigationSession();

  Navigator& navigator() { return nav_; }
  bool walker() const { return walker_; }
  const SessionSetup& setup() const { return s_; }

  // -- goals ---------------------------------------------------------------
  /** A goal (one entry) or a patrol (several, visited in turn, each leg
   *  ended by `leg_timeout` s); plans the route from `from`. False when
   *  there is no route (the replanner keeps trying). */
  bool setGoals(std::vector<SessionGoal> goals, bool patrol, double leg_timeout,
                const TPoint2D& from);
  bool goalMode() const { return goal_.has_value(); }
  const std::optional<TPose2D>& goal() const { return goal_; }
  bool hasRoute() const { return route_.has_value(); }
  /** The route as the local planner follows it: from where it was planned. */
  std::vector<TPoint2D> routePoints() const;
  /** A walker guided along the route (its user walks it): whether `truth`
   *  has arrived; a patrol then takes its next leg, else the run ends. Also
   *  moves a patrol on when the leg timed out. */
  bool walkerArrived(const TPose2D& truth, double t);

  // -- sensor data and the user --------------------------------------------
  void odometry(const TPose2D& odo, const Twist& measured, double t);
  /** A 2D scan or range array (obstacles, and localisation from its lidar),
   *  or a depth frame (perception); odometry is the pose it was taken at. */
  void observation(const mrpt::obs::CObservation::Ptr& obs, const TPose2D& odo, double t);
  /** The user's command, sampled at `sample_t`; taken as the user's now
   *  (fidelity, the log) while not older than intent_timeout. */
  void userIntent(const Twist& cmd, double sample_t, double now);
  /** A point of the user's intended path (the picture). */
  void userPathPoint(const TPoint2D& p);
  /** The robot's own clock (the log's robot_t), where it sends one. */
  void robotTime(double t) { robot_t_ = t; }

  // -- the control cycle ---------------------------------------------------
  /** Marks the start of the robot's work of this period (sensor data). */
  void beginWork() { work0_ = threadCpuMs(); }
  struct Step {
    Navigator::Cycle cycle;
    SessionEnd end = SessionEnd::None;
  };
  /** One control cycle at time t: the command is step.cycle.decision.cmd. */
  Step cycle(double t, const std::optional<Truth>& truth = std::nullopt);

  // -- the end -------------------------------------------------------------
  /** The metrics so far (the adapter completes duration, path length,
   *  outcome and success). */
  RunMetrics& metrics() { return m_; }
  /** How and when the session ended the run (None: the adapter did). */
  SessionEnd ended() const { return end_; }
  double endTime() const { return end_t_; }
  /** The planner's last note when the recoveries gave up. */
  const std::string& gaveUpNote() const { return gave_up_note_; }
  /** Fills the run's statistics into metrics() (call once, at the end). */
  void finishMetrics();
  /** The run's picture, navlog and summary.json into out_dir (if set):
   *  `title` begins the picture's title; `extra` overlays (e.g. forbidden
   *  regions) drawn under the robot's path. */
  void writeOutputs(const std::string& title, std::vector<io::Overlay> extra = {});

 private:
  void openLog();
  void endRun(SessionEnd why, double t);
  std::vector<io::Overlay> overlays(std::vector<io::Overlay> extra) const;
  void nextLeg(bool reported, const TPoint2D& where, double now);
  void planRoute(const TPoint2D& from);
  /** Replans when due, or at once when a recovery ended (begun at `stuck_at`). */
  void replan(size_t k, bool recovery_ended, const std::optional<TPoint2D>& stuck_at);
  void depthFrame(const mrpt::obs::CObservation& obs, const TPose2D& odo, double t);
  void scan2d(const mrpt::obs::CObservation::Ptr& obs, const TPose2D& odo, double t);
  void record(double t, const Navigator::Cycle& c, const std::optional<Truth>& truth, double ms);
  void logRow(double t, const Navigator::Cycle& c, const std::optional<Truth>& truth, double cl);
  void statusLine(double t, const Navigator::Cycle& c, const std::optional<Truth>& truth,
                  double cl);
  void sampleHealth(size_t k);
  std::optional<SessionEnd> goalCheck(double t, const Navigator::Cycle& c,
                                      const std::optional<Truth>& truth);

  SessionSetup s_;
  Navigator nav_;
  bool walker_ = false;
  // goals and the route
  std::vector<SessionGoal> goals_;
  bool patrol_ = false;
  double leg_timeout_ = 300, leg_t0_ = 0;
  size_t leg_ = 0;
  std::optional<TPose2D> goal_;
  std::optional<Route> route_;
  TPoint2D route_start_, route_origin_;
  SessionEnd end_ = SessionEnd::None;
  double end_t_ = 0;
  std::string gave_up_note_;
  Footprint fp_;
  std::unique_ptr<GlobalPlanner> gp_;
  RouteReplanner replanner_;
  // sensors
  std::unique_ptr<localization::Localizer> loc_;
  std::string loc_sensor_;
  mrpt::poses::CPose2D last_loc_odo_;
  bool loc_started_ = false, have_odom_ = false;
  bool dead_reckoning_ = false;  ///< the last localiser scan had too few returns to weigh
  TPose2D odom_;
  std::optional<double> robot_t_;
  std::unique_ptr<perception::Pipeline> perceive_;
  std::string perception_sensor_;
  double perceive_ms_ = 0;
  std::unique_ptr<UnknownAhead> unknown_;  ///< unknown floor ahead (with a depth camera)
  double measured_v_ = 0;                  ///< m/s, the odometry's forward speed
  // the user
  std::optional<Twist> user_;
  // metrics and outputs
  RunMetrics m_;
  std::vector<TPoint2D> path_, user_path_;
  double clear_sum_ = 0, fid_sum_ = 0, cycle_ms_sum_ = 0, work0_ = 0, work_ms_ = 0;
  size_t fid_n_ = 0, clear_n_ = 0, k_ = 0;
  std::string last_recovery_;
  DurationHistogram work_all_, work_window_;
  std::ofstream log_;
  bool tty_ = false;
  std::chrono::steady_clock::time_point wall0_;
};

/** A path kept for the picture: beyond kMaxPathPoints every second point is
 *  dropped, so a run of any length holds a bounded number of them. */
constexpr size_t kMaxPathPoints = 20000;
void appendBounded(std::vector<TPoint2D>& path, const TPoint2D& p);

}  // namespace carenav::navigation
