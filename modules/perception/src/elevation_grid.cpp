#include <carenav/perception/elevation_grid.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace carenav::perception {

void ElevationCell::add(float z) {
  if (n == 0) {
    z_lo = z_hi = z;
  } else {
    z_lo = std::min(z_lo, z);
    z_hi = std::max(z_hi, z);
  }
  ++n;
  const double d = z - mean;
  mean += d / n;
  m2 += d * (z - mean);
}

ElevationGrid::ElevationGrid(int cells, double resolution)
    : m_(cells), r_(resolution), cells_(static_cast<size_t>(cells) * cells) {
  acc_.resize(cells_.size());
}

void ElevationGrid::clear() {
  for (int32_t k : touched_) cells_[k] = ElevationCell{};
  touched_.clear();
  valid_ = outliers_ = 0;
}

size_t ElevationGrid::build(const Cloud& c, double z_min, double z_max, double outlier_sigma) {
  clear();
  const size_t np = c.points.size();
  if (point_cell_.size() < np) point_cell_.resize(np);
  // Cell index with one multiply-add per axis: the grid spans [-m r/2, m r/2[.
  const float inv = static_cast<float>(1.0 / r_), off = 0.5f * static_cast<float>(m_);
  const float mf = static_cast<float>(m_), zlo = static_cast<float>(z_min),
              zhi = static_cast<float>(z_max);
  const Point3f* pts = c.points.data();
  Acc* acc = acc_.data();
  size_t used = 0, valid = 0;
  PointCell* pc = point_cell_.data();
  for (size_t k = 0; k < np; ++k) {
    const Point3f& p = pts[k];
    // NaN/inf fail every comparison; zero depth is the exact origin.
    if (!(std::abs(p.x) < 1e6f && std::abs(p.y) < 1e6f && std::abs(p.z) < 1e6f) ||
        (p.x == 0.f && p.y == 0.f && p.z == 0.f))
      continue;
    ++valid;
    if (!(p.z >= zlo && p.z <= zhi)) continue;
    const float fi = p.x * inv + off, fj = p.y * inv + off;
    if (!(fi >= 0.f && fi < mf && fj >= 0.f && fj < mf)) continue;
    const int32_t ci = static_cast<int32_t>(fi) * m_ + static_cast<int32_t>(fj);
    pc[used++] = {ci, p.z};
    Acc& a = acc[ci];
    if (a.n == 0) {
      touched_.push_back(ci);
      a.lo = a.hi = a.ref = p.z;
      a.s = a.ss = 0;
    } else {
      a.lo = std::min(a.lo, p.z);
      a.hi = std::max(a.hi, p.z);
    }
    ++a.n;
    const double d = static_cast<double>(p.z - a.ref);
    a.s += d;
    a.ss += d * d;
  }
  last_valid_ = valid;
  if (outlier_sigma > 0) {
    // 3-sigma step: keep the statistics of pass 1 (mean and band per cell),
    // rebuild each cell from the elevations within outlier_sigma standard
    // deviations of its mean.
    std::vector<Band>& band = band_;
    band.resize(acc_.size());
    for (int32_t ci : touched_) {
      Acc& a = acc[ci];
      const double mean = a.s / a.n;
      const double var = a.n > 1 ? std::max(0.0, (a.ss - a.s * mean) / (a.n - 1)) : 0.0;
      const double half = outlier_sigma * std::sqrt(var);
      const float lo = static_cast<float>(a.ref + mean - half),
                  hi = static_cast<float>(a.ref + mean + half);
      if (a.n < 3 || (a.lo >= lo && a.hi <= hi)) {
        // Nothing to drop: pass 1's statistics are final (marked lo > hi).
        band[ci] = {std::numeric_limits<float>::infinity(),
                    -std::numeric_limits<float>::infinity()};
        continue;
      }
      band[ci] = {lo, hi};
      a.n = 0;
    }
    for (size_t k = 0; k < used; ++k) {
      const int32_t ci = pc[k].cell;
      const Band& b = band[ci];
      if (b.lo > b.hi) continue;  // cell kept whole
      const float z = pc[k].z;
      if (z < b.lo || z > b.hi) {
        ++outliers_;
        continue;
      }
      Acc& a = acc[ci];
      if (a.n == 0) {
        a.lo = a.hi = a.ref = z;
        a.s = a.ss = 0;
      } else {
        a.lo = std::min(a.lo, z);
        a.hi = std::max(a.hi, z);
      }
      ++a.n;
      const double d = static_cast<double>(z - a.ref);
      a.s += d;
      a.ss += d * d;
    }
    used -= outliers_;
  }
  valid_ = 0;
  for (int32_t ci : touched_) {
    Acc& a = acc[ci];
    ElevationCell& e = cells_[ci];
    if (a.n > 0) {
      ++valid_;
      e.n = a.n;
      e.z_lo = a.lo;
      e.z_hi = a.hi;
      const double m = a.s / a.n;
      e.mean = a.ref + m;
      e.m2 = std::max(0.0, a.ss - a.s * m);
    }
    a = Acc{};
  }
  return used;
}

std::optional<double> ElevationGrid::idw(double x, double y, int s) const {
  const int ci = cellOf(x), cj = cellOf(y), h = s / 2;
  double wsum = 0, zsum = 0;
  for (int i = ci - h; i <= ci + h; ++i)
    for (int j = cj - h; j <= cj + h; ++j) {
      if (!valid(i, j)) continue;
      const double dx = centre(i) - x, dy = centre(j) - y;
      const double d2 = dx * dx + dy * dy;
      const double z = cells_[idx(i, j)].mean;
      if (d2 < 1e-12) return z;
      const double w = 1.0 / d2;  // inverse distance weighting, power 2
      wsum += w;
      zsum += w * z;
    }
  if (wsum <= 0) return std::nullopt;
  return zsum / wsum;
}

}  // namespace carenav::perception
