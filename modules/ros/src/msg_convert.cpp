#include "msg_convert.h"

#include <mrpt/math/CQuaternion.h>

#include <cmath>
#include <cstring>
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

mrpt::obs::CObservation3DRangeScan::Ptr cloudFromRos(const sensor_msgs::PointCloud2& m,
                                                     const std::string& label,
                                                     const mrpt::poses::CPose3D& sensor_pose) {
  int off[3] = {-1, -1, -1};
  for (const auto& f : m.fields)
    for (int i = 0; i < 3; ++i)
      if (f.name == std::string(1, "xyz"[i]) && f.datatype == sensor_msgs::PointField::FLOAT32)
        off[i] = static_cast<int>(f.offset);
  if (off[0] < 0 || off[1] < 0 || off[2] < 0 || m.point_step < 12) return nullptr;
  const size_t n = size_t{m.width} * m.height;
  if (m.data.size() < n * m.point_step) return nullptr;
  auto o = mrpt::obs::CObservation3DRangeScan::Create();
  o->sensorLabel = label;
  o->timestamp = fromRosTime(m.header.stamp);
  o->sensorPose = sensor_pose;
  o->hasPoints3D = true;
  for (size_t i = 0; i < n; ++i) {
    float v[3];
    for (int k = 0; k < 3; ++k) std::memcpy(&v[k], &m.data[i * m.point_step + off[k]], 4);
    if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) continue;
    o->points3D_x.push_back(v[0]);
    o->points3D_y.push_back(v[1]);
    o->points3D_z.push_back(v[2]);
    // the point's pixel (column, row) of an organised cloud; MRPT's
    // serialisation wants one per point
    o->points3D_idxs_x.push_back(static_cast<uint16_t>(i % m.width));
    o->points3D_idxs_y.push_back(static_cast<uint16_t>(i / m.width));
  }
  return o;
}

namespace {

/** Depth in metres of pixel `i` of a 16UC1 / mono16 (mm) or 32FC1 (m) image; 0: none. */
double depthAt(const sensor_msgs::Image& img, bool metres, size_t row, size_t col) {
  const uint8_t* p = &img.data[row * img.step + col * (metres ? 4 : 2)];
  if (!metres) {
    uint16_t mm;
    std::memcpy(&mm, p, 2);
    return mm * 0.001;
  }
  float d;
  std::memcpy(&d, p, 4);
  return std::isfinite(d) && d > 0 ? d : 0;
}

}  // namespace

mrpt::obs::CObservation3DRangeScan::Ptr depthFromRos(const sensor_msgs::Image& img,
                                                     const sensor_msgs::CameraInfo& info,
                                                     const std::string& label,
                                                     const mrpt::poses::CPose3D& sensor_pose) {
  const bool mm = img.encoding == "16UC1" || img.encoding == "mono16";
  const bool metres = img.encoding == "32FC1";
  const size_t W = img.width, H = img.height;
  if ((!mm && !metres) || img.is_bigendian || W == 0 || H == 0 || img.step < W * (metres ? 4 : 2) ||
      img.data.size() < H * img.step || info.K[0] <= 0 || info.K[4] <= 0)
    return nullptr;
  auto o = mrpt::obs::CObservation3DRangeScan::Create();
  o->sensorLabel = label;
  o->timestamp = fromRosTime(img.header.stamp);
  o->sensorPose = sensor_pose;
  o->hasRangeImage = true;
  o->range_is_depth = true;
  o->rangeUnits = 0.001f;
  o->rangeImage_setSize(static_cast<int>(H), static_cast<int>(W));
  o->cameraParams.ncols = static_cast<uint32_t>(W);
  o->cameraParams.nrows = static_cast<uint32_t>(H);
  o->cameraParams.setIntrinsicParamsFromValues(info.K[0], info.K[4], info.K[2], info.K[5]);
  for (size_t r = 0; r < H; ++r)
    for (size_t c = 0; c < W; ++c) {
      const double d = depthAt(img, metres, r, c) / 0.001;
      o->rangeImage(r, c) = static_cast<uint16_t>(d < 65535 ? std::lround(d) : 0);
    }
  return o;
}

bool depthToRos(const mrpt::obs::CObservation3DRangeScan& o, const std::string& frame,
                const ::ros::Time& stamp, sensor_msgs::Image& img, sensor_msgs::CameraInfo& info) {
  if (!o.hasRangeImage) return false;
  const size_t H = static_cast<size_t>(o.rangeImage.rows());
  const size_t W = static_cast<size_t>(o.rangeImage.cols());
  img.header.stamp = info.header.stamp = stamp;
  img.header.frame_id = info.header.frame_id = frame;
  img.height = info.height = static_cast<uint32_t>(H);
  img.width = info.width = static_cast<uint32_t>(W);
  img.encoding = "16UC1";
  img.is_bigendian = 0;
  img.step = static_cast<uint32_t>(2 * W);
  img.data.resize(2 * W * H);
  const double to_mm = o.rangeUnits / 0.001;
  for (size_t r = 0; r < H; ++r)
    for (size_t c = 0; c < W; ++c) {
      const double mm = std::round(o.rangeImage(r, c) * to_mm);
      const uint16_t v = mm < 65535 ? static_cast<uint16_t>(mm) : 0;
      std::memcpy(&img.data[2 * (r * W + c)], &v, 2);
    }
  const auto& cp = o.cameraParams;
  info.distortion_model = "plumb_bob";
  info.D.assign(5, 0.0);
  info.K = {cp.fx(), 0, cp.cx(), 0, cp.fy(), cp.cy(), 0, 0, 1};
  info.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  info.P = {cp.fx(), 0, cp.cx(), 0, 0, cp.fy(), cp.cy(), 0, 0, 0, 1, 0};
  return true;
}

mrpt::poses::CPose3D opticalInBody() {
  return mrpt::poses::CPose3D(0, 0, 0, -M_PI / 2, 0, -M_PI / 2);
}

std::string cameraOfOpticalFrame(const std::string& frame) {
  for (const std::string suffix : {"_optical_frame", "_optical"})
    if (frame.size() > suffix.size() &&
        frame.compare(frame.size() - suffix.size(), suffix.size(), suffix) == 0)
      return frame.substr(0, frame.size() - suffix.size());
  return frame;
}

nav_msgs::OccupancyGrid gridToRos(const mrpt::maps::COccupancyGridMap2D& g,
                                  const std::string& frame, const ::ros::Time& stamp) {
  nav_msgs::OccupancyGrid m;
  m.header.stamp = stamp;
  m.header.frame_id = frame;
  m.info.map_load_time = stamp;
  m.info.resolution = g.getResolution();
  m.info.width = static_cast<uint32_t>(g.getSizeX());
  m.info.height = static_cast<uint32_t>(g.getSizeY());
  m.info.origin.position.x = g.getXMin();
  m.info.origin.position.y = g.getYMin();
  m.info.origin.orientation.w = 1;
  m.data.resize(size_t{m.info.width} * m.info.height);
  for (unsigned j = 0; j < m.info.height; ++j)
    for (unsigned i = 0; i < m.info.width; ++i) {
      const double occ = 1.0 - g.getCell(i, j);  // MRPT cells: p(free)
      m.data[size_t{j} * m.info.width + i] =
          std::abs(occ - 0.5) < 0.01 ? -1 : static_cast<int8_t>(std::lround(100 * occ));
    }
  return m;
}

std::string bareFrame(const std::string& f) { return !f.empty() && f[0] == '/' ? f.substr(1) : f; }

}  // namespace carenav::ros
