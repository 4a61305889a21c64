// The simulator: a differential-drive robot in a World, its odometry and its
// profile's sensors, stepped in-process faster than real time and
// deterministic under a seed.
#pragma once

#include <carenav/common/robot.h>
#include <carenav/sim/raycast.h>
#include <carenav/sim/sim_params.h>
#include <carenav/sim/world.h>

#include <mrpt/core/Clock.h>
#include <mrpt/obs/CObservation.h>

#include <deque>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace carenav::sim {

struct Pose2 {
  double x = 0, y = 0, yaw = 0;  ///< m, m, rad
};

/** What one instant of the simulation produced: the odometry reading (a
 *  CObservationOdometry, first) and every sensor whose frame was due, all
 *  stamped with the same time. */
struct SimFrame {
  double t = 0;  ///< simulated seconds since the start
  Pose2 truth;   ///< ground-truth pose at t
  Pose2 odometry;
  std::vector<mrpt::obs::CObservation::Ptr> observations;
};

/** Simulated clock epoch: t = 0 is this UNIX time, so outputs are
 *  deterministic (2023-11-14 22:13:20 UTC). */
constexpr double kSimEpoch = 1700000000.0;
mrpt::Clock::time_point simStamp(double t);

class Simulator {
 public:
  /** Sensors of type lidar2d, range-array and depth-camera are simulated;
   *  bumper sections add nothing (collided() is the bumper). The seed is
   *  SimParams::seed. */
  Simulator(std::shared_ptr<const World> world, RobotParams robot,
            std::vector<SensorParams> sensors, SimParams params);

  /** Places the robot (truth and odometry restart there); velocities 0. */
  void reset(const Pose2& start);
  /** True when the footprint at `p` touches a wall, a raised cell or a person at time t. */
  bool footprintBlocked(const Pose2& p, double t) const;

  /** Command (m/s, rad/s), clamped to the robot's limits; takes effect
   *  `latency` seconds later, reached under the acceleration limits. */
  void setCommand(double v, double w);
  /** Advances the simulated time by dt and returns the frames that fell due
   *  (sensor times are k / rate_hz from the start), in time order. */
  std::vector<SimFrame> step(double dt);

  double time() const { return t_; }
  Pose2 groundTruth() const { return truth_; }
  Pose2 odometry() const { return odo_; }
  double v() const { return v_; }
  double w() const { return w_; }
  /** The bumper: a motion step was blocked by an obstacle (a wall, a raised
   *  cell, a person) and the robot has not yet moved 5 cm clear since. */
  bool collided() const { return collided_; }
  /** Bumper contacts so far (a contact counts once until it clears). */
  size_t collisions() const { return contacts_; }
  /** Distance travelled by the truth (m). */
  double distance() const { return distance_; }
  const std::vector<SensorParams>& sensors() const { return sensors_; }
  const World& world() const { return *world_; }

  /** One observation of sensor `i` at the current state (exposed for tests). */
  mrpt::obs::CObservation::Ptr observe(size_t i);

 private:
  void integrate(double dt);
  void applyDueCommands();
  mrpt::obs::CObservation::Ptr lidar(size_t i, const std::vector<PersonNow>& people);
  mrpt::obs::CObservation::Ptr rangeArray(size_t i, const std::vector<PersonNow>& people);
  mrpt::obs::CObservation::Ptr depth(size_t i, const std::vector<PersonNow>& people);
  mrpt::obs::CObservation::Ptr odometryObs() const;

  std::shared_ptr<const World> world_;
  RobotParams robot_;
  std::vector<SensorParams> sensors_;
  SimParams params_;
  double t_ = 0;
  Pose2 truth_, odo_;
  double v_ = 0, w_ = 0;          // actual velocities
  double v_cmd_ = 0, w_cmd_ = 0;  // command in effect
  double v_odo_ = 0, w_odo_ = 0;  // measured velocities (last step)
  struct Pending {
    double t_apply, v, w;
  };
  std::deque<Pending> pending_;
  bool collided_ = false;
  size_t contacts_ = 0;
  double clear_distance_ = 0;
  double distance_ = 0;
  std::vector<long> next_frame_;  // per sensor: index k of its next frame (t = k / rate)
  std::mt19937_64 odo_rng_;
  std::vector<std::mt19937_64> sensor_rng_;
  // depth cameras: per-pixel ray directions in the camera frame (x forward)
  std::vector<std::vector<float>> depth_dirs_;
};

}  // namespace carenav::sim
