#include <carenav/common/distance_transform.h>
#include <carenav/common/errors.h>
#include <carenav/navigation/local_map.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace carenav::navigation {

// ---------------------------------------------------------------- memory

ObstacleMemory::ObstacleMemory(double resolution, double persistence, double radius)
    : res_(resolution), persistence_(persistence), radius_(radius) {}

namespace {

/** Cell index of a coordinate: floor(v / res), clamped to the 32 bits a
 *  cell key holds (a coordinate beyond 2^31 cells, ~1e8 m at 5 cm, lands in
 *  the border cell instead of overflowing); NaN gives the lowest cell (off
 *  every grid; the memories skip non-finite points). No conversion of an
 *  out-of-range double to an integer, no shift of a negative value. */
int32_t cellIndex(double v, double res) {
  const double c = std::floor(v / res);
  if (!(c > static_cast<double>(std::numeric_limits<int32_t>::min())))
    return std::numeric_limits<int32_t>::min();
  if (c >= static_cast<double>(std::numeric_limits<int32_t>::max()))
    return std::numeric_limits<int32_t>::max();
  return static_cast<int32_t>(c);
}

/** Two cell indices in one key: x in the high 32 bits, y in the low ones,
 *  each as its two's-complement bit pattern (unsigned arithmetic only). */
uint64_t packCell(double x, double y, double res) {
  return (static_cast<uint64_t>(static_cast<uint32_t>(cellIndex(x, res))) << 32) |
         static_cast<uint64_t>(static_cast<uint32_t>(cellIndex(y, res)));
}

int32_t signedHalf(uint64_t bits32) {
  const auto u = static_cast<uint32_t>(bits32);
  return u <= static_cast<uint32_t>(std::numeric_limits<int32_t>::max())
             ? static_cast<int32_t>(u)
             : static_cast<int32_t>(u - 0x80000000u) + std::numeric_limits<int32_t>::min();
}
int32_t keyX(uint64_t key) { return signedHalf(key >> 32); }
int32_t keyY(uint64_t key) { return signedHalf(key & 0xffffffffu); }

bool finite(const TPoint2D& p) { return std::isfinite(p.x) && std::isfinite(p.y); }

/** Walks the rays of `s` (its origin finite) from where the sensor sees to
 *  `short_of_hit` before each hit (or to the ray's end), at most `reach`
 *  from the origin, every `step` m; calls f(key, x, y) once per cell. */
template <class F>
void walkRays(const WorldScan& s, ScanCells& visited, double res, double reach, double short_of_hit,
              double step, const F& f) {
  const uint64_t o = packCell(s.origin.x, s.origin.y, res);
  visited.begin(keyX(o), keyY(o), static_cast<int64_t>(std::ceil(reach / res)));
  for (size_t i = 0; i < s.ends.size(); ++i) {
    if (!finite(s.ends[i])) continue;
    const double dx = s.ends[i].x - s.origin.x, dy = s.ends[i].y - s.origin.y;
    const double len = std::hypot(dx, dy);
    if (len <= 0) continue;
    const double stop = std::min((i < s.hit.size() && s.hit[i]) ? len - short_of_hit : len, reach);
    for (double d = std::max(s.range_min, 0.0); d < stop; d += step) {
      const double x = s.origin.x + dx * d / len, y = s.origin.y + dy * d / len;
      const uint64_t k = packCell(x, y, res);
      if (visited.first(keyX(k), keyY(k))) f(k, x, y);
    }
  }
}

}  // namespace

void ScanCells::begin(int64_t ox, int64_t oy, int64_t reach_cells) {
  ox_ = ox;
  oy_ = oy;
  half_ = reach_cells + 1 <= kMaxHalf ? std::max<int64_t>(reach_cells + 1, 0) : -1;
  if (half_ < 0) return;
  const auto side = static_cast<size_t>(2 * half_ + 1);
  if (stamp_.size() < side * side) stamp_.assign(side * side, 0);
  if (++now_ == 0) {  // the stamp wrapped: forget every old mark
    std::fill(stamp_.begin(), stamp_.end(), 0);
    now_ = 1;
  }
}

bool ScanCells::first(int64_t cx, int64_t cy) {
  const int64_t dx = cx - ox_, dy = cy - oy_;
  if (half_ < 0 || dx < -half_ || dx > half_ || dy < -half_ || dy > half_) return true;
  const auto side = static_cast<size_t>(2 * half_ + 1);
  uint32_t& s = stamp_[static_cast<size_t>(dy + half_) * side + static_cast<size_t>(dx + half_)];
  if (s == now_) return false;
  s = now_;
  return true;
}

uint64_t ObstacleMemory::key(double x, double y) const { return packCell(x, y, res_); }

void ObstacleMemory::add(const WorldScan& s, double t) {
  // Clear along each ray, from where the sensor sees to one cell before
  // the end point, then mark the hits. Non-finite points are no cells.
  if (!finite(s.origin)) return;
  view_.add(s);
  // No remembered cell lies farther from the sensor than `reach`: rays are
  // walked no farther (a long ray in a big room costs nothing then).
  double reach = 0;
  for (const auto& [k, seen] : cells_) {
    (void)seen;
    const double x = (static_cast<double>(keyX(k)) + 0.5) * res_;
    const double y = (static_cast<double>(keyY(k)) + 0.5) * res_;
    reach = std::max(reach, std::hypot(x - s.origin.x, y - s.origin.y) + res_);
  }
  // Each cell once per scan, up to a cell short of each hit.
  walkRays(s, visited_, res_, reach, res_, res_ * 0.5, [&](uint64_t k, double, double) {
    auto it = cells_.find(k);
    if (it != cells_.end() && it->second.t < t) cells_.erase(it);
  });
  // Hits whose cell lies beyond the radius would be dropped by the next
  // prune: they are not kept now (nor do they lengthen the next scan's rays).
  const TPoint2D centre = s.robot.value_or(s.origin);
  std::vector<std::pair<uint64_t, TPoint2D>> hits;
  for (size_t i = 0; i < s.ends.size(); ++i) {
    if (i >= s.hit.size() || !s.hit[i] || !finite(s.ends[i])) continue;
    const uint64_t k = key(s.ends[i].x, s.ends[i].y);
    const double x = (static_cast<double>(keyX(k)) + 0.5) * res_;
    const double y = (static_cast<double>(keyY(k)) + 0.5) * res_;
    if (std::hypot(x - centre.x, y - centre.y) > radius_) continue;
    hits.push_back({k, s.ends[i]});
  }
  // Each cell the scan hit holds the segment of this scan's hits in it
  // (an older scan's is replaced).
  std::stable_sort(hits.begin(), hits.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<TPoint2D> pts(hits.size());
  for (size_t i = 0; i < hits.size(); ++i) pts[i] = hits[i].second;
  for (size_t b = 0, e = 0; b < hits.size(); b = e) {
    while (e < hits.size() && hits[e].first == hits[b].first) ++e;
    const Segment g = fitAlongBearings(s.origin, pts, b, e);
    cells_[hits[b].first] = {t, static_cast<float>(g.a.x), static_cast<float>(g.a.y),
                             static_cast<float>(g.b.x), static_cast<float>(g.b.y)};
  }
}

Segment fitAlongBearings(const TPoint2D& o, const std::vector<TPoint2D>& pts, size_t begin,
                         size_t end) {
  if (end - begin < 2) return {pts[begin], pts[begin]};
  if (end - begin == 2) return {pts[begin], pts[begin + 1]};
  // Bearings about the first hit's (a cell spans a small angle), ranges.
  const double a0 = std::atan2(pts[begin].y - o.y, pts[begin].x - o.x);
  const double n = static_cast<double>(end - begin);
  double sa = 0, sr = 0, saa = 0, sar = 0, lo = 0, hi = 0;
  for (size_t i = begin; i < end; ++i) {
    const double a = std::remainder(std::atan2(pts[i].y - o.y, pts[i].x - o.x) - a0, 2 * M_PI);
    const double r = std::hypot(pts[i].x - o.x, pts[i].y - o.y);
    sa += a, sr += r, saa += a * a, sar += a * r;
    lo = std::min(lo, a), hi = std::max(hi, a);
  }
  // Range linear in bearing (a plane face), fitted by least squares (the
  // bearings are small, about the first hit's: one pass of sums is exact
  // enough); the ends at the extreme bearings.
  const double ma = sa / n, mr = sr / n;
  const double vaa = saa - n * ma * ma, var = sar - n * ma * mr;
  const double slope = vaa > 0 ? var / vaa : 0.0;
  auto at = [&](double a) {
    const double r = mr + slope * (a - ma);
    return TPoint2D{o.x + r * std::cos(a0 + a), o.y + r * std::sin(a0 + a)};
  };
  return {at(lo), at(hi)};
}

void ObstacleMemory::addPoints(const std::vector<TPoint2D>& points, double t) {
  for (const auto& p : points)
    if (finite(p)) {
      const auto x = static_cast<float>(p.x), y = static_cast<float>(p.y);
      cells_[key(p.x, p.y)] = {t, x, y, x, y};
    }
}

void ObstacleMemory::prune(double now, const TPoint2D& robot) {
  for (auto it = cells_.begin(); it != cells_.end();) {
    const double x = (static_cast<double>(keyX(it->first)) + 0.5) * res_;
    const double y = (static_cast<double>(keyY(it->first)) + 0.5) * res_;
    // Out of date only where the sensors looked last (no scan ever:
    // everywhere); out of every sensor's view it stays.
    const bool stale = now - it->second.t > persistence_ && (!view_.any || view_.covers(x, y));
    if (stale || std::hypot(x - robot.x, y - robot.y) > radius_)
      it = cells_.erase(it);
    else
      ++it;
  }
  view_.next = true;
}

int ObstacleMemory::View::bin(double x, double y) const {
  const double a = std::atan2(y - origin.y, x - origin.x);
  return std::clamp(static_cast<int>(std::floor((a + M_PI) / (2 * M_PI) * kBins)), 0, kBins - 1);
}

void ObstacleMemory::View::add(const WorldScan& s) {
  // The first scan after a prune starts the view afresh; the ones before
  // the next prune add to it.
  if (!any || next) bins.assign(kBins, 0);
  any = true;
  next = false;
  origin = s.origin;
  // Each ray's bearing, and the bins between neighbouring rays up to 3 deg
  // apart (a sparse scan still covers the arc between its rays).
  int prev = -1;
  for (const auto& e : s.ends) {
    if (!finite(e)) continue;
    const int b = bin(e.x, e.y);
    bins[static_cast<size_t>(b)] = 1;
    const int gap = prev < 0 ? 0 : (b - prev + kBins) % kBins;
    if (gap > 1 && gap <= 3)
      for (int k = 1; k < gap; ++k) bins[static_cast<size_t>((prev + k) % kBins)] = 1;
    prev = b;
  }
}

bool ObstacleMemory::View::covers(double x, double y) const {
  return bins[static_cast<size_t>(bin(x, y))] != 0;
}

std::vector<TPoint2D> ObstacleMemory::points() const {
  std::vector<TPoint2D> out;
  out.reserve(cells_.size());
  for (const auto& [k, c] : cells_) {
    (void)k;
    out.push_back({c.ax, c.ay});
    if (c.bx != c.ax || c.by != c.ay) out.push_back({c.bx, c.by});
  }
  return out;
}

// ---------------------------------------------------------------- free space

uint64_t FreeSpaceHistory::key(double x, double y) const { return packCell(x, y, res_); }

void FreeSpaceHistory::markFree(double x, double y, double t) {
  if (!std::isfinite(x) || !std::isfinite(y)) return;
  Stretch& c = cells_[key(x, y)];
  // A hit since, or a gap longer than a second between sightings, starts a
  // new stretch.
  if (c.hit >= c.last || t - c.last > 1.0) {
    c.first = t;
    c.hit_before = c.hit;
  }
  c.last = t;
}

void FreeSpaceHistory::markHit(double x, double y, double t) {
  if (!std::isfinite(x) || !std::isfinite(y)) return;
  Stretch& c = cells_[key(x, y)];
  if (c.hit < c.last) c.hit_since = t;  // seen free since its last hit: a new run of hits
  c.hit = std::max(c.hit, t);
}

void FreeSpaceHistory::addScan(const WorldScan& s, double t) {
  if (!finite(s.origin)) return;
  // Two cells short of a hit: the range noise must not free the obstacle's
  // own cell. Each cell once per scan.
  walkRays(s, visited_, res_, radius_, 2 * res_, res_,
           [&](uint64_t, double x, double y) { markFree(x, y, t); });
  for (size_t i = 0; i < s.ends.size(); ++i)
    if (i < s.hit.size() && s.hit[i] &&
        std::hypot(s.ends[i].x - s.origin.x, s.ends[i].y - s.origin.y) <= radius_)
      markHit(s.ends[i].x, s.ends[i].y, t);
}

bool FreeSpaceHistory::recentlyFree(double x, double y, double now, double window, double min_free,
                                    double static_memory) const {
  const auto it = cells_.find(key(x, y));
  if (it == cells_.end()) return false;
  const Stretch& c = it->second;
  return now - c.last <= window && c.last - c.first >= min_free &&
         (static_memory <= 0 || c.first - c.hit_before > static_memory);
}

bool FreeSpaceHistory::movedIn(double x, double y, double now, double window, double min_free,
                               double static_memory) const {
  if (!recentlyFree(x, y, now, window, min_free, static_memory)) return false;
  const double since = cells_.find(key(x, y))->second.first;
  int around = 0;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      if (!dx && !dy) continue;
      const double nx = x + dx * res_, ny = y + dy * res_;
      if (recentlyFree(nx, ny, now, window, min_free, static_memory))
        ++around;
      else if (staticHit(nx, ny, now, window, since))
        return false;
    }
  return around >= 7;
}

bool FreeSpaceHistory::staticHit(double x, double y, double now, double window,
                                 double since) const {
  const auto it = cells_.find(key(x, y));
  if (it == cells_.end()) return false;
  const Stretch& c = it->second;
  return now - c.hit <= window && c.hit >= c.last && c.hit_since <= since;
}

void FreeSpaceHistory::prune(double now, double keep, double keep_hits) {
  for (auto it = cells_.begin(); it != cells_.end();)
    if (now - it->second.last > keep && now - it->second.hit > keep_hits)
      it = cells_.erase(it);
    else
      ++it;
}

// ---------------------------------------------------------------- seen free

void SeenFree::addScan(const WorldScan& s, const Sight& stamp) {
  if (!finite(s.origin)) return;
  // A cell short of a hit: the range noise must not free the obstacle's cell.
  walkRays(s, visited_, res_, radius_, res_, res_ / 2,
           [&](uint64_t k, double, double) { cells_[k] = stamp; });
}

void SeenFree::prune(const TPoint2D& robot, const std::function<bool(const Sight&)>& keep) {
  const double r = radius_ / res_ + 1;
  const double cx = robot.x / res_ - 0.5, cy = robot.y / res_ - 0.5;
  for (auto it = cells_.begin(); it != cells_.end();)
    if (std::hypot(keyX(it->first) - cx, keyY(it->first) - cy) > r || !keep(it->second))
      it = cells_.erase(it);
    else
      ++it;
}

const SeenFree::Sight* SeenFree::at(double x, double y) const {
  if (!std::isfinite(x) || !std::isfinite(y)) return nullptr;
  const auto it = cells_.find(packCell(x, y, res_));
  return it == cells_.end() ? nullptr : &it->second;
}

// ---------------------------------------------------------------- footprint

namespace {

/** Squared distance from (x, y) to the segment a-b (no square root: the
 *  footprint queries take the least of several first). */
double segmentDistance2(const Point2& a, const Point2& b, double x, double y) {
  const double vx = b.x - a.x, vy = b.y - a.y;
  const double l2 = vx * vx + vy * vy;
  double u = l2 > 0 ? ((x - a.x) * vx + (y - a.y) * vy) / l2 : 0;
  u = std::clamp(u, 0.0, 1.0);
  const double ex = a.x + u * vx - x, ey = a.y + u * vy - y;
  return ex * ex + ey * ey;
}

double segmentDistance(const Point2& a, const Point2& b, double x, double y) {
  return std::sqrt(segmentDistance2(a, b, x, y));
}

}  // namespace

Footprint::Footprint(const std::vector<Point2>& poly, double spacing) : polygon(poly) {
  if (poly.size() < 3) throw InputError("footprint: needs at least 3 corners");
  double area = 0;
  for (size_t i = 0; i < poly.size(); ++i) {
    const auto& a = poly[i];
    const auto& b = poly[(i + 1) % poly.size()];
    area += a.x * b.y - b.x * a.y;
  }
  if (std::abs(area) < 1e-6) throw InputError("footprint: the polygon has no area");
  circumscribed = 0;
  inscribed = std::numeric_limits<double>::infinity();
  double xmin = 1e9, xmax = -1e9, ymin = 1e9, ymax = -1e9;
  for (size_t i = 0; i < poly.size(); ++i) {
    const auto& a = poly[i];
    const auto& b = poly[(i + 1) % poly.size()];
    circumscribed = std::max(circumscribed, std::hypot(a.x, a.y));
    inscribed = std::min(inscribed, segmentDistance(a, b, 0, 0));
    xmin = std::min(xmin, a.x), xmax = std::max(xmax, a.x);
    ymin = std::min(ymin, a.y), ymax = std::max(ymax, a.y);
    const double len = std::hypot(b.x - a.x, b.y - a.y);
    const int n = std::max(1, static_cast<int>(std::ceil(len / spacing)));
    for (int k = 0; k < n; ++k)
      boundary.push_back({a.x + (b.x - a.x) * k / n, a.y + (b.y - a.y) * k / n});
  }
  if (!contains(0, 0)) inscribed = 0;  // origin outside its own footprint
  // Interior samples tile by tile (4 x 4 samples), each tile a group.
  const double tile = 4 * spacing;
  for (double tx = xmin; tx < xmax; tx += tile)
    for (double ty = ymin; ty < ymax; ty += tile) {
      const size_t begin = interior.size();
      for (double x = tx + spacing / 2; x < std::min(xmax, tx + tile); x += spacing)
        for (double y = ty + spacing / 2; y < std::min(ymax, ty + tile); y += spacing)
          if (contains(x, y)) interior.push_back({x, y});
      if (interior.size() > begin) interior_groups.push_back({{}, 0, begin, interior.size()});
    }
  // The outline in runs of 6 samples.
  for (size_t b = 0; b < boundary.size(); b += 6)
    boundary_groups.push_back({{}, 0, b, std::min(boundary.size(), b + 6)});
  auto enclose = [](std::vector<Group>& groups, const std::vector<TPoint2D>& pts) {
    for (auto& g : groups) {
      for (size_t i = g.begin; i < g.end; ++i) g.centre.x += pts[i].x, g.centre.y += pts[i].y;
      g.centre.x /= static_cast<double>(g.end - g.begin);
      g.centre.y /= static_cast<double>(g.end - g.begin);
      for (size_t i = g.begin; i < g.end; ++i)
        g.radius = std::max(g.radius, std::hypot(pts[i].x - g.centre.x, pts[i].y - g.centre.y));
    }
  };
  enclose(boundary_groups, boundary);
  enclose(interior_groups, interior);
}

bool Footprint::contains(double x, double y) const {
  bool in = false;  // crossing number
  for (size_t i = 0, j = polygon.size() - 1; i < polygon.size(); j = i++) {
    const auto& a = polygon[i];
    const auto& b = polygon[j];
    if ((a.y > y) != (b.y > y) && x < (b.x - a.x) * (y - a.y) / (b.y - a.y) + a.x) in = !in;
  }
  return in;
}

// ---------------------------------------------------------------- cost map

LocalCostmap::LocalCostmap(const LocalMapParams& p, const Footprint& footprint)
    : res_(p.resolution),
      decay_(p.cost_decay),
      contact_(std::max(p.resolution * 0.5, p.footprint_padding + p.resolution * 0.5)),
      padding_(p.footprint_padding),
      fp_(footprint) {
  n_ = std::max(8, static_cast<int>(std::ceil(p.local_size / res_)));
  far_ = n_ * res_ * 2;
  dist_.assign(static_cast<size_t>(n_) * n_, static_cast<float>(far_));
  mdist_ = dist_;
  occ_.assign(dist_.size(), 0);
  px_.assign(dist_.size(), 0.f);
  py_.assign(dist_.size(), 0.f);
  qx_ = px_;
  qy_ = py_;
  count_.assign(dist_.size(), 0);
}

// Clamped like the memory's keys: a point far off the grid is just outside.
int LocalCostmap::cellX(double x) const { return cellIndex(x - x0_, res_); }
int LocalCostmap::cellY(double y) const { return cellIndex(y - y0_, res_); }

void LocalCostmap::build(const TPoint2D& c, const std::vector<TPoint2D>& obstacles,
                         const mrpt::maps::COccupancyGridMap2D* static_map,
                         double static_occupied) {
  build(c, obstacles, {}, static_map, static_occupied);
}

void LocalCostmap::setPoint(size_t i, const TPoint2D& o) {
  occ_[i] = 1;
  count_[i] = 1;
  px_[i] = qx_[i] = static_cast<float>(o.x);
  py_[i] = qy_[i] = static_cast<float>(o.y);
}

void LocalCostmap::addToCell(size_t i, const TPoint2D& o) {
  if (occ_[i] != 1) return setPoint(i, o);
  const auto x = static_cast<float>(o.x), y = static_cast<float>(o.y);
  if (++count_[i] == 2) {  // a segment from the first to this one
    qx_[i] = x, qy_[i] = y;
    return;
  }
  if (count_[i] == 3) {  // the box of the segment's ends
    const float ax = px_[i], ay = py_[i], bx = qx_[i], by = qy_[i];
    px_[i] = std::min(ax, bx), py_[i] = std::min(ay, by);
    qx_[i] = std::max(ax, bx), qy_[i] = std::max(ay, by);
  }
  px_[i] = std::min(px_[i], x), py_[i] = std::min(py_[i], y);
  qx_[i] = std::max(qx_[i], x), qy_[i] = std::max(qy_[i], y);
  count_[i] = 3;
}

void LocalCostmap::build(const TPoint2D& c, const std::vector<TPoint2D>& obstacles,
                         const std::vector<TPoint2D>& cell_points,
                         const mrpt::maps::COccupancyGridMap2D* static_map,
                         double static_occupied) {
  // Snap the origin to the cell grid so that cells do not shift between builds.
  x0_ = std::floor(c.x / res_) * res_ - (n_ / 2) * res_;
  y0_ = std::floor(c.y / res_) * res_ - (n_ / 2) * res_;
  std::vector<uint8_t> free(static_cast<size_t>(n_) * n_, 1);
  std::fill(occ_.begin(), occ_.end(), 0);
  std::fill(mdist_.begin(), mdist_.end(), static_cast<float>(far_));
  obstacle_cells_ = 0;
  auto mark = [&](int ix, int iy) {
    if (ix < 0 || iy < 0 || ix >= n_ || iy >= n_) return;
    const size_t i = static_cast<size_t>(iy) * n_ + ix;
    if (free[i]) ++obstacle_cells_;
    free[i] = 0;
    if (!occ_[i]) occ_[i] = 2;
  };
  // A cell's points: one is a point, two a segment (the memory's segment of
  // a scan's hits), more their box; a cell point stands alone.
  for (const auto& o : obstacles) {
    const int ix = cellX(o.x), iy = cellY(o.y);
    if (ix < 0 || iy < 0 || ix >= n_ || iy >= n_) continue;
    mark(ix, iy);
    addToCell(static_cast<size_t>(iy) * n_ + ix, o);
  }
  for (const auto& o : cell_points) {
    const int ix = cellX(o.x), iy = cellY(o.y);
    if (ix < 0 || iy < 0 || ix >= n_ || iy >= n_) continue;
    mark(ix, iy);
    setPoint(static_cast<size_t>(iy) * n_ + ix, o);
  }
  if (static_map) {
    for (int iy = 0; iy < n_; ++iy)
      for (int ix = 0; ix < n_; ++ix) {
        const double x = x0_ + (ix + 0.5) * res_, y = y0_ + (iy + 0.5) * res_;
        if (x < static_map->getXMin() || x >= static_map->getXMax() || y < static_map->getYMin() ||
            y >= static_map->getYMax())
          continue;
        if (1.0 - static_map->getPos(x, y) > static_occupied) mark(ix, iy);
      }
  }
  const auto d2 = squaredDistanceTransform<float>(free, n_, n_);
  dist_.resize(d2.size());
  for (size_t i = 0; i < d2.size(); ++i)
    dist_[i] =
        std::isinf(d2[i]) ? static_cast<float>(far_) : static_cast<float>(std::sqrt(d2[i]) * res_);
}

void LocalCostmap::addMoving(const std::vector<TPoint2D>& moving, double inflation) {
  moving_cells_ = 0;
  if (moving.empty()) return;
  std::vector<uint8_t> free(static_cast<size_t>(n_) * n_, 1);
  for (const auto& o : moving) {
    const int ix = cellX(o.x), iy = cellY(o.y);
    if (ix < 0 || iy < 0 || ix >= n_ || iy >= n_) continue;
    uint8_t& f = free[static_cast<size_t>(iy) * n_ + ix];
    moving_cells_ += f;
    f = 0;
  }
  if (!moving_cells_) return;
  const auto d2 = squaredDistanceTransform<float>(free, n_, n_);
  for (size_t i = 0; i < d2.size(); ++i) {
    if (std::isinf(d2[i])) continue;
    const double d = std::max(0.0, std::sqrt(d2[i]) * res_ - inflation);
    mdist_[i] = static_cast<float>(d);
    if (d < dist_[i]) dist_[i] = static_cast<float>(d);
  }
}

bool LocalCostmap::inside(double x, double y) const {
  const int ix = cellX(x), iy = cellY(y);
  return ix >= 0 && iy >= 0 && ix < n_ && iy < n_;
}

double LocalCostmap::distance(double x, double y) const {
  const int ix = cellX(x), iy = cellY(y);
  if (ix < 0 || iy < 0 || ix >= n_ || iy >= n_) return -1;
  return dist_[static_cast<size_t>(iy) * n_ + ix];
}

int LocalCostmap::cellCost(double x, double y) const {
  const double d = distance(x, y);
  if (d < 0) return 100;
  if (d <= 0) return 100;
  if (d >= decay_) return 0;
  return static_cast<int>(std::lround(99.0 * (1.0 - d / decay_)));
}

FootprintCheck LocalCostmap::check(const TPose2D& pose) const {
  return check(pose, std::numeric_limits<double>::infinity());
}

FootprintCheck LocalCostmap::check(const TPose2D& pose, double cap) const {
  return check(pose, cap, std::cos(pose.phi), std::sin(pose.phi));
}

double LocalCostmap::outlineDistanceOf(double wx, double wy, const TPose2D& pose, double c,
                                       double s) const {
  const double dx = wx - pose.x, dy = wy - pose.y;
  const double rx = c * dx + s * dy, ry = -s * dx + c * dy;  // robot frame
  double d2 = std::numeric_limits<double>::infinity();
  const auto& poly = fp_.polygon;
  for (size_t i = 0; i < poly.size(); ++i)
    d2 = std::min(d2, segmentDistance2(poly[i], poly[(i + 1) % poly.size()], rx, ry));
  const double d = std::sqrt(d2);
  return fp_.contains(rx, ry) ? -d : d;
}

namespace {

/** Segments (p, q) and (r, s) cross. */
bool segmentsCross(double px, double py, double qx, double qy, double rx, double ry, double sx,
                   double sy) {
  auto side = [](double ax, double ay, double bx, double by, double cx, double cy) {
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
  };
  const double d1 = side(px, py, qx, qy, rx, ry), d2 = side(px, py, qx, qy, sx, sy);
  const double d3 = side(rx, ry, sx, sy, px, py), d4 = side(rx, ry, sx, sy, qx, qy);
  return ((d1 > 0) != (d2 > 0)) && ((d3 > 0) != (d4 > 0));
}

}  // namespace

double LocalCostmap::shapeDistanceOf(size_t i, const TPose2D& pose, double c, double s) const {
  return count_[i] >= 3 ? boxDistanceOf(i, pose, c, s) : segmentDistanceOf(i, pose, c, s);
}

double LocalCostmap::segmentDistanceOf(size_t i, const TPose2D& pose, double c, double s) const {
  const double ax = px_[i], ay = py_[i], bx = qx_[i], by = qy_[i];
  if (ax == bx && ay == by) return outlineDistanceOf(ax, ay, pose, c, s);
  double d = std::min(outlineDistanceOf(ax, ay, pose, c, s), outlineDistanceOf(bx, by, pose, c, s));
  if (d < 0) return d;
  // Apart, two shapes are nearest at a vertex of one of them; crossing the
  // outline is contact.
  const auto& poly = fp_.polygon;
  for (size_t k = 0; k < poly.size(); ++k) {
    const auto& v = poly[k];
    const auto& w = poly[(k + 1) % poly.size()];
    const double vx = pose.x + c * v.x - s * v.y, vy = pose.y + s * v.x + c * v.y;
    const double wx = pose.x + c * w.x - s * w.y, wy = pose.y + s * w.x + c * w.y;
    if (segmentsCross(ax, ay, bx, by, vx, vy, wx, wy)) return 0;
    d = std::min(d, segmentDistance({ax, ay}, {bx, by}, vx, vy));
  }
  return d;
}

double LocalCostmap::boxDistanceOf(size_t i, const TPose2D& pose, double c, double s) const {
  const double x0 = px_[i], y0 = py_[i], x1 = qx_[i], y1 = qy_[i];
  double d = std::numeric_limits<double>::infinity();
  for (const double x : {x0, x1})
    for (const double y : {y0, y1}) d = std::min(d, outlineDistanceOf(x, y, pose, c, s));
  if (d < 0) return d;
  // The outline's vertices (world frame) against the box: two convex
  // shapes apart are nearest at a vertex of one of them.
  for (const auto& v : fp_.polygon) {
    const double wx = pose.x + c * v.x - s * v.y, wy = pose.y + s * v.x + c * v.y;
    const double ex = std::max({x0 - wx, 0.0, wx - x1}), ey = std::max({y0 - wy, 0.0, wy - y1});
    if (ex == 0 && ey == 0) return 0;  // a vertex in the box
    d = std::min(d, std::sqrt(ex * ex + ey * ey));
  }
  return d;
}

double LocalCostmap::outlineDistanceNear(double wx, double wy, const TPose2D& pose, double c,
                                         double s, int reach) const {
  const int cx = cellX(wx), cy = cellY(wy);
  double best = std::numeric_limits<double>::infinity();
  for (int iy = std::max(0, cy - reach); iy <= std::min(n_ - 1, cy + reach); ++iy)
    for (int ix = std::max(0, cx - reach); ix <= std::min(n_ - 1, cx + reach); ++ix) {
      const size_t i = static_cast<size_t>(iy) * n_ + ix;
      if (!occ_[i]) continue;
      if (occ_[i] == 1) {
        best = std::min(best, shapeDistanceOf(i, pose, c, s));
        continue;
      }
      // A static map's cell: its centre less half its diagonal (a square).
      const double ox = x0_ + (ix + 0.5) * res_, oy = y0_ + (iy + 0.5) * res_;
      best = std::min(best, outlineDistanceOf(ox, oy, pose, c, s) - res_ * M_SQRT1_2);
    }
  return best;
}

bool LocalCostmap::sampleContact(double wx, double wy, const TPose2D& pose, double c, double s,
                                 double& clearance) const {
  const int ix = cellX(wx), iy = cellY(wy);
  const size_t i = static_cast<size_t>(iy) * n_ + ix;
  const double d = dist_[i];
  if (mdist_[i] < contact_) return true;  // a moving obstacle's grown region
  if (d > padding_ + 2 * res_) {
    clearance = std::min(clearance, d - res_ * 0.5);
    return false;
  }
  // Near: the exact points, within the cells that can hold the nearest one.
  const int reach = static_cast<int>(std::ceil(d / res_ + 1.5));
  const double e = outlineDistanceNear(wx, wy, pose, c, s, reach);
  if (e < padding_) return true;
  clearance = std::min({clearance, e, mdist_[i] - res_ * 0.5});
  return false;
}

bool LocalCostmap::interiorContact(double wx, double wy, const TPose2D& pose, double c,
                                   double s) const {
  if (distance(wx, wy) >= res_ * 0.75) return false;
  // An obstacle cell under the sample: a static or moving one is inside; a
  // sensed point only if it is (or touches the outline).
  const size_t k = static_cast<size_t>(cellY(wy)) * n_ + cellX(wx);
  return occ_[k] != 1 || mdist_[k] < res_ * 0.75 || shapeDistanceOf(k, pose, c, s) < padding_;
}

double LocalCostmap::outlineClearance(const TPose2D& pose) const {
  const double c = std::cos(pose.phi), s = std::sin(pose.phi);
  double best = std::numeric_limits<double>::infinity();
  for (const auto& b : fp_.boundary) {
    const double wx = pose.x + c * b.x - s * b.y, wy = pose.y + s * b.x + c * b.y;
    if (!inside(wx, wy)) return 0;
    const size_t i = static_cast<size_t>(cellY(wy)) * n_ + cellX(wx);
    if (mdist_[i] <= 0) return 0;
    best = std::min(best, static_cast<double>(mdist_[i]));
    const double d = dist_[i];
    if (d > padding_ + 2 * res_) {
      best = std::min(best, d - res_ * 0.5);
      continue;
    }
    best = std::min(
        best, outlineDistanceNear(wx, wy, pose, c, s, static_cast<int>(std::ceil(d / res_ + 1.5))));
  }
  // Obstacles under the footprint: a sensed point inside it gives its
  // (negative) depth; a static or moving cell, 0.
  for (const auto& q : fp_.interior) {
    const double wx = pose.x + c * q.x - s * q.y, wy = pose.y + s * q.x + c * q.y;
    if (distance(wx, wy) >= res_ * 0.75) continue;
    const size_t k = static_cast<size_t>(cellY(wy)) * n_ + cellX(wx);
    if (occ_[k] != 1 || mdist_[k] < res_ * 0.75) return 0;
    best = std::min(best, shapeDistanceOf(k, pose, c, s));
  }
  return best;
}

FootprintCheck LocalCostmap::check(const TPose2D& pose, double cap, double c, double s) const {
  FootprintCheck r;
  const double dc = distance(pose.x, pose.y);
  if (dc < 0) {
    r.outside = true;
    return r;
  }
  // Every point of the footprint is within `circumscribed` of the origin:
  // far from everything, a bound is enough.
  const double bound = dc - fp_.circumscribed - res_ - contact_;
  if (bound >= cap) {
    r.clearance = cap;
    // Still make sure the footprint lies on the grid.
    if (!inside(pose.x + fp_.circumscribed, pose.y + fp_.circumscribed) ||
        !inside(pose.x - fp_.circumscribed, pose.y - fp_.circumscribed))
      r.outside = true;
    return r;
  }
  double clearance = std::numeric_limits<double>::infinity();
  // A group's samples lie within its radius of its centre, and the distance
  // of two cells differs by at most the distance of their centres (within
  // 1.5 cells of the points'): a group whose centre is farther than that
  // from every obstacle, beyond what the samples are tested against, is
  // skipped (the answer is the same as sample by sample).
  const double slack = 1.5 * res_;
  // (Only where the whole footprint is on the grid: a sample off it must be seen.)
  const bool on_grid = inside(pose.x + fp_.circumscribed, pose.y + fp_.circumscribed) &&
                       inside(pose.x - fp_.circumscribed, pose.y - fp_.circumscribed);
  const double need_b = std::max(cap + res_ * 0.5, padding_ + 2 * res_);
  for (const auto& g : fp_.boundary_groups) {
    const double gd = distance(pose.x + c * g.centre.x - s * g.centre.y,
                               pose.y + s * g.centre.x + c * g.centre.y);
    if (on_grid && gd - g.radius - slack >= need_b) continue;
    for (size_t i = g.begin; i < g.end; ++i) {
      const auto& b = fp_.boundary[i];
      const double wx = pose.x + c * b.x - s * b.y, wy = pose.y + s * b.x + c * b.y;
      if (!inside(wx, wy)) {
        r.outside = true;
        return r;
      }
      // Touching: the nearest obstacle (the sensed point itself, not its
      // cell) within the padding of the outline, or inside it.
      if (sampleContact(wx, wy, pose, c, s, clearance)) {
        r.collision = true;
        r.clearance = 0;
        return r;
      }
    }
  }
  // An obstacle wholly inside the footprint is far from the outline: look
  // inside when the origin is close enough to anything for that to happen.
  if (dc < fp_.circumscribed + res_) {
    for (const auto& g : fp_.interior_groups) {
      const double gd = distance(pose.x + c * g.centre.x - s * g.centre.y,
                                 pose.y + s * g.centre.x + c * g.centre.y);
      if (on_grid && gd - g.radius - slack >= res_ * 0.75) continue;
      for (size_t i = g.begin; i < g.end; ++i) {
        const auto& q = fp_.interior[i];
        if (interiorContact(pose.x + c * q.x - s * q.y, pose.y + s * q.x + c * q.y, pose, c, s)) {
          r.collision = true;
          r.clearance = 0;
          return r;
        }
      }
    }
  }
  r.clearance = std::min(clearance, cap);
  return r;
}

}  // namespace carenav::navigation
