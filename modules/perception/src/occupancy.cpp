#include <carenav/io/map_io.h>
#include <carenav/perception/occupancy.h>

#include <algorithm>
#include <cmath>

namespace carenav::perception {

namespace {
inline float logit(float p) { return std::log(p / (1 - p)); }
constexpr float kPMin = 0.02f, kPMax = 0.98f;  // per-measurement clamp (no certainty)
}  // namespace

LocalOccupancy::LocalOccupancy(int cells, double resolution, double logodds_max)
    : m_(cells), r_(resolution), lmax_(logodds_max) {
  reset();
}

void LocalOccupancy::reset() {
  const size_t n = static_cast<size_t>(m_) * m_;
  logodds_.assign(n, 0.f);
  occ_.assign(n, 0.5f);
  free_.assign(n, 0.5f);
  drop_.assign(n, 0);
  robot_ = mrpt::poses::CPose2D();
  org_i_ = org_j_ = -m_ / 2;
}

void LocalOccupancy::moveTo(const mrpt::poses::CPose2D& robot) {
  robot_ = robot;
  const long ni = static_cast<long>(std::floor(robot.x() / r_)) - m_ / 2;
  const long nj = static_cast<long>(std::floor(robot.y() / r_)) - m_ / 2;
  if (ni == org_i_ && nj == org_j_) return;
  std::vector<float> moved(logodds_.size(), 0.f);
  std::vector<uint8_t> moved_drop(drop_.size(), 0);
  for (int i = 0; i < m_; ++i)
    for (int j = 0; j < m_; ++j) {
      const long oi = ni + i - org_i_, oj = nj + j - org_j_;  // old grid index
      if (oi < 0 || oj < 0 || oi >= m_ || oj >= m_) continue;
      const size_t k = static_cast<size_t>(i) * m_ + j, ok = static_cast<size_t>(oi) * m_ + oj;
      moved[k] = logodds_[ok];
      moved_drop[k] = drop_[ok];
    }
  logodds_.swap(moved);
  drop_.swap(moved_drop);
  org_i_ = ni;
  org_j_ = nj;
}

int LocalOccupancy::cellX(double x) const {
  return static_cast<int>(static_cast<long>(std::floor(x / r_)) - org_i_);
}
int LocalOccupancy::cellY(double y) const {
  return static_cast<int>(static_cast<long>(std::floor(y / r_)) - org_j_);
}
double LocalOccupancy::centreX(int i) const { return (org_i_ + i + 0.5) * r_; }
double LocalOccupancy::centreY(int j) const { return (org_j_ + j + 0.5) * r_; }

void LocalOccupancy::beginFrame() {
  std::fill(occ_.begin(), occ_.end(), 0.5f);
  std::fill(free_.begin(), free_.end(), 0.5f);
}

void LocalOccupancy::addEvidence(int i, int j, float p) {
  if (!inside(i, j)) return;
  const size_t k = static_cast<size_t>(i) * m_ + j;
  if (p > 0.5f)
    occ_[k] = std::max(occ_[k], p);
  else if (p < 0.5f)
    free_[k] = std::min(free_[k], p);
}

void LocalOccupancy::endFrame() {
  const float lm = static_cast<float>(lmax_);
  for (size_t k = 0; k < logodds_.size(); ++k) {
    const float p = occ_[k] > 0.5f ? occ_[k] : free_[k];
    if (p == 0.5f) continue;  // no information
    // [Garrote17, Eq. 3] with p(c) = 0.5: l_t = logit(p(c|z_t)) + l_{t-1}.
    const float l = logodds_[k] + logit(std::clamp(p, kPMin, kPMax));
    logodds_[k] = std::clamp(l, -lm, lm);
  }
}

double LocalOccupancy::prob(int i, int j) const {
  if (!inside(i, j)) return 0.5;
  const float l = logodds_[static_cast<size_t>(i) * m_ + j];
  return 1.0 / (1.0 + std::exp(-static_cast<double>(l)));
}

double LocalOccupancy::probAt(double x, double y) const { return prob(cellX(x), cellY(y)); }

CellCounts LocalOccupancy::counts(double free_below, double occupied_above) const {
  // p > t  <=>  log-odds > logit(t): no exp per cell.
  const double lo = std::log(occupied_above / (1 - occupied_above));
  const double lf = std::log(free_below / (1 - free_below));
  CellCounts c;
  for (const float l : logodds_) {
    if (l > lo)
      ++c.occupied;
    else if (l < lf)
      ++c.free;
    else
      ++c.unknown;
  }
  return c;
}

mrpt::maps::COccupancyGridMap2D LocalOccupancy::toMrpt() const {
  auto g = io::makeGrid(org_i_ * r_, org_j_ * r_, r_, static_cast<size_t>(m_),
                        static_cast<size_t>(m_), 0.5f);
  for (int i = 0; i < m_; ++i)
    for (int j = 0; j < m_; ++j) g.setCell(i, j, static_cast<float>(1.0 - prob(i, j)));
  return g;
}

size_t integrateHeightBand(const Cloud& c, const PerceptionParams& p, LocalOccupancy& grid) {
  const double bin = p.scan_resolution * M_PI / 180.0;
  const int nb = static_cast<int>(std::ceil(2 * M_PI / bin));
  std::vector<double> hit(nb, 1e300), seen(nb, 0.0);
  const double ca = std::cos(grid.robot().phi()), sa = std::sin(grid.robot().phi());
  const double rx = grid.robot().x(), ry = grid.robot().y();
  size_t band = 0;
  for (const auto& q : c.points) {
    if (!validPoint(q)) continue;
    const double r = std::hypot(q.x, q.y);
    const int b = std::clamp(static_cast<int>((std::atan2(q.y, q.x) + M_PI) / bin), 0, nb - 1);
    if (q.z > p.band_z_min && q.z < p.band_z_max) {
      ++band;
      hit[b] = std::min(hit[b], r);
      grid.addEvidence(grid.cellX(rx + ca * q.x - sa * q.y), grid.cellY(ry + sa * q.x + ca * q.y),
                       0.8f);
    }
    seen[b] = std::max(seen[b], r);
  }
  for (int b = 0; b < nb; ++b) {
    const bool has_hit = hit[b] < 1e299;
    const double range = has_hit ? hit[b] : seen[b];
    if (range <= 0) continue;
    const double a = -M_PI + (b + 0.5) * bin + grid.robot().phi();
    const double ex = rx + std::cos(a) * range, ey = ry + std::sin(a) * range;
    const int hi = grid.cellX(ex), hj = grid.cellY(ey);
    grid.walkRay(ex, ey, range, [&](int ci, int cj, double, int) {
      if (has_hit && ci == hi && cj == hj) return;
      grid.addEvidence(ci, cj, 0.35f);
    });
  }
  return band;
}

void integrateScan(const mrpt::obs::CObservation2DRangeScan& scan, LocalOccupancy& grid,
                   float p_free, float p_occ) {
  const mrpt::poses::CPose3D robot3(grid.robot());
  const mrpt::poses::CPose3D sensor = robot3 + scan.sensorPose;
  const size_t n = scan.getScanSize();
  const double a0 = -0.5 * scan.aperture;
  const double da = n > 1 ? scan.aperture / (n - 1) : 0.0;
  for (size_t k = 0; k < n; ++k) {
    if (!scan.getScanRangeValidity(k)) continue;
    const double r = scan.getScanRange(k);
    const double a = scan.rightToLeft ? a0 + k * da : -(a0 + k * da);
    double gx, gy, gz;
    sensor.composePoint(r * std::cos(a), r * std::sin(a), 0.0, gx, gy, gz);
    const int hi = grid.cellX(gx), hj = grid.cellY(gy);
    const double range = std::hypot(gx - grid.robot().x(), gy - grid.robot().y());
    grid.walkRay(gx, gy, range, [&](int ci, int cj, double, int) {
      if (ci == hi && cj == hj) return;
      grid.addEvidence(ci, cj, p_free);
    });
    grid.addEvidence(hi, hj, p_occ);
  }
}

}  // namespace carenav::perception
