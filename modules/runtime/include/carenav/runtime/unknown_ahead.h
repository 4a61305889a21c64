// Unknown floor ahead: the cells of the perception grid that no frame has
// seen free (a shadow behind a drop or a box, floor outside the camera's
// view) and that lie ahead of the robot within its braking distance are not
// traversable. The navigation session adds them to the perception grid's
// obstacles (docs/navigate.md, 'Unknown floor ahead').
#pragma once

#include <carenav/common/robot.h>

#include <mrpt/math/TPoint2D.h>
#include <mrpt/math/TPose2D.h>

#include <cstdint>
#include <unordered_set>
#include <vector>

namespace carenav::perception {
class LocalOccupancy;
}

namespace carenav::navigation {

/** What the braking distance and "seen free" are made of (from the profile). */
struct UnknownAheadParams {
  double command_latency = 0.05;  ///< s, between a command and its effect ([robot] command_latency)
  double control_period = 0.1;    ///< s, one control cycle (the next chance to brake)
  double frame_period = 0.1;      ///< s, between depth frames (the zone's age at most)
  double margin = 0.25;           ///< m, kept before the zone: the robot's safe_distance
  double seen_free_below = 0.45;  ///< occupancy p below this: seen free ([perception])
  double occupied_above = 0.6;    ///< p above this: already an obstacle for navigation
};

/** Distance covered from speed v (m/s) until stopped: v times the reaction
 *  time, then braking at `acc` (m/s^2): v t + v^2 / (2 acc). */
double brakingDistance(double v, double acc, double reaction_time);

class UnknownAhead {
 public:
  UnknownAhead(const RobotParams& robot, const UnknownAheadParams& p, double resolution);
  /** The footprint at `pose` (odometry frame) covers floor: known free for
   *  good (the start pose, and every pose the robot drove through). The
   *  first call is the start: the zone at full speed ahead of the footprint
   *  (reach(v_max)) is known free too, the floor the robot was started
   *  facing (docs/navigate.md, 'Unknown floor ahead'). */
  void stoodOn(const mrpt::math::TPose2D& pose);
  /** How far beyond the footprint's front (back when reversing) the zone
   *  reaches at speed v: safe_distance plus the braking distance. */
  double reach(double v) const;
  /** Centres (odometry frame) of the grid cells in the zone ahead of the
   *  robot at `pose` moving at v (forward when v >= 0) that are neither seen
   *  free nor already obstacles nor stood on. */
  std::vector<mrpt::math::TPoint2D> cells(const perception::LocalOccupancy& grid,
                                          const mrpt::math::TPose2D& pose, double v) const;
  size_t stoodCells() const { return stood_.size(); }

 private:
  static int64_t key(long i, long j) { return (static_cast<int64_t>(i) << 32) ^ (j & 0xffffffff); }
  bool inFootprint(double x, double y) const;
  void startStrip(const mrpt::math::TPose2D& pose);
  /** f(i, j, x, y) for the grid cells (i, j) within the square of half-side
   *  r around `pose`, with (x, y) their centres in the robot's frame. */
  template <class F>
  void forCellsAround(const mrpt::math::TPose2D& pose, double r, F&& f) const;

  RobotParams robot_;
  UnknownAheadParams p_;
  double res_;
  double front_ = 0, back_ = 0, half_width_ = 0;
  std::unordered_set<int64_t> stood_;
};

}  // namespace carenav::navigation
