#include <carenav/common/profile.h>
#include <carenav/sim/sim_params.h>

namespace carenav::sim {

const ParamTable<SimParams>& SimParams::table() {
  using P = SimParams;
  static const auto t =
      ParamTable<P>()
          .real("odom_scale_d", &P::odom_scale_d, "", -0.5, 0.5,
                "odometry: systematic relative error of the distance (0.01: reads 1 % more)")
          .real("odom_scale_w", &P::odom_scale_w, "", -0.5, 0.5,
                "odometry: systematic relative error of the turn")
          .real("odom_bias_w", &P::odom_bias_w, "deg/m", -90, 90,
                "odometry: systematic heading drift per metre travelled")
          .real("odom_std_d", &P::odom_std_d, "m", 0, 1,
                "odometry: random distance error (std) after 1 m; variance grows with distance")
          .real("odom_std_w", &P::odom_std_w, "deg", 0, 90,
                "odometry: random heading error (std) after 1 rad turned")
          .real("odom_std_wd", &P::odom_std_wd, "deg", 0, 90,
                "odometry: random heading error (std) after 1 m travelled")
          .real("latency", &P::latency, "s", 0, 5, "delay between a command and its effect")
          .real("physics_dt", &P::physics_dt, "s", 0.0005, 0.1, "integration step")
          .integer("seed", &P::seed, "", 0, 2147483647,
                   "seed of every random draw (odometry and sensor noise)")
          .choice("lidar_max_range", &P::lidar_max_range, {"invalid", "max"},
                  "lidar beams with no hit within range_max: 'invalid' (range_max, marked "
                  "invalid) or 'max' (range_max, marked valid)")
          .real("depth_invalid_rate", &P::depth_invalid_rate, "", 0, 1,
                "depth cameras: share of pixels dropped (0) at random")
          .integer("depth_decimation", &P::depth_decimation, "", 1, 64,
                   "depth cameras: image of width/d x height/d pixels (intrinsics scaled)")
          .real("wall_height", &P::wall_height, "m", 0.1, 100,
                "height of the map's occupied cells (a world file's wall_height wins)")
          .real("bumper_step", &P::bumper_step, "m", 0, 1,
                "floor raised more than this (steps, legs, walls) stops the robot: a bumper "
                "contact");
  return t;
}

void registerProfileSections() {
  ProfileSchemas::instance().add(
      SectionSchema::of(SimParams::table(), "sim",
                        "simulator only: odometry noise, command latency, seed, sensor artefacts"));
}

}  // namespace carenav::sim
