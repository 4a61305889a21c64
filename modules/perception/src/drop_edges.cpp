// Drop edges from the image columns of an organised cloud: missing or lower
// returns where the floor should be (docs/perceive.md "Drops the camera
// cannot see into").
#include <carenav/perception/ism.h>

#include "float_order.h"

#include <algorithm>
#include <cmath>

namespace carenav::perception {

namespace {

/** What one image column has seen so far, from the bottom row up. */
struct Column {
  int f_row = -1, prev_row = -1;       // rows of the last floor point and the one before (-1: none)
  int gap = 0, lower = 0;              // invalid rows / lower returns since the last floor point
  int first_low = -1, first_lows = 0;  // the column's first returns, lower (-1 lows: not first)
};

/** What a pixel is to its column's floor (classifyRow). */
enum PixelClass : int8_t { kNoReturn = 0, kFloor = 1, kLowerReturn = 2, kAbove = 3 };

/** The plane, the sensor origin and the rule-1 thresholds, as the per-row pass uses them. */
struct RowRule {
  double pa, pb, pc, pd;
  double ox, oy, oz;
  double dpth2, kv2;
};

/** Per pixel of one image row: its class against its column's followed floor level, and its
 *  signed distance sd over that level (Plane::signedDistance minus the level). Floor: sd^2
 *  within max(d_pth, noise_k sigma_v)^2 (the squared rule-1 threshold, no sqrt); else lower
 *  (sd < 0) or above. The arithmetic of one pixel at a time, in double, as vector clones (no
 *  FMA): the classes are those of the per-pixel test. */
CARENAV_VECTOR_CLONES void classifyRow(const Point3f* row, size_t w, const float* level,
                                       const RowRule& r, double* sd, int8_t* cls) {
  for (size_t u = 0; u < w; ++u) {
    const float x = row[u].x, y = row[u].y, z = row[u].z;
    const bool valid = (std::abs(x) < 1e6f) & (std::abs(y) < 1e6f) & (std::abs(z) < 1e6f) &
                       !((x == 0.f) & (y == 0.f) & (z == 0.f));
    const double d = r.pa * x + r.pb * y + r.pc * z + r.pd - level[u], d2 = d * d;
    const double dx = x - r.ox, dy = y - r.oy, dz = z - r.oz;
    const double t2 = std::max(r.dpth2, r.kv2 * (dx * dx + dy * dy + dz * dz) * dz * dz);
    const int8_t c =
        (d2 <= r.dpth2) | (d2 <= t2) ? int8_t{kFloor} : int8_t{d < 0 ? kLowerReturn : kAbove};
    cls[u] = valid ? c : int8_t{kNoReturn};
    sd[u] = d;
  }
}

struct ColumnScan {
  const Cloud& c;
  const Plane& plane;
  const PerceptionParams& p;
  const Point3f& o;
  LocalOccupancy& grid;
  double so;  // sensor height over the plane
  size_t edges = 0;

  RowRule rule() const {
    const double kv = p.noise_k * p.depth_noise_std;
    return {plane.a, plane.b, plane.c, plane.d, o.x, o.y, o.z, p.d_pth * p.d_pth, kv * kv};
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
      const int i = grid.cellX(rb.x() + ca * x - sa * y), j = grid.cellY(rb.y() + sa * x + ca * y);
      grid.addEvidence(i, j, static_cast<float>(p.k_m));
      grid.setDrop(i, j, true);
    }
    ++edges;
  }
  /** The column's first returns are lower than the floor: the floor ends
   *  before the view (a drop edge in the blind zone under the camera).
   *  Occupied evidence where the ray to q crosses the plane: the floor would
   *  have been seen there. */
  void markBeforeView(const Point3f& q) {
    const double sq = plane.signedDistance(q.x, q.y, q.z);
    if (sq >= 0) return;
    const double t = so / (so - sq);
    mark({static_cast<float>(o.x + t * (q.x - o.x)), static_cast<float>(o.y + t * (q.y - o.y)),
          static_cast<float>(o.z + t * (q.z - o.z))});
  }
  void step(Column& k, float& level, int8_t cls, double sd, size_t u, int v);
  /** Two lower returns side by side in one row count as kLower in one
   *  column: a column's first lower return after its floor, with a lower
   *  return in a neighbouring column of the same row, marks the edge (a
   *  small hole's far wall, seen over one row at a quarter of the
   *  resolution, gives one lower return per column). Only with a noise
   *  model (depth_noise_std > 0): then "lower" lies noise_k sigmas down
   *  and two such returns are unlikely from noise; below a fixed d_pth the
   *  far floor's noise crosses it (a simulated Kinect One without the
   *  model: drop edges on a flat floor in 385 of 900 frames, 173 of 710
   *  without the pairs). */
  void pairInRow(std::vector<Column>& cols, const std::vector<int8_t>& cls);
  void finish(Column& k, size_t u);
  const Point3f& at(int v, size_t u) const {
    return c.points[static_cast<size_t>(v) * c.width + u];
  }
};

// Per column, from the bottom row (nearest floor) up. The floor level is
// followed along the column (a running mean of the floor points' height over
// the plane, starting on the plane): a plane a degree off, or a gentle ramp,
// moves it slowly; a drop or an obstacle jumps off it.
constexpr int kGap = 4;          // invalid rows in a row: not the sensor's random dropout
constexpr int kLower = 2;        // lower returns in a row (or side by side): not one noisy sample
constexpr float kFollow = 0.2f;  // weight of a new floor point in the level
constexpr int kFirstLower = 4;   // a column's first returns lower than the floor: no floor seen

/** After kGap invalid rows following a floor point: a drop when the floor
 *  there would still have returned within depth_max. */
void ColumnScan::finish(Column& k, size_t u) {
  if (k.f_row >= 0 && k.gap >= kGap && k.prev_row >= 0 &&
      floorExpected(at(k.f_row, u), at(k.prev_row, u), k.prev_row - k.f_row, kGap))
    mark(at(k.f_row, u));
}

void ColumnScan::step(Column& k, float& level, int8_t cls, double sd, size_t u, int v) {
  switch (cls) {
    case kNoReturn:
      k.gap += k.f_row >= 0;
      return;
    case kFloor:
      finish(k, u);
      k.prev_row = k.f_row;
      k.f_row = v;
      k.gap = k.lower = 0;
      level += kFollow * static_cast<float>(sd);
      return;
    case kLowerReturn:
      if (k.f_row >= 0) {
        if (++k.lower == kLower) mark(at(k.f_row, u));
      } else if (k.first_lows >= 0) {
        if (k.first_lows++ == 0) k.first_low = v;
        if (k.first_lows == kFirstLower) markBeforeView(at(k.first_low, u));
      }
      return;
    default:
      k = Column{};  // above the floor: an obstacle (its shadow is no drop)
      k.first_lows = -1;
      level = 0;
  }
}

void ColumnScan::pairInRow(std::vector<Column>& cols, const std::vector<int8_t>& cls) {
  const size_t w = cols.size();
  for (size_t u = 0; u < w; ++u) {
    Column& k = cols[u];
    if (cls[u] != kLowerReturn || k.f_row < 0 || k.lower != 1) continue;
    const bool left = u > 0 && cls[u - 1] == kLowerReturn;
    const bool right = u + 1 < w && cls[u + 1] == kLowerReturn;
    if (!left && !right) continue;
    mark(at(k.f_row, u));
    k.lower = kLower;
  }
}

}  // namespace

size_t markImageDropEdges(const Cloud& c, const Plane& plane, const PerceptionParams& p,
                          const Point3f& sensor_origin, LocalOccupancy& grid) {
  if (!c.organised()) return 0;
  ColumnScan s{c,    plane,
               p,    sensor_origin,
               grid, plane.signedDistance(sensor_origin.x, sensor_origin.y, sensor_origin.z)};
  if (s.so <= 0) return 0;
  // Row by row from the bottom (memory order), one state per column. Every
  // column: stepping over some (two per cell at depth_max) let a curb of the
  // randomised benchmark through.
  // Each row is classified in one vector pass, then the columns' states step.
  const size_t w = c.width;
  thread_local std::vector<Column> cols;
  thread_local std::vector<float> level;  // floor level over the plane, followed per column
  thread_local std::vector<double> sd;
  thread_local std::vector<int8_t> cls;
  cols.assign(w, Column{});
  level.assign(w, 0.f);
  sd.resize(w);
  cls.resize(w);
  const RowRule rule = s.rule();
  for (size_t v = c.height; v-- > 0;) {
    classifyRow(c.points.data() + v * w, w, level.data(), rule, sd.data(), cls.data());
    for (size_t u = 0; u < w; ++u) s.step(cols[u], level[u], cls[u], sd[u], u, static_cast<int>(v));
    if (p.depth_noise_std > 0) s.pairInRow(cols, cls);
  }
  for (size_t u = 0; u < w; ++u) s.finish(cols[u], u);
  return s.edges;
}

}  // namespace carenav::perception
