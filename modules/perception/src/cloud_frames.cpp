// Frames and extraction of points from MRPT observations.
#include <carenav/common/errors.h>
#include <carenav/perception/cloud.h>

#include <mrpt/maps/CPointsMap.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CObservationVelodyneScan.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace carenav::perception {

namespace {
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

struct Rigid {
  float r[9], t[3];
  explicit Rigid(const mrpt::poses::CPose3D& p) {
    const auto R = p.getRotationMatrix();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) r[i * 3 + j] = static_cast<float>(R(i, j));
    t[0] = static_cast<float>(p.x());
    t[1] = static_cast<float>(p.y());
    t[2] = static_cast<float>(p.z());
  }
  Point3f operator()(const Point3f& a) const {
    return {r[0] * a.x + r[1] * a.y + r[2] * a.z + t[0],
            r[3] * a.x + r[4] * a.y + r[5] * a.z + t[1],
            r[6] * a.x + r[7] * a.y + r[8] * a.z + t[2]};
  }
};
/** The image layout of a point list whose points carry their pixel
 *  (points3D_idxs_x / _y: column, row), e.g. an organised ROS PointCloud2
 *  without its invalid points (modules/ros cloudFromRos): width x height
 *  with NaN where no point is, so the rules that follow image columns (drop
 *  edges, FSPF+) run on it. False, and `out` untouched, when the pixels are
 *  missing, one row only, any pixel twice, or the image larger than
 *  kMaxCloudPoints: then the list stays a list. */
bool organisedFromPixels(const mrpt::obs::CObservation3DRangeScan& o, Cloud& out) {
  const size_t n = o.points3D_x.size();
  if (n == 0 || o.points3D_y.size() != n || o.points3D_z.size() != n ||
      o.points3D_idxs_x.size() != n || o.points3D_idxs_y.size() != n)
    return false;
  size_t w = 0, h = 0;
  for (size_t i = 0; i < n; ++i) {
    w = std::max<size_t>(w, o.points3D_idxs_x[i] + size_t{1});
    h = std::max<size_t>(h, o.points3D_idxs_y[i] + size_t{1});
  }
  if (h < 2 || w * h > kMaxCloudPoints) return false;
  std::vector<Point3f> pts(w * h, Point3f{kNaN, kNaN, kNaN});
  std::vector<char> used(w * h, 0);
  for (size_t i = 0; i < n; ++i) {
    const size_t k = size_t{o.points3D_idxs_y[i]} * w + o.points3D_idxs_x[i];
    if (used[k]++) return false;
    pts[k] = {o.points3D_x[i], o.points3D_y[i], o.points3D_z[i]};
  }
  out.width = w;
  out.height = h;
  out.points = std::move(pts);
  return true;
}

}  // namespace

mrpt::poses::CPose3D parseSensorPose(const std::string& text) {
  std::string t = text;
  for (char& ch : t)
    if (ch == ',') ch = ' ';
  std::istringstream ss(t);
  double v[6];
  for (double& x : v)
    if (!(ss >> x))
      throw InputError("--sensor-pose '" + text +
                       "': expected six numbers x,y,z,yaw,pitch,roll (m, deg)");
  std::string extra;
  if (ss >> extra) throw InputError("--sensor-pose '" + text + "': more than six numbers");
  const double d2r = M_PI / 180.0;
  return mrpt::poses::CPose3D(v[0], v[1], v[2], v[3] * d2r, v[4] * d2r, v[5] * d2r);
}

Cloud toRobotFrame(const Cloud& c, const mrpt::poses::CPose3D& sensor_pose, bool optical) {
  const Rigid T(sensor_pose);
  Cloud out;
  out.width = c.width;
  out.height = c.height;
  out.points.resize(c.points.size());
  for (size_t i = 0; i < c.points.size(); ++i) {
    const Point3f& p = c.points[i];
    if (!validPoint(p)) {
      out.points[i] = {kNaN, kNaN, kNaN};
      continue;
    }
    out.points[i] = T(optical ? opticalToSensor(p) : p);
  }
  return out;
}

std::optional<Cloud> cloudFromObservation(
    const mrpt::obs::CObservation& obs, const std::optional<mrpt::poses::CPose3D>& pose_override) {
  using namespace mrpt::obs;
  Cloud local;  // sensor frame (MRPT: x forward, y left, z up)
  mrpt::poses::CPose3D pose;
  if (const auto* o = dynamic_cast<const CObservation3DRangeScan*>(&obs)) {
    o->load();
    pose = o->sensorPose;
    if (o->hasRangeImage) {
      const auto& cam = o->cameraParams;
      const size_t H = static_cast<size_t>(o->rangeImage.rows());
      const size_t W = static_cast<size_t>(o->rangeImage.cols());
      const double fx = cam.fx(), fy = cam.fy(), cx = cam.cx(), cy = cam.cy();
      local.width = W;
      local.height = H;
      local.points.resize(W * H);
      for (size_t r = 0; r < H; ++r)
        for (size_t col = 0; col < W; ++col) {
          const uint16_t raw = o->rangeImage(r, col);
          Point3f& p = local.points[r * W + col];
          if (raw == 0 || fx <= 0 || fy <= 0) {
            p = {kNaN, kNaN, kNaN};
            continue;
          }
          const double ky = (cx - col) / fx, kz = (cy - r) / fy;
          double x = raw * o->rangeUnits;  // MRPT's formulas (CObservation3DRangeScan docs)
          if (!o->range_is_depth) x /= std::sqrt(1 + ky * ky + kz * kz);
          p = {static_cast<float>(x), static_cast<float>(ky * x), static_cast<float>(kz * x)};
        }
    } else if (o->hasPoints3D) {
      if (!organisedFromPixels(*o, local)) {
        for (size_t i = 0; i < o->points3D_x.size(); ++i)
          local.points.push_back({o->points3D_x[i], o->points3D_y[i], o->points3D_z[i]});
        local.width = local.points.size();
      }
    } else {
      local.width = 0;  // no data: an empty frame
    }
  } else if (const auto* pc = dynamic_cast<const CObservationPointCloud*>(&obs)) {
    pc->load();
    pose = pc->sensorPose;
    if (pc->pointcloud) {
      const auto& xs = pc->pointcloud->getPointsBufferRef_x();
      const auto& ys = pc->pointcloud->getPointsBufferRef_y();
      const auto& zs = pc->pointcloud->getPointsBufferRef_z();
      for (size_t i = 0; i < xs.size(); ++i) local.points.push_back({xs[i], ys[i], zs[i]});
    }
    local.width = local.points.size();
  } else if (const auto* v = dynamic_cast<const CObservationVelodyneScan*>(&obs)) {
    CObservationVelodyneScan copy = *v;  // generatePointCloud fills a member
    copy.generatePointCloud();
    pose = copy.sensorPose;
    const auto& pcl = copy.point_cloud;
    for (size_t i = 0; i < pcl.x.size(); ++i)
      local.points.push_back({pcl.x[i], pcl.y[i], pcl.z[i]});
    local.width = local.points.size();
  } else {
    return std::nullopt;
  }
  return toRobotFrame(local, pose_override ? *pose_override : pose, false);
}

}  // namespace carenav::perception
