// The robot bridge: `carenav navigate --bridge HOST:PORT` drives a real
// robot through a line-based TCP protocol (docs/navigate.md, "Robot
// bridge"). The robot side (a small program on the robot, or a ROS node)
// listens; carenav connects, reads odometry, scans and the user's command,
// and answers every control cycle with a velocity command.
//
// Robot -> carenav, one message per line, numbers in SI units:
//   odom T X Y YAW V W         pose in the odometry frame (m, rad) and the
//                              measured velocity (m/s, rad/s) at robot time T (s)
//   scan T LABEL N R1 .. RN    ranges of the profile's [sensor.LABEL]: a
//                              lidar2d's N beams or a range-array's N
//                              segments, spread evenly over its fov, right
//                              to left; 0, nan, inf or beyond range_max:
//                              no return
//   intent T V W               the user's command (a walker's handle)
//   bye                        end of the session
//   (empty lines and lines starting with '#' are ignored)
// carenav -> robot:
//   hello carenav 1 PROFILE PLUGIN   once, on connecting
//   cmd T V W                  every control cycle; T is the newest robot
//                              time carenav has seen
//   stop REASON                once, when carenav ends (after a last "cmd T 0 0")
// The robot must stop by itself when no "cmd" arrives for a few cycles.
#pragma once

#include <carenav/common/robot.h>
#include <carenav/navigation/local_planner.h>
#include <carenav/runtime/intent.h>
#include <carenav/runtime/live_run.h>
#include <carenav/runtime/scenario.h>

#include <mrpt/obs/CObservation.h>

#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace carenav::navigation {

struct BridgeMessage {
  enum class Kind { Odom, Scan, Intent, Bye } kind = Kind::Bye;
  double t = 0;
  TPose2D pose;               ///< odom
  Twist vel;                  ///< odom: measured; intent: the user's
  std::string label;          ///< scan
  std::vector<float> ranges;  ///< scan
};

/** Plausibility bounds of the numbers a robot sends (docs/navigate.md):
 *  anything beyond is refused as a malformed line. Coordinates as the
 *  simulator's worlds (100 km); yaw may be unwrapped (a million radians);
 *  robot time may be Unix time (1e12 s is year 33658). */
constexpr double kBridgeMaxCoordinate = 1e5;  ///< m, |x|, |y| of odom
constexpr double kBridgeMaxYaw = 1e6;         ///< rad
constexpr double kBridgeMaxSpeed = 1e3;       ///< m/s or rad/s, odom and intent
constexpr double kBridgeMaxTime = 1e12;       ///< s, |T|

/** Parses one robot -> carenav line; nullopt for empty and comment lines.
 *  Throws std::invalid_argument saying what is wrong. */
std::optional<BridgeMessage> parseBridgeLine(const std::string& line);
/** "cmd T V W". */
std::string formatCommand(double t, const Twist& c);
/** A scan of more than `n` ranges reduced to `n`: each output range the
 *  nearest valid range of its share of the input (0, no return, when it has
 *  none), so no obstacle is lost and the work per scan is bounded by the
 *  profile's beam count. Fewer ranges come back unchanged. */
std::vector<float> reduceRanges(const std::vector<float>& ranges, size_t n,
                                const std::function<bool(float)>& valid);

/** A `scan` message as the observation of its sensor `s` (a lidar2d or a
 *  range-array of the profile); more ranges than the sensor's beams or
 *  segments are reduced (reduceRanges: each kept bin its nearest return). */
mrpt::obs::CObservation::Ptr bridgeObservation(const BridgeMessage& scan, const SensorParams& s);

/** With LiveRunOptions (profile, sets, plugin, start, control_rate, out_dir,
 *  stop, progress); `duration` 0: until "bye", the source ends or `stop`. */
struct BridgeOptions : LiveRunOptions {
  std::string address;  ///< HOST:PORT of the robot's bridge
  /** Goal navigation: the static map, the start pose on it (`start`) and
   *  the goal ("x,y,deg" or a place of MAP's places file). */
  std::string map;
  std::string goal;
  /** The walker's user; without it, the bridge's "intent" lines. */
  std::shared_ptr<IntentSource> intent;
  double connect_timeout = 10;
  /** s; a robot that sends no line for this long (connected, but silent)
   *  ends the run: `cmd T 0 0`, `stop error`, exit 2. Scans older than
   *  sensor_timeout already stop it before. */
  double silence_timeout = 5;
};

/** Runs the navigation loop against the bridge in real time. Returns the
 *  run's metrics (clearance from the robot's own sensors; collisions are
 *  not known). Throws InputError for a bad profile, map or goal, a robot
 *  that cannot be reached, a malformed message (after commanding a stop
 *  and writing the outputs) or a connection lost without "bye". */
RunMetrics runBridge(const BridgeOptions& o);

}  // namespace carenav::navigation
