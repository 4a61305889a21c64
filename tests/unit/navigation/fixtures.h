// Shared fixtures of the navigation unit tests.
#pragma once

#include <carenav/common/robot.h>

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

}  // namespace carenav::navigation::test
