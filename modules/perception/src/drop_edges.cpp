// Drop edges from the image columns of an organised cloud: missing or lower
// returns where the floor should be (docs/perceive.md "Drops the camera
// cannot see into").
#include <carenav/perception/ism.h>

#include <algorithm>
#include <cmath>

namespace carenav::perception {

namespace {

struct ColumnScan {
  const Cloud& c;
  const Plane& plane;
  const PerceptionParams& p;
  const Point3f& o;
  LocalOccupancy& grid;
  double so;  // sensor height over the plane
  size_t edges = 0;

  double thr(const Point3f& q) const {
    return std::max(p.d_pth, p.noise_k * verticalNoise(p, &o, q.x, q.y, q.z));
  }
  /** Depression of the ray o -> q below the plane, rad. */
  double depression(const Point3f& q) const {
    const double dx = q.x - o.x, dy = q.y - o.y, dz = q.z - o.z;
    const double r = std::sqrt(dx * dx + dy * dy + dz * dz);
    return std::asin(std::clamp((so - plane.signedDistance(q.x, q.y, q.z)) / r, -1.0, 1.0));
  }
  /** Whether the floor `rows` pixel rows beyond the floor point f (prev: the
   *  floor point `step_rows` rows before it) would return within depth_max:
   *  then missing returns there mean no floor. */
  bool floorExpected(const Point3f& f, const Point3f& prev, int step_rows, int rows) const {
    const double bf = depression(f), bp = depression(prev);
    const double delta = (bp - bf) / step_rows;  // per row
    if (delta <= 0) return false;
    const double b = bf - rows * delta;
    if (b <= 0) return false;
    const double r = so / std::sin(b);
    return r + p.noise_k * p.depth_noise_std * r * r < p.depth_max;
  }
  /** Occupied evidence on the edge line: from the floor point f on along the
   *  ray's horizontal direction over kEdgeLength. */
  void mark(const Point3f& f) {
    constexpr double kEdgeLength = 0.1;  // m
    const double hx = f.x - o.x, hy = f.y - o.y, len = std::hypot(hx, hy);
    if (len < 1e-6) return;
    const auto& rb = grid.robot();
    const double ca = std::cos(rb.phi()), sa = std::sin(rb.phi());
    for (double d = 0; d <= kEdgeLength + 1e-9; d += 0.5 * grid.resolution()) {
      const double x = f.x + hx / len * d, y = f.y + hy / len * d;
      grid.addEvidence(grid.cellX(rb.x() + ca * x - sa * y), grid.cellY(rb.y() + sa * x + ca * y),
                       static_cast<float>(p.k_m));
    }
    ++edges;
  }
  void column(size_t u);
};

/** One image column from the bottom row (nearest floor) up. The floor level
 *  is followed along the column (a running mean of the floor points' height
 *  over the plane, starting on the plane): a plane a degree off, or a gentle
 *  ramp, moves it slowly; a drop or an obstacle jumps off it. */
void ColumnScan::column(size_t u) {
  constexpr int kGap = 4;          // invalid rows in a row: not the sensor's random dropout
  constexpr int kLower = 2;        // lower returns in a row: not one noisy sample
  constexpr double kFollow = 0.2;  // weight of a new floor point in the level
  const size_t W = c.width, H = c.height;
  bool floor = false, has_prev = false;
  Point3f f, prev;
  int f_row = 0, prev_row = 0, gap = 0, lower = 0;
  double level = 0;
  auto gapIsDrop = [&]() {
    return floor && gap >= kGap && has_prev && floorExpected(f, prev, prev_row - f_row, kGap);
  };
  for (size_t v = H; v-- > 0;) {
    const Point3f& q = c.points[v * W + u];
    if (!validPoint(q)) {
      gap += floor;
      continue;
    }
    const double sd = plane.signedDistance(q.x, q.y, q.z) - level, t = thr(q);
    if (std::abs(sd) <= t) {
      if (gapIsDrop()) mark(f);
      if (floor) {
        prev = f;
        prev_row = f_row;
        has_prev = true;
      }
      f = q;
      f_row = static_cast<int>(v);
      floor = true;
      gap = lower = 0;
      level += kFollow * sd;
    } else if (sd < -t) {
      if (floor && ++lower == kLower) mark(f);
    } else {
      floor = has_prev = false;  // above the floor: an obstacle (its shadow is no drop)
      gap = lower = 0;
      level = 0;
    }
  }
  if (gapIsDrop()) mark(f);
}

}  // namespace

size_t markImageDropEdges(const Cloud& c, const Plane& plane, const PerceptionParams& p,
                          const Point3f& sensor_origin, LocalOccupancy& grid) {
  if (!c.organised()) return 0;
  ColumnScan s{c,    plane,
               p,    sensor_origin,
               grid, plane.signedDistance(sensor_origin.x, sensor_origin.y, sensor_origin.z)};
  if (s.so <= 0) return 0;
  for (size_t u = 0; u < c.width; ++u) s.column(u);
  return s.edges;
}

}  // namespace carenav::perception
