// Who drives the simulated robot: a waypoint follower (`--path`) or a
// timed command script (`--script`).
#pragma once

#include <carenav/common/robot.h>
#include <carenav/sim/simulator.h>

#include <string>
#include <vector>

namespace carenav::sim {

/** "x,y x,y ..." (at least one point). Throws InputError naming `what`. */
std::vector<Vec2> parsePath(const std::string& text, const std::string& what = "--path");
/** "x,y,deg". Throws InputError naming `what`. */
Pose2 parseStart(const std::string& text, const std::string& what = "--start");

/** Follows waypoints on the ground-truth pose: turns on the spot when the
 *  heading error exceeds 60 deg, otherwise drives at up to v_max slowed by
 *  the heading error, and brakes under acc_v before the last waypoint
 *  (v <= sqrt(2 acc_v d)). A waypoint is reached within `tolerance` m
 *  (the last one within tolerance / 2). */
class WaypointFollower {
 public:
  WaypointFollower(std::vector<Vec2> path, const RobotParams& robot, double tolerance = 0.2);
  /** Command for the pose; (0, 0) once the last waypoint is reached. */
  void command(const Pose2& pose, double& v, double& w);
  bool done() const { return next_ >= path_.size(); }
  size_t reached() const { return next_; }

 private:
  std::vector<Vec2> path_;
  RobotParams robot_;
  double tol_;
  size_t next_ = 0;
};

/** Timed commands: rows "t v w" (s, m/s, rad/s), each held until the next
 *  row's time; t must not decrease. */
/** Latest time a command script or a simulation may reach: one day of
 *  simulated driving (a rawlog of a day is already gigabytes). */
inline constexpr double kMaxSimSeconds = 86400;

struct CommandScript {
  struct Row {
    double t, v, w;
  };
  std::vector<Row> rows;
  /** The command in effect at time t ((0, 0) before the first row). */
  void at(double t, double& v, double& w) const;
  double endTime() const { return rows.empty() ? 0 : rows.back().t; }
};

/** Reads a script file ('#' comments, blank lines skipped). Throws
 *  InputError naming the file and line: missing, empty, a row without three
 *  numbers, a time that goes back. */
CommandScript readCommandScript(const std::string& path);

}  // namespace carenav::sim
