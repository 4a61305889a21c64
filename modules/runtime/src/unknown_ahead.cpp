// Unknown floor ahead of the robot within its braking distance (unknown_ahead.h).
#include <carenav/perception/occupancy.h>
#include <carenav/runtime/unknown_ahead.h>

#include <algorithm>
#include <cmath>

namespace carenav::navigation {

namespace {
/** Beyond this many stood-on cells the set starts again from the robot's
 *  footprint (the perception grid forgets what is 5 m behind anyway). */
constexpr size_t kStoodPrune = 50000;  // ~190 m of a walker's travel
}  // namespace

double brakingDistance(double v, double acc, double reaction_time) {
  const double s = std::abs(v);
  return s * reaction_time + (acc > 0 ? s * s / (2 * acc) : 0.0);
}

UnknownAhead::UnknownAhead(const RobotParams& robot, const UnknownAheadParams& p, double resolution)
    : robot_(robot), p_(p), res_(resolution) {
  for (const auto& q : robot_.footprint) {
    front_ = std::max(front_, q.x);
    back_ = std::min(back_, q.x);
    half_width_ = std::max(half_width_, std::abs(q.y));
  }
}

bool UnknownAhead::inFootprint(double x, double y) const {
  // Crossing number of the footprint polygon (robot frame).
  const auto& f = robot_.footprint;
  bool in = false;
  for (size_t a = 0, b = f.size() - 1; a < f.size(); b = a++)
    if ((f[a].y > y) != (f[b].y > y) &&
        x < (f[b].x - f[a].x) * (y - f[a].y) / (f[b].y - f[a].y) + f[a].x)
      in = !in;
  return in;
}

template <class F>
void UnknownAhead::forCellsAround(const mrpt::math::TPose2D& pose, double r, F&& f) const {
  const double c = std::cos(pose.phi), s = std::sin(pose.phi);
  const long i0 = static_cast<long>(std::floor((pose.x - r) / res_));
  const long i1 = static_cast<long>(std::floor((pose.x + r) / res_));
  const long j0 = static_cast<long>(std::floor((pose.y - r) / res_));
  const long j1 = static_cast<long>(std::floor((pose.y + r) / res_));
  for (long i = i0; i <= i1; ++i)
    for (long j = j0; j <= j1; ++j) {
      const double dx = (i + 0.5) * res_ - pose.x, dy = (j + 0.5) * res_ - pose.y;
      f(i, j, c * dx + s * dy, -s * dx + c * dy);
    }
}

void UnknownAhead::stoodOn(const mrpt::math::TPose2D& pose) {
  if (robot_.footprint.size() < 3) return;
  if (stood_.empty()) startStrip(pose);
  if (stood_.size() > kStoodPrune) {
    // Forget what lies far behind (rebuilt around the robot from now on).
    stood_.clear();
  }
  const double r = std::max({front_, -back_, half_width_}) * std::sqrt(2.0);
  forCellsAround(pose, r, [&](long i, long j, double x, double y) {
    // Centres on the outline count (pulled 1 mm towards the axle, inside).
    const double k = 1.0 - 1e-3 / std::max(1e-3, std::hypot(x, y));
    if (inFootprint(x, y) || inFootprint(k * x, k * y)) stood_.insert(key(i, j));
  });
}

void UnknownAhead::startStrip(const mrpt::math::TPose2D& pose) {
  // The start: the zone at full speed ahead of the footprint, across its
  // width (the cells beside the camera's view there get no ray).
  const double x1 = front_ + reach(robot_.v_max);
  const double r = std::hypot(x1, half_width_) + res_;
  forCellsAround(pose, r, [&](long i, long j, double x, double y) {
    if (x >= front_ - 1e-9 && x <= x1 + 1e-9 && std::abs(y) <= half_width_ + 1e-9)
      stood_.insert(key(i, j));
  });
}

double UnknownAhead::reach(double v) const {
  const double t = p_.command_latency + p_.control_period + p_.frame_period;
  return p_.margin + brakingDistance(v, robot_.acc_v, t);
}

std::vector<mrpt::math::TPoint2D> UnknownAhead::cells(const perception::LocalOccupancy& g,
                                                      const mrpt::math::TPose2D& pose,
                                                      double v) const {
  std::vector<mrpt::math::TPoint2D> out;
  const bool fwd = v >= 0 || robot_.v_min >= 0;
  // The zone in the robot frame: x in [x0, x1], |y| <= half_width_.
  const double x0 = fwd ? front_ : back_ - reach(v);
  const double x1 = fwd ? front_ + reach(v) : back_;
  const double c = std::cos(pose.phi), s = std::sin(pose.phi);
  const double r = std::max(std::abs(x0), std::abs(x1)) + half_width_;
  const int i0 = std::max(0, g.cellX(pose.x - r)),
            i1 = std::min(g.cells() - 1, g.cellX(pose.x + r));
  const int j0 = std::max(0, g.cellY(pose.y - r)),
            j1 = std::min(g.cells() - 1, g.cellY(pose.y + r));
  const double inv = 1.0 / g.resolution();
  for (int i = i0; i <= i1; ++i)
    for (int j = j0; j <= j1; ++j) {
      const double wx = g.centreX(i), wy = g.centreY(j);
      const double dx = wx - pose.x, dy = wy - pose.y;
      const double x = c * dx + s * dy, y = -s * dx + c * dy;
      if (x < x0 || x > x1 || std::abs(y) > half_width_) continue;
      const double p = g.prob(i, j);
      if (p < p_.seen_free_below || p > p_.occupied_above) continue;
      const long ki = static_cast<long>(std::floor(wx * inv)),
                 kj = static_cast<long>(std::floor(wy * inv));
      if (stood_.count(key(ki, kj))) continue;
      out.push_back({wx, wy});
    }
  return out;
}

}  // namespace carenav::navigation
