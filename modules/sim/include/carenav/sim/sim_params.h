// Parameters of the simulator that no real robot has: the profile's [sim]
// section (odometry noise, command latency, seed, sensor artefacts).
#pragma once

#include <carenav/common/params.h>

#include <string>

namespace carenav::sim {

/** [sim]: how `carenav simulate` and sim::Simulator degrade the truth.
 *  ```ini
 *  [sim]
 *  odom_scale_d = 0.01     ; odometry reads 1 % more distance than travelled
 *  odom_std_d = 0.02       ; m of random error after 1 m
 *  seed = 1
 *  ```
 *  Odometry (per integration step with true increments dd, dth):
 *    dd'  = dd (1 + odom_scale_d) + N(0, odom_std_d^2 |dd|)
 *    dth' = dth (1 + odom_scale_w) + odom_bias_w |dd|
 *           + N(0, odom_std_w^2 |dth| + odom_std_wd^2 |dd|)
 *  so the random part's variance grows linearly with the distance and the
 *  turn (a random walk), and the systematic part (scale, drift) accumulates. */
struct SimParams {
  double odom_scale_d = 0.01;               ///< systematic relative error of the distance
  double odom_scale_w = -0.01;              ///< systematic relative error of the turn
  double odom_bias_w = 0.5;                 ///< deg/m, heading drift per metre travelled
  double odom_std_d = 0.02;                 ///< m, random distance error after 1 m (std)
  double odom_std_w = 1.0;                  ///< deg, random heading error after 1 rad turned (std)
  double odom_std_wd = 0.5;                 ///< deg, random heading error after 1 m travelled (std)
  double latency = 0.05;                    ///< s, delay between setCommand and its effect
  double physics_dt = 0.01;                 ///< s, integration step
  int seed = 1;                             ///< seed of every random draw
  std::string lidar_max_range = "invalid";  ///< "invalid" or "max": readings with no hit
  double depth_invalid_rate = 0.01;         ///< share of depth pixels dropped at random
  int depth_decimation = 1;   ///< depth image is width/d x height/d (1: full resolution)
  double wall_height = 2.5;   ///< m, height of the map's occupied cells
  double bumper_step = 0.05;  ///< m, floor steps higher than this stop the robot (bumper)
  static const ParamTable<SimParams>& table();
};

/** Registers [sim] with the profile schemas. */
void registerProfileSections();

}  // namespace carenav::sim
