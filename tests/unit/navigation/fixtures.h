// Shared fixtures of the navigation unit tests.
#pragma once

#include <carenav/common/robot.h>

#include <cmath>
#include <vector>

namespace carenav::navigation::test {

/** The ISR-AIWALKER-like walker of [Rosa17] (Table 5.1 limits): 0.70 x
 *  0.65 m, axle 0.25 m behind the front. */
inline RobotParams walkerRobot() {
  RobotParams r;
  r.footprint = {{0.25, 0.325}, {-0.45, 0.325}, {-0.45, -0.325}, {0.25, -0.325}};
  r.v_max = 0.3;
  r.v_min = -0.15;
  r.w_max = 0.75;
  r.acc_v = 0.5;
  r.acc_w = 1.0;
  r.safe_distance = 0.325;
  return r;
}

/** The clutter benchmark's robot: 0.51 x 0.43 m, 2 m/s, 4 rad/s, reverses. */
inline RobotParams fastRobot() {
  RobotParams r;
  r.footprint = {{0.255, 0.215}, {-0.255, 0.215}, {-0.255, -0.215}, {0.255, -0.215}};
  r.v_max = 2.0;
  r.v_min = -0.5;
  r.w_max = 4.0;
  r.acc_v = 2.0;
  r.acc_w = 4.0;
  r.safe_distance = 0.1;
  return r;
}

/** fastRobot() at the walker's limits (vmax 0.5: 1.57 rad/s) or its own
 *  (vmax above 1 m/s: 4 rad/s). */
inline RobotParams fastRobotAt(double vmax) {
  RobotParams r = fastRobot();
  r.v_max = vmax;
  r.w_max = vmax > 1 ? 4.0 : 1.57;
  return r;
}

/** Points every 1 cm around a post of radius `r` at (x, y). */
inline void post(std::vector<TPoint2D>& out, double x, double y, double r) {
  for (int k = 0; k < 48; ++k)
    out.push_back({x + r * std::cos(k * M_PI / 24), y + r * std::sin(k * M_PI / 24)});
}

/** A gap between two posts on the line x = gx, `width` m between their
 *  surfaces, in a row of touching posts 1.1 m to either side of y = 0. */
struct GapScene {
  double gx = 0.6, width = 0.55, radius = 0.075;
  std::vector<TPoint2D> obs;
  explicit GapScene(double w) : width(w) {
    const double c = width / 2 + radius;
    for (int k = 0; k < 6; ++k) {
      post(obs, gx, c + k * 2 * radius, radius);
      post(obs, gx, -c - k * 2 * radius, radius);
    }
  }
};

}  // namespace carenav::navigation::test
