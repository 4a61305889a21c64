// The robot and its sensors as a profile describes them ([robot], [sensor.*]).
#pragma once

#include <carenav/common/params.h>

#include <string>
#include <vector>

namespace carenav {

class Profile;

/** [profile]: identification and layering.
 *  ```ini
 *  [profile]
 *  name = isr-aiwalker
 *  base = defaults.ini   ; read first, relative to this file
 *  ```
 */
struct ProfileInfo {
  std::string name;         ///< short robot name
  std::string description;  ///< one line for humans
  std::string base;         ///< INI read first, path relative to this file
  static const ParamTable<ProfileInfo>& table();
};

/** [robot]: body and motion limits. Frame: x forward, y left, z up, origin
 *  at the centre of the wheel axle on the floor. */
struct RobotParams {
  std::string kinematics = "diff-drive";  ///< only differential drive for now
  std::string control = "autonomous";     ///< "user-intent" for a walker pushed by its user
  /** Footprint polygon in the robot frame (m), "x1,y1 x2,y2 ...". */
  std::vector<Point2> footprint = {{0.25, 0.25}, {-0.25, 0.25}, {-0.25, -0.25}, {0.25, -0.25}};
  double height = 1.0;          ///< m, top of the robot (overhang checks)
  double v_max = 0.3;           ///< m/s, top forward speed
  double v_min = 0.0;           ///< m/s, top reverse speed (negative or 0)
  double w_max = 0.75;          ///< rad/s, top turn rate
  double acc_v = 0.5;           ///< m/s^2, linear acceleration (and braking) limit
  double acc_w = 1.0;           ///< rad/s^2, angular acceleration limit
  double safe_distance = 0.25;  ///< m, distance to keep in front of the footprint
  /** s, between a velocity command and its effect on the base (the
   *  simulator's [sim] latency is 0.05 s by default): rollouts and the
   *  braking rule start from the measured velocity and the last command
   *  (navigation::MotionState). */
  double command_latency = 0.05;
  static const ParamTable<RobotParams>& table();
  /** Radius of the smallest circle about the origin holding the footprint. */
  double circumscribedRadius() const;
};

/** [sensor.<label>]: one sensor on the robot. <label> is the sensorLabel its
 *  observations carry in rawlogs. Keys allowed depend on `type`. */
struct SensorParams {
  std::string label;             ///< from the section name, not a key
  std::string type = "lidar2d";  ///< lidar2d | depth-camera | range-array | bumper
  std::string model;             ///< product name, for humans
  // Pose on the robot (robot frame; angles in degrees as MRPT's CPose3D text).
  double x = 0, y = 0, z = 0;
  double yaw = 0, pitch = 0, roll = 0;
  double rate_hz = 10;        ///< Hz, frame or scan rate
  double range_min = 0.1;     ///< m
  double range_max = 10;      ///< m
  double noise_std = 0.01;    ///< m, range noise (1 sigma; at 1 m for depth cameras)
  double fov = 180;           ///< deg, horizontal field of view
  double vfov = 0;            ///< deg, vertical field of view (depth cameras)
  int beams = 181;            ///< lidar2d: rays per scan
  int segments = 16;          ///< range-array: number of segments
  int width = 0, height = 0;  ///< depth-camera: image size (px)
  static const ParamTable<SensorParams>& tableFor(const std::string& type);
  /** Common keys only (type, model, pose, rate); what every sensor type has. */
  static const ParamTable<SensorParams>& table();
  static const std::vector<std::string>& types();
};

/** Reads every [sensor.*] section. Throws InputError on a bad one. */
std::vector<SensorParams> loadSensors(const Profile& profile);

/** Registers [profile], [robot] and the [sensor.*] variants (called once by
 *  ProfileSchemas' constructor). */
void registerCommonSections();

}  // namespace carenav
