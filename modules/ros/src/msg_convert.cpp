#include "msg_convert.h"

#include <mrpt/math/CQuaternion.h>

#include <cmath>
#include <limits>

namespace carenav::ros {

mrpt::Clock::time_point fromRosTime(const ::ros::Time& t) {
  return mrpt::Clock::fromDouble(t.toSec());
}

::ros::Time toRosTime(mrpt::Clock::time_point t) {
  return ::ros::Time(std::max(0.0, mrpt::Clock::toDouble(t)));
}

double yawOf(const geometry_msgs::Quaternion& q) {
  return std::atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z));
}

geometry_msgs::Quaternion yawQuaternion(double yaw) {
  geometry_msgs::Quaternion q;
  q.z = std::sin(yaw / 2);
  q.w = std::cos(yaw / 2);
  return q;
}

mrpt::poses::CPose3D poseOf(const geometry_msgs::Transform& t) {
  const auto& r = t.rotation;
  const mrpt::math::CQuaternionDouble q(r.w, r.x, r.y, r.z);
  return mrpt::poses::CPose3D(q, t.translation.x, t.translation.y, t.translation.z);
}

geometry_msgs::Transform transformOf(const mrpt::poses::CPose3D& p) {
  geometry_msgs::Transform t;
  t.translation.x = p.x();
  t.translation.y = p.y();
  t.translation.z = p.z();
  mrpt::math::CQuaternionDouble q;
  p.getAsQuaternion(q);
  t.rotation.w = q.r();
  t.rotation.x = q.x();
  t.rotation.y = q.y();
  t.rotation.z = q.z();
  return t;
}

mrpt::obs::CObservation2DRangeScan::Ptr scanFromRos(const sensor_msgs::LaserScan& m,
                                                    const std::string& label,
                                                    const mrpt::poses::CPose3D& sensor_pose) {
  auto o = mrpt::obs::CObservation2DRangeScan::Create();
  o->sensorLabel = label;
  o->timestamp = fromRosTime(m.header.stamp);
  const size_t n = m.ranges.size();
  const double span = n > 1 ? std::abs(m.angle_increment) * (n - 1) : 0;
  o->aperture = static_cast<float>(span);
  o->rightToLeft = m.angle_increment >= 0;
  o->maxRange = m.range_max;
  const double middle = m.angle_min + m.angle_increment * (n > 1 ? (n - 1) / 2.0 : 0);
  // (float bearings of a centred scan leave a middle of ~1e-8 rad: none)
  o->sensorPose = std::abs(middle) < 1e-6
                      ? sensor_pose
                      : sensor_pose + mrpt::poses::CPose3D(0, 0, 0, middle, 0, 0);
  o->resizeScan(n);
  for (size_t i = 0; i < n; ++i) {
    const float r = m.ranges[i];
    const bool valid = std::isfinite(r) && r >= m.range_min && r > 0 && r <= m.range_max;
    o->setScanRange(i, valid ? r : 0.0f);
    o->setScanRangeValidity(i, valid);
  }
  return o;
}

sensor_msgs::LaserScan scanToRos(const mrpt::obs::CObservation2DRangeScan& s,
                                 const std::string& frame) {
  sensor_msgs::LaserScan m;
  m.header.frame_id = frame;
  m.header.stamp = toRosTime(s.timestamp);
  const size_t n = s.getScanSize();
  const double half = s.aperture / 2.0;
  const double step = n > 1 ? s.aperture / (n - 1) : 0;
  m.angle_min = static_cast<float>(s.rightToLeft ? -half : half);
  m.angle_max = static_cast<float>(s.rightToLeft ? half : -half);
  m.angle_increment = static_cast<float>(s.rightToLeft ? step : -step);
  m.range_min = 0;
  m.range_max = s.maxRange;
  m.ranges.resize(n);
  for (size_t i = 0; i < n; ++i)
    m.ranges[i] =
        s.getScanRangeValidity(i) ? s.getScanRange(i) : std::numeric_limits<float>::infinity();
  return m;
}

std::string bareFrame(const std::string& f) { return !f.empty() && f[0] == '/' ? f.substr(1) : f; }

}  // namespace carenav::ros
