#include <carenav/perception/elevation_grid.h>

#include "float_order.h"

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

namespace {
constexpr size_t kChunk = 256;
constexpr int32_t kInvalid = -1;  ///< not a valid point (NaN, inf, |v| >= 1e6, the origin)
constexpr int32_t kOutside = -2;  ///< valid, but outside the z band or the grid

/** The grid's cell index per point of pts[0, m) (kInvalid, kOutside), with the arithmetic of
 *  one point at a time: fi = x / r + m / 2 as one multiply-add in float, the same for y, in
 *  the grid when 0 <= fi < m. Returns the valid points. Compiled as vector clones: every
 *  point gets the same operations (no FMA), so the cells are those of the scalar loop. */
CARENAV_VECTOR_CLONES size_t chunkCells(const Point3f* pts, size_t m, float inv, float off,
                                        float mf, float zlo, float zhi, int32_t cells,
                                        int32_t* cell) {
  size_t valid = 0;
  for (size_t k = 0; k < m; ++k) {
    const float x = pts[k].x, y = pts[k].y, z = pts[k].z;
    // NaN/inf fail every comparison; zero depth is the exact origin.
    const bool finite = (std::abs(x) < 1e6f) & (std::abs(y) < 1e6f) & (std::abs(z) < 1e6f);
    const bool ok = finite & !((x == 0.f) & (y == 0.f) & (z == 0.f));
    const float fi = x * inv + off, fj = y * inv + off;
    const bool in = (z >= zlo) & (z <= zhi) & (fi >= 0.f) & (fi < mf) & (fj >= 0.f) & (fj < mf);
    // Clamped before the conversion (NaN to 0): only cells in the grid are kept anyway.
    const int32_t i = static_cast<int32_t>(std::min(mf - 1.f, std::max(0.f, fi)));
    const int32_t j = static_cast<int32_t>(std::min(mf - 1.f, std::max(0.f, fj)));
    const int32_t c = in ? i * cells + j : kOutside;
    cell[k] = ok ? c : kInvalid;
    valid += ok;
  }
  return valid;
}
}  // namespace

void ElevationGrid::Acc::add(float z, bool first) {
  if (first) {
    lo = hi = ref = z;
    s = ss = 0;
  } else {
    lo = std::min(lo, z);
    hi = std::max(hi, z);
  }
  ++n;
  const double d = static_cast<double>(z - ref);
  s += d;
  ss += d * d;
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
  int32_t cell[kChunk];
  for (size_t k0 = 0; k0 < np; k0 += kChunk) {
    const size_t m = std::min(kChunk, np - k0);
    valid += chunkCells(pts + k0, m, inv, off, mf, zlo, zhi, m_, cell);
    for (size_t k = 0; k < m; ++k) {
      const int32_t ci = cell[k];
      if (ci < 0) continue;
      const float z = pts[k0 + k].z;
      pc[used++] = {ci, z};
      Acc& a = acc[ci];
      if (a.n == 0) touched_.push_back(ci);
      a.add(z, a.n == 0);
    }
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
      a.add(z, a.n == 0);
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
