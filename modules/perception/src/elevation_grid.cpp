#include <carenav/perception/elevation_grid.h>

#include <algorithm>
#include <cmath>

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
    : m_(cells), r_(resolution), cells_(static_cast<size_t>(cells) * cells) {}

void ElevationGrid::clear() {
  std::fill(cells_.begin(), cells_.end(), ElevationCell{});
  valid_ = outliers_ = 0;
}

size_t ElevationGrid::build(const Cloud& c, double z_min, double z_max, double outlier_sigma) {
  clear();
  point_cell_.assign(c.points.size(), -1);
  size_t used = 0;
  for (size_t k = 0; k < c.points.size(); ++k) {
    const Point3f& p = c.points[k];
    if (!validPoint(p) || p.z < z_min || p.z > z_max) continue;
    const int i = cellOf(p.x), j = cellOf(p.y);
    if (!inside(i, j)) continue;
    point_cell_[k] = static_cast<int32_t>(idx(i, j));
    cells_[idx(i, j)].add(p.z);
    ++used;
  }
  if (outlier_sigma > 0) {
    // 3-sigma step: keep the statistics of pass 1, rebuild each cell from the
    // elevations within outlier_sigma standard deviations of its mean.
    std::vector<ElevationCell> before;
    before.swap(cells_);
    cells_.assign(before.size(), ElevationCell{});
    for (size_t k = 0; k < c.points.size(); ++k) {
      const int32_t ci = point_cell_[k];
      if (ci < 0) continue;
      const ElevationCell& b = before[ci];
      const double sd = std::sqrt(b.variance());
      const float z = c.points[k].z;
      if (b.n >= 3 && std::abs(z - b.mean) > outlier_sigma * sd) {
        ++outliers_;
        continue;
      }
      cells_[ci].add(z);
    }
    used -= outliers_;
  }
  valid_ = static_cast<size_t>(
      std::count_if(cells_.begin(), cells_.end(), [](const ElevationCell& e) { return e.n > 0; }));
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
