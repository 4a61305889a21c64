#include <carenav/sim/simulator.h>

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CObservationRange.h>
#include <mrpt/poses/CPose3D.h>

#include <algorithm>
#include <cmath>

namespace carenav::sim {

namespace {
constexpr double kDeg = M_PI / 180.0;

double wrap(double a) {
  while (a > M_PI) a -= 2 * M_PI;
  while (a < -M_PI) a += 2 * M_PI;
  return a;
}

mrpt::poses::CPose3D sensorPose(const SensorParams& s) {
  return mrpt::poses::CPose3D(s.x, s.y, s.z, s.yaw * kDeg, s.pitch * kDeg, s.roll * kDeg);
}

/** Pose after moving with (v, w) for dt: exact arc. */
Pose2 advance(const Pose2& p, double v, double w, double dt) {
  Pose2 q = p;
  const double dth = w * dt;
  if (std::abs(dth) < 1e-9) {
    q.x += v * dt * std::cos(p.yaw + dth / 2);
    q.y += v * dt * std::sin(p.yaw + dth / 2);
  } else {
    const double r = v / w;
    q.x += r * (std::sin(p.yaw + dth) - std::sin(p.yaw));
    q.y -= r * (std::cos(p.yaw + dth) - std::cos(p.yaw));
  }
  q.yaw = wrap(p.yaw + dth);
  return q;
}

/** SplitMix64 (Steele, Lea, Flood 2014): a fast generator for per-pixel draws. */
inline uint64_t splitmix64(uint64_t& state) {
  uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

/** Standard normal quantiles at (i + 0.5) / 4096: a draw indexes it with 12
 *  random bits (a Gaussian sampled on 4096 levels, tails cut at 3.5 sigma). */
const std::vector<float>& normalTable() {
  static const std::vector<float> t = [] {
    std::vector<float> q(4096);
    for (int i = 0; i < 4096; ++i) {
      const double p = (i + 0.5) / 4096;
      double lo = -10, hi = 10;  // bisection on the CDF 0.5 erfc(-x / sqrt 2)
      for (int k = 0; k < 80; ++k) {
        const double mid = 0.5 * (lo + hi);
        (0.5 * std::erfc(-mid / std::sqrt(2.0)) < p ? lo : hi) = mid;
      }
      q[i] = static_cast<float>(0.5 * (lo + hi));
    }
    return q;
  }();
  return t;
}

int depthCols(const SensorParams& s, const SimParams& p) {
  return std::max(1, s.width / p.depth_decimation);
}
int depthRows(const SensorParams& s, const SimParams& p) {
  return std::max(1, s.height / p.depth_decimation);
}
}  // namespace

mrpt::Clock::time_point simStamp(double t) { return mrpt::Clock::fromDouble(kSimEpoch + t); }

Simulator::Simulator(std::shared_ptr<const World> world, RobotParams robot,
                     std::vector<SensorParams> sensors, SimParams params)
    : world_(std::move(world)),
      robot_(std::move(robot)),
      sensors_(std::move(sensors)),
      params_(std::move(params)),
      odo_rng_(static_cast<uint64_t>(params_.seed)) {
  for (size_t i = 0; i < sensors_.size(); ++i) {
    sensor_rng_.emplace_back(static_cast<uint64_t>(params_.seed) * 1000003ULL + 7919ULL * (i + 1));
    std::vector<float> dirs;
    const auto& s = sensors_[i];
    if (s.type == "depth-camera") {
      const int W = depthCols(s, params_), H = depthRows(s, params_);
      const double fx = (W / 2.0) / std::tan(s.fov * kDeg / 2);
      const double fy = (H / 2.0) / std::tan(s.vfov * kDeg / 2);
      const double cx = (W - 1) / 2.0, cy = (H - 1) / 2.0;
      dirs.reserve(static_cast<size_t>(W) * H * 2);
      for (int r = 0; r < H; ++r)
        for (int c = 0; c < W; ++c) {
          dirs.push_back(static_cast<float>((cx - c) / fx));  // Ky (MRPT: y left)
          dirs.push_back(static_cast<float>((cy - r) / fy));  // Kz (z up)
        }
    }
    depth_dirs_.push_back(std::move(dirs));
  }
  reset({});
}

void Simulator::reset(const Pose2& start) {
  t_ = 0;
  truth_ = odo_ = start;
  v_ = w_ = v_cmd_ = w_cmd_ = v_odo_ = w_odo_ = 0;
  pending_.clear();
  collided_ = false;
  clear_distance_ = 0;
  contacts_ = 0;
  distance_ = 0;
  next_frame_.assign(sensors_.size(), 0);
}

void Simulator::setCommand(double v, double w) {
  v = std::clamp(v, robot_.v_min, robot_.v_max);
  w = std::clamp(w, -robot_.w_max, robot_.w_max);
  pending_.push_back({t_ + params_.latency, v, w});
}

bool Simulator::footprintBlocked(const Pose2& p, double t) const {
  const World& w = *world_;
  const double c = std::cos(p.yaw), s = std::sin(p.yaw);
  std::vector<Vec2> poly;
  for (const auto& q : robot_.footprint)
    poly.push_back({p.x + c * q.x - s * q.y, p.y + s * q.x + c * q.y});
  // people: a person touches the footprint when its circle reaches the polygon
  for (const auto& person : peopleAt(w, t)) {
    if (pointInPolygon(poly, person.x, person.y)) return true;
    for (size_t i = 0; i < poly.size(); ++i) {
      const Vec2& a = poly[i];
      const Vec2& b = poly[(i + 1) % poly.size()];
      const double ex = b.x - a.x, ey = b.y - a.y;
      const double u = std::clamp(
          ((person.x - a.x) * ex + (person.y - a.y) * ey) / std::max(1e-12, ex * ex + ey * ey), 0.0,
          1.0);
      if (std::hypot(a.x + u * ex - person.x, a.y + u * ey - person.y) < person.r) return true;
    }
  }
  // cells: anything raised more than bumper_step, walls included
  const int pcx = w.cellX(p.x), pcy = w.cellY(p.y);
  const double rad = robot_.circumscribedRadius();
  if (w.inside(pcx, pcy) && w.clearance(pcx, pcy) > rad / w.resolution() + 2) return false;
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (const auto& v : poly)
    x0 = std::min(x0, v.x), y0 = std::min(y0, v.y), x1 = std::max(x1, v.x), y1 = std::max(y1, v.y);
  const int cx0 = std::max(0, w.cellX(x0)), cx1 = std::min(w.sizeX() - 1, w.cellX(x1));
  const int cy0 = std::max(0, w.cellY(y0)), cy1 = std::min(w.sizeY() - 1, w.cellY(y1));
  const double res = w.resolution();
  for (int cy = cy0; cy <= cy1; ++cy)
    for (int cx = cx0; cx <= cx1; ++cx) {
      const Cell& cell = w.cell(cx, cy);
      if (cell.plain() || !(cell.floor > params_.bumper_step)) continue;
      // the cell touches the footprint: its centre inside, or a corner of the footprint in it
      const double mx = w.xMin() + (cx + 0.5) * res, my = w.yMin() + (cy + 0.5) * res;
      if (pointInPolygon(poly, mx, my)) return true;
      for (const auto& v : poly)
        if (w.cellX(v.x) == cx && w.cellY(v.y) == cy) return true;
      // an edge of the footprint crossing the cell
      for (size_t i = 0; i < poly.size(); ++i) {
        const Vec2& a = poly[i];
        const Vec2& b = poly[(i + 1) % poly.size()];
        const int n = static_cast<int>(std::ceil(std::hypot(b.x - a.x, b.y - a.y) / (res / 2))) + 1;
        for (int k = 0; k <= n; ++k) {
          const double u = static_cast<double>(k) / n;
          if (w.cellX(a.x + u * (b.x - a.x)) == cx && w.cellY(a.y + u * (b.y - a.y)) == cy)
            return true;
        }
      }
    }
  return false;
}

void Simulator::applyDueCommands() {
  while (!pending_.empty() && pending_.front().t_apply <= t_ + 1e-12) {
    v_cmd_ = pending_.front().v;
    w_cmd_ = pending_.front().w;
    pending_.pop_front();
  }
}

void Simulator::integrate(double dt) {
  if (dt <= 0) return;
  applyDueCommands();
  v_ += std::clamp(v_cmd_ - v_, -robot_.acc_v * dt, robot_.acc_v * dt);
  w_ += std::clamp(w_cmd_ - w_, -robot_.acc_w * dt, robot_.acc_w * dt);
  const Pose2 next = advance(truth_, v_, w_, dt);
  double dd = v_ * dt, dth = w_ * dt;
  if ((v_ != 0 || w_ != 0) && footprintBlocked(next, t_ + dt)) {
    if (!collided_) ++contacts_;
    collided_ = true;
    clear_distance_ = 0;
    v_ = w_ = 0;  // the bumper stops the robot
    dd = dth = 0;
  } else {
    truth_ = next;
    // the bumper releases once the robot has moved 5 cm without touching
    clear_distance_ += std::abs(dd);
    if (clear_distance_ > 0.05) collided_ = false;
  }
  distance_ += std::abs(dd);
  // Odometry: systematic scale and drift plus random-walk noise (SimParams).
  const double ad = std::abs(dd), ath = std::abs(dth);
  double dd_o = dd * (1 + params_.odom_scale_d);
  double dth_o = dth * (1 + params_.odom_scale_w) + params_.odom_bias_w * kDeg * ad;
  if (ad > 0 || ath > 0) {
    std::normal_distribution<double> n01(0.0, 1.0);
    const double sd = params_.odom_std_d * std::sqrt(ad);
    const double sw = std::sqrt(std::pow(params_.odom_std_w * kDeg, 2) * ath +
                                std::pow(params_.odom_std_wd * kDeg, 2) * ad);
    dd_o += sd * n01(odo_rng_);
    dth_o += sw * n01(odo_rng_);
  }
  odo_ = advance(odo_, dd_o / dt, dth_o / dt, dt);
  v_odo_ = dd_o / dt;
  w_odo_ = dth_o / dt;
  t_ += dt;
}

std::vector<SimFrame> Simulator::step(double dt) {
  std::vector<SimFrame> out;
  const double t_end = t_ + dt;
  const double tol = 1e-9;
  while (true) {
    // frames due now
    std::vector<size_t> due;
    for (size_t i = 0; i < sensors_.size(); ++i) {
      if (sensors_[i].type == "bumper") continue;
      if (next_frame_[i] / sensors_[i].rate_hz <= t_ + tol) due.push_back(i);
    }
    if (!due.empty() && t_ < t_end - tol) {
      SimFrame f;
      f.t = t_;
      f.truth = truth_;
      f.odometry = odo_;
      f.observations.push_back(odometryObs());
      for (size_t i : due) {
        f.observations.push_back(observe(i));
        ++next_frame_[i];
      }
      out.push_back(std::move(f));
    }
    if (t_ >= t_end - tol) break;
    double next = t_end;
    for (size_t i = 0; i < sensors_.size(); ++i)
      if (sensors_[i].type != "bumper") next = std::min(next, next_frame_[i] / sensors_[i].rate_hz);
    next = std::min(next, t_ + params_.physics_dt);
    applyDueCommands();
    if (!pending_.empty()) next = std::min(next, pending_.front().t_apply);
    if (next <= t_) next = t_ + tol;
    integrate(next - t_);
    t_ = next;  // exact sensor times (no drift of the sum)
  }
  return out;
}

mrpt::obs::CObservation::Ptr Simulator::odometryObs() const {
  auto o = mrpt::obs::CObservationOdometry::Create();
  o->sensorLabel = "odometry";
  o->timestamp = simStamp(t_);
  o->odometry = mrpt::poses::CPose2D(odo_.x, odo_.y, odo_.yaw);
  o->hasVelocities = true;
  o->velocityLocal = mrpt::math::TTwist2D(v_odo_, 0, w_odo_);
  return o;
}

mrpt::obs::CObservation::Ptr Simulator::observe(size_t i) {
  const auto people = peopleAt(*world_, t_);
  const auto& s = sensors_[i];
  if (s.type == "lidar2d") return lidar(i, people);
  if (s.type == "range-array") return rangeArray(i, people);
  if (s.type == "depth-camera") return depth(i, people);
  return {};
}

mrpt::obs::CObservation::Ptr Simulator::lidar(size_t i, const std::vector<PersonNow>& people) {
  const auto& s = sensors_[i];
  auto o = mrpt::obs::CObservation2DRangeScan::Create();
  o->sensorLabel = s.label;
  o->timestamp = simStamp(t_);
  o->aperture = static_cast<float>(s.fov * kDeg);
  o->rightToLeft = true;
  o->maxRange = static_cast<float>(s.range_max);
  o->stdError = static_cast<float>(s.noise_std);
  o->sensorPose = sensorPose(s);
  const int n = s.beams;
  o->resizeScan(n);
  const double c = std::cos(truth_.yaw), sn = std::sin(truth_.yaw);
  const double px = truth_.x + c * s.x - sn * s.y, py = truth_.y + sn * s.x + c * s.y;
  const double heading = truth_.yaw + s.yaw * kDeg;
  const double fov = s.fov * kDeg;
  std::normal_distribution<double> noise(0.0, s.noise_std);
  auto& rng = sensor_rng_[i];
  const bool max_valid = params_.lidar_max_range == "max";
  for (int k = 0; k < n; ++k) {
    const double a = -fov / 2 + (n > 1 ? fov * k / (n - 1) : 0);
    const double r = castRay2D(*world_, people, px, py, s.z, heading + a, s.range_max);
    float range;
    bool valid;
    if (r == kNoHit) {
      range = static_cast<float>(s.range_max);
      valid = max_valid;
    } else {
      const double rn = s.noise_std > 0 ? r + noise(rng) : r;
      range = static_cast<float>(std::clamp(rn, 0.0, s.range_max));
      valid = rn >= s.range_min && rn < s.range_max;
    }
    o->setScanRange(k, range);
    o->setScanRangeValidity(k, valid);
  }
  return o;
}

mrpt::obs::CObservation::Ptr Simulator::rangeArray(size_t i, const std::vector<PersonNow>& people) {
  const auto& s = sensors_[i];
  auto o = mrpt::obs::CObservationRange::Create();
  o->sensorLabel = s.label;
  o->timestamp = simStamp(t_);
  o->minSensorDistance = static_cast<float>(s.range_min);
  o->maxSensorDistance = static_cast<float>(s.range_max);
  const double seg = s.fov * kDeg / s.segments;
  o->sensorConeApperture = static_cast<float>(seg);
  const double c = std::cos(truth_.yaw), sn = std::sin(truth_.yaw);
  const double px = truth_.x + c * s.x - sn * s.y, py = truth_.y + sn * s.x + c * s.y;
  std::normal_distribution<double> noise(0.0, s.noise_std);
  auto& rng = sensor_rng_[i];
  for (int k = 0; k < s.segments; ++k) {
    // segment k spans [a - seg/2, a + seg/2]; the nearest of 3 rays across it
    const double a = s.yaw * kDeg - s.fov * kDeg / 2 + (k + 0.5) * seg;
    double r = kNoHit;
    for (double f : {-0.45, 0.0, 0.45})
      r = std::min(r,
                   castRay2D(*world_, people, px, py, s.z, truth_.yaw + a + f * seg, s.range_max));
    mrpt::obs::CObservationRange::TMeasurement m;
    m.sensorID = static_cast<uint16_t>(k);
    m.sensorPose = mrpt::math::TPose3D(s.x, s.y, s.z, a, s.pitch * kDeg, s.roll * kDeg);
    m.sensedDistance = static_cast<float>(
        r == kNoHit ? s.range_max
                    : std::clamp(s.noise_std > 0 ? r + noise(rng) : r, 0.0, s.range_max));
    o->sensedData.push_back(m);
  }
  return o;
}

mrpt::obs::CObservation::Ptr Simulator::depth(size_t i, const std::vector<PersonNow>& people) {
  const auto& s = sensors_[i];
  const int W = depthCols(s, params_), H = depthRows(s, params_);
  auto o = mrpt::obs::CObservation3DRangeScan::Create();
  o->sensorLabel = s.label;
  o->timestamp = simStamp(t_);
  o->sensorPose = sensorPose(s);
  o->maxRange = static_cast<float>(s.range_max);
  o->stdError = static_cast<float>(s.noise_std);
  o->range_is_depth = true;
  o->hasRangeImage = true;
  o->rangeUnits = 0.001f;
  o->rangeImage_setSize(H, W);
  const double fx = (W / 2.0) / std::tan(s.fov * kDeg / 2);
  const double fy = (H / 2.0) / std::tan(s.vfov * kDeg / 2);
  o->cameraParams.ncols = W;
  o->cameraParams.nrows = H;
  o->cameraParams.setIntrinsicParamsFromValues(fx, fy, (W - 1) / 2.0, (H - 1) / 2.0);
  o->cameraParamsIntensity = o->cameraParams;
  // camera pose in the map
  const mrpt::poses::CPose3D cam =
      mrpt::poses::CPose3D(truth_.x, truth_.y, 0, truth_.yaw, 0, 0) + o->sensorPose;
  const auto R = cam.getRotationMatrix();
  const double org[3] = {cam.x(), cam.y(), cam.z()};
  const double c0[3] = {R(0, 0), R(1, 0), R(2, 0)};  // camera x (optical axis)
  const double c1[3] = {R(0, 1), R(1, 1), R(2, 1)};  // camera y (left)
  const double c2[3] = {R(0, 2), R(1, 2), R(2, 2)};  // camera z (up)
  const auto& dirs = depth_dirs_[i];
  // per-pixel draws: SplitMix64 seeded from the sensor's generator (deterministic)
  uint64_t state = sensor_rng_[i]();
  const auto& normal = normalTable();
  const double drop = params_.depth_invalid_rate;
  const uint64_t drop_below = static_cast<uint64_t>(drop * 4294967296.0);
  for (int r = 0; r < H; ++r)
    for (int c = 0; c < W; ++c) {
      const size_t k = (static_cast<size_t>(r) * W + c) * 2;
      const double ky = dirs[k], kz = dirs[k + 1];
      const double d[3] = {c0[0] + ky * c1[0] + kz * c2[0], c0[1] + ky * c1[1] + kz * c2[1],
                           c0[2] + ky * c1[2] + kz * c2[2]};
      double z = castRay3D(*world_, people, org, d, s.range_max);
      uint16_t mm = 0;
      if (z != kNoHit) {
        const uint64_t r64 = splitmix64(state);
        // noise grows with the square of the depth: noise_std is the std at 1 m
        if (s.noise_std > 0) z += s.noise_std * z * z * normal[r64 & 4095];
        if (z >= s.range_min && z <= s.range_max && (r64 >> 32) >= drop_below)
          mm = static_cast<uint16_t>(z * 1000.0 + 0.5);
      }
      o->rangeImage(r, c) = mm;
    }
  return o;
}

}  // namespace carenav::sim
