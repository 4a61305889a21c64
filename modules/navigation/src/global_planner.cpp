#include <carenav/common/distance_transform.h>
#include <carenav/common/errors.h>
#include <carenav/navigation/global_planner.h>
#include <carenav/navigation/local_map.h>
#include <carenav/navigation/polyline.h>

#include "footprint_route.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <sstream>

namespace carenav::navigation {

namespace {
/** p_free above which a cell of the static map is free (GlobalPlanner's default). */
constexpr double kFreeThreshold = 0.65;
}  // namespace

GlobalPlanner::GlobalPlanner(const mrpt::maps::COccupancyGridMap2D& map, double robot_radius,
                             const NavigationParams& p, double free_threshold)
    : map_(map),
      nx_(static_cast<int>(map.getSizeX())),
      ny_(static_cast<int>(map.getSizeY())),
      res_(map.getResolution()),
      radius_(robot_radius + p.plan_clearance),
      floor_(robot_radius + std::min(p.plan_clearance, p.footprint_padding)),
      influence_(robot_radius + p.plan_clearance + 0.5),
      weight_(p.plan_cost_weight),
      passage_margin_(p.passage_margin),
      passage_approach_(p.passage_approach),
      footprint_on_(p.route_footprint),
      footprint_margin_(p.route_footprint_margin),
      footprint_nodes_(p.route_footprint_nodes) {
  free_.resize(static_cast<size_t>(nx_) * ny_);
  for (int y = 0; y < ny_; ++y)
    for (int x = 0; x < nx_; ++x)
      free_[static_cast<size_t>(y) * nx_ + x] = map.getCell(x, y) > free_threshold ? 1 : 0;
  const auto d2 = squaredDistanceTransform<float>(free_, nx_, ny_);
  dist_.resize(d2.size());
  for (size_t i = 0; i < d2.size(); ++i)
    dist_[i] = std::isinf(d2[i]) ? 1e6f : static_cast<float>(std::sqrt(d2[i]) * res_);
}

void GlobalPlanner::setFootprint(const std::vector<Point2>& polygon) { polygon_ = polygon; }

FootprintRoute GlobalPlanner::footprintRoute(double margin) const {
  const RouteGrid grid{nx_,    ny_,    res_,       map_.getXMin(), map_.getYMin(),
                       &free_, &dist_, influence_, weight_};
  return FootprintRoute(grid, polygon_, margin, footprint_nodes_);
}

bool GlobalPlanner::footprintClear(const std::vector<TPoint2D>& pts, double skip) const {
  if (polygon_.empty()) return polylineClear(pts, skip, floor_);
  // Half the planning margin: a route is not dropped for a centimetre.
  const FootprintRoute fr = footprintRoute(footprint_margin_ / 2);
  return fr.drivable(pts, skip);
}

bool GlobalPlanner::isFree(double x, double y) const {
  const int ix = map_.x2idx(x), iy = map_.y2idx(y);
  if (ix < 0 || iy < 0 || ix >= nx_ || iy >= ny_) return false;
  return free_[static_cast<size_t>(iy) * nx_ + ix] != 0;
}

double GlobalPlanner::clearance(double x, double y) const {
  const int ix = map_.x2idx(x), iy = map_.y2idx(y);
  if (ix < 0 || iy < 0 || ix >= nx_ || iy >= ny_) return 0;
  return dist_[static_cast<size_t>(iy) * nx_ + ix];
}

bool GlobalPlanner::cellPassable(int ix, int iy, double radius) const {
  if (ix < 0 || iy < 0 || ix >= nx_ || iy >= ny_) return false;
  const size_t i = static_cast<size_t>(iy) * nx_ + ix;
  return free_[i] && dist_[i] > radius;
}

bool GlobalPlanner::isPassable(double x, double y, double radius) const {
  return cellPassable(map_.x2idx(x), map_.y2idx(y), radius < 0 ? radius_ : radius);
}

bool GlobalPlanner::lineOfSight(int x0, int y0, int x1, int y1, double radius) const {
  // Samples every half cell along the segment.
  const double len = std::hypot(x1 - x0, y1 - y0);
  const int n = std::max(1, static_cast<int>(std::ceil(len * 2)));
  for (int k = 0; k <= n; ++k) {
    const int x = static_cast<int>(std::lround(x0 + (x1 - x0) * double(k) / n));
    const int y = static_cast<int>(std::lround(y0 + (y1 - y0) * double(k) / n));
    if (!cellPassable(x, y, radius)) return false;
  }
  return true;
}

namespace {

/** Whether `ok(x, y)` holds at every point of the polyline `pts`, sampled
 *  every `step` metres along each segment, but for those within `skip` of
 *  its start. */
template <typename Ok>
bool everySample(const std::vector<TPoint2D>& pts, double skip, double step, Ok ok) {
  if (pts.empty()) return true;
  const TPoint2D s0 = pts.front();
  for (size_t i = 0; i + 1 < pts.size(); ++i) {
    const double len = std::hypot(pts[i + 1].x - pts[i].x, pts[i + 1].y - pts[i].y);
    const int n = std::max(1, static_cast<int>(std::ceil(len / step)));
    for (int k = 0; k <= n; ++k) {
      const double x = pts[i].x + (pts[i + 1].x - pts[i].x) * k / n;
      const double y = pts[i].y + (pts[i + 1].y - pts[i].y) * k / n;
      if (std::hypot(x - s0.x, y - s0.y) >= skip && !ok(x, y)) return false;
    }
  }
  return true;
}

}  // namespace

bool GlobalPlanner::polylineClear(const std::vector<TPoint2D>& pts, double skip,
                                  double radius) const {
  return everySample(pts, skip, res_ / 2,
                     [&](double x, double y) { return isPassable(x, y, radius); });
}

bool GlobalPlanner::polylineClearOf(const GlobalPlanner& before, const std::vector<TPoint2D>& pts,
                                    double skip, double radius) const {
  return everySample(pts, skip, res_ / 2, [&](double x, double y) {
    if (!before.isFree(x, y)) return true;  // the map's own obstacle: not new
    return isPassable(x, y, std::min(radius, before.clearance(x, y) - 1e-6));
  });
}

namespace {

using Cell = std::pair<int, int>;

/** What the A* search of a route needs of the planner's grid. */
struct SearchGrid {
  int nx, ny;
  double res, influence, weight;
  const std::vector<float>& dist;
};

/** The cell of a start or goal point; refuses points off the map or not on free space. */
Cell startOrGoalCell(const mrpt::maps::COccupancyGridMap2D& map, int nx, int ny,
                     const std::vector<uint8_t>& free, const TPoint2D& p, const char* what) {
  std::ostringstream m;
  m << what << " (" << p.x << ", " << p.y << ")";
  // Bounds in metres first: MRPT's x2idx converts to int unchecked (UBSan:
  // a 1e300 m start was undefined behaviour before it was called outside).
  const bool on_map =
      p.x >= map.getXMin() && p.x < map.getXMax() && p.y >= map.getYMin() && p.y < map.getYMax();
  const int ix = on_map ? map.x2idx(p.x) : -1, iy = on_map ? map.y2idx(p.y) : -1;
  if (ix < 0 || iy < 0 || ix >= nx || iy >= ny) {
    m << " is outside the map";
    throw InputError(m.str());
  }
  if (!free[static_cast<size_t>(iy) * nx + ix]) {
    m << " is not on free space of the map (occupied or unknown)";
    throw InputError(m.str());
  }
  return Cell{ix, iy};
}

/** A* over 8-connected cells, cost = length x (1 + clearance penalty); the
 *  cells from start to goal, or nullopt when the goal cannot be reached.
 *  `passable(x, y)` admits a cell, `clear(x, y)` tells whether it is outside
 *  the robot's radius of any obstacle (else it costs more). */
template <class Passable, class Clear>
std::optional<std::vector<Cell>> aStarCells(const SearchGrid& g, Cell start, Cell goal,
                                            const Passable& passable, const Clear& clear) {
  const int sx = start.first, sy = start.second, gx = goal.first, gy = goal.second;
  const int nx = g.nx;
  const size_t n = static_cast<size_t>(g.nx) * g.ny;
  std::vector<float> cost(n, std::numeric_limits<float>::infinity());
  std::vector<int32_t> parent(n, -1);
  std::vector<uint8_t> closed(n, 0);
  using Item = std::pair<float, int32_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
  auto idx = [&](int x, int y) { return static_cast<int32_t>(y * nx + x); };
  auto h = [&](int x, int y) { return static_cast<float>(std::hypot(x - gx, y - gy) * g.res); };
  cost[idx(sx, sy)] = 0;
  open.push({h(sx, sy), idx(sx, sy)});
  const int dx[8] = {1, -1, 0, 0, 1, 1, -1, -1}, dy[8] = {0, 0, 1, -1, 1, -1, 1, -1};
  bool found = false;
  while (!open.empty()) {
    const auto [f, i] = open.top();
    open.pop();
    if (closed[i]) continue;
    closed[i] = 1;
    const int x = i % nx, y = i / nx;
    if (x == gx && y == gy) {
      found = true;
      break;
    }
    for (int k = 0; k < 8; ++k) {
      const int ax = x + dx[k], ay = y + dy[k];
      if (!passable(ax, ay)) continue;
      const int32_t j = idx(ax, ay);
      if (closed[j]) continue;
      // Diagonal steps must not cut a blocked corner.
      if (k >= 4 && (!passable(x + dx[k], y) || !passable(x, y + dy[k]))) continue;
      const double step = (k >= 4 ? M_SQRT2 : 1.0) * g.res;
      const double d = g.dist[j];
      double penalty = d < g.influence ? g.weight * (g.influence - d) / g.influence : 0;
      if (!clear(ax, ay)) penalty += 10;  // inside the radius near start/goal
      const float c = cost[i] + static_cast<float>(step * (1 + penalty));
      if (c < cost[j]) {
        cost[j] = c;
        parent[j] = i;
        open.push({c + h(ax, ay), j});
      }
    }
  }
  if (!found) return std::nullopt;
  std::vector<Cell> cells;
  for (int32_t i = idx(gx, gy); i >= 0; i = parent[i]) cells.emplace_back(i % nx, i / nx);
  std::reverse(cells.begin(), cells.end());
  return cells;
}

/** A narrow passage of the path, crossed straight: a waypoint before it, its
 *  throat and one after it. */
struct Passage {
  size_t centre;
  TPoint2D before, mid, after;
  TPoint2D axis;  ///< unit vector across the passage, in the direction of travel
};

/** Of 16 directions, the one along which the clearance around `c` rises most
 *  on both sides (a saddle of the distance field); with that clearance. */
std::pair<TPoint2D, double> crossingAxis(const GlobalPlanner& planner, const TPoint2D& c) {
  double best_gain = -1e9, ux = 0, uy = 0;
  for (int k = 0; k < 16; ++k) {
    const double th = M_PI * k / 16;
    const double dx = std::cos(th), dy = std::sin(th);
    const double gain = std::min(planner.clearance(c.x + dx * 0.4, c.y + dy * 0.4),
                                 planner.clearance(c.x - dx * 0.4, c.y - dy * 0.4));
    if (gain > best_gain) best_gain = gain, ux = dx, uy = dy;
  }
  return {TPoint2D{ux, uy}, best_gain};
}

// Narrow passages (doorways): runs of path cells closer than
// passage_clearance to anything not free. Each is crossed straight: a
// waypoint before it, its throat (the narrowest cell of the run) and one
// after it, along the axis across the passage ([Conceicao16]: intermediate
// goals at doorways, reached with in-place turns).
std::vector<Passage> findPassages(const GlobalPlanner& planner, const std::vector<Cell>& cells,
                                  const std::vector<TPoint2D>& pts, const std::vector<float>& dist,
                                  int nx, double narrow, double radius, double approach) {
  std::vector<Passage> passages;
  auto clear = [&](size_t k) {
    return dist[static_cast<size_t>(cells[k].second) * nx + cells[k].first];
  };
  for (size_t i = 0; i < cells.size();) {
    if (clear(i) >= narrow) {
      ++i;
      continue;
    }
    size_t j = i, best = i;
    while (j < cells.size() && clear(j) < narrow) {
      if (clear(j) < clear(best)) best = j;  // the throat
      ++j;
    }
    // Only real passages (obstacles on both sides), not a path along one wall:
    // the clearance grows on both sides along the crossing axis.
    const TPoint2D c = pts[best];
    const TPoint2D a = pts[i > 0 ? i - 1 : i], b = pts[std::min(j, cells.size() - 1)];
    const double ax = b.x - a.x, ay = b.y - a.y;
    auto [u, best_gain] = crossingAxis(planner, c);
    if (u.x * ax + u.y * ay < 0) u.x = -u.x, u.y = -u.y;  // in the direction of travel
    const double d = approach;
    const TPoint2D pre{c.x - u.x * d, c.y - u.y * d}, post{c.x + u.x * d, c.y + u.y * d};
    if (best_gain > planner.clearance(c.x, c.y) && planner.isPassable(pre.x, pre.y, radius) &&
        planner.isPassable(post.x, post.y, radius))
      passages.push_back({best, pre, c, post, u});
    i = j;
  }
  return passages;
}

// Corners: from each anchor, the farthest cell still in line of sight;
// passages split the path and add their three points. A passage's point
// before it is left out when the path reaches it no earlier than the
// previous waypoint (the start, or the previous passage's throat) and that
// waypoint lies before the throat: the route would go back to it, and a
// robot nearer to the throat than that turned round to reach it; the route
// follows the path into the throat instead. The point after a passage is
// left out when the next passage's approach begins no later.
template <class LineOfSight>
void addWaypoints(const std::vector<Cell>& cells, const std::vector<Passage>& passages,
                  double approach, const LineOfSight& lineOfSight, Route& r) {
  auto simplify = [&](size_t from, size_t to) {  // cells (from, to], `to` included
    size_t anchor = from;
    while (anchor < to) {
      size_t next = anchor + 1;
      while (next < to && lineOfSight(cells[anchor].first, cells[anchor].second,
                                      cells[next + 1].first, cells[next + 1].second))
        ++next;
      r.waypoints.push_back(r.cells[next]);
      anchor = next;
    }
  };
  auto near = [&](size_t i, const Passage& ps) {
    return std::hypot(r.cells[i].x - ps.mid.x, r.cells[i].y - ps.mid.y) < approach;
  };
  // Each passage's approach: the last cell before it and the first after it
  // at least `approach` from its throat.
  std::vector<size_t> upto(passages.size()), after(passages.size());
  for (size_t k = 0; k < passages.size(); ++k) {
    upto[k] = after[k] = passages[k].centre;
    while (upto[k] > 0 && near(upto[k], passages[k])) --upto[k];
    while (after[k] + 1 < cells.size() && near(after[k], passages[k])) ++after[k];
  }
  size_t from = 0;
  for (size_t k = 0; k < passages.size(); ++k) {
    const Passage& ps = passages[k];
    const TPoint2D prev = r.waypoints.empty() ? r.cells.front() : r.waypoints.back();
    const bool before_throat =
        (prev.x - ps.mid.x) * ps.axis.x + (prev.y - ps.mid.y) * ps.axis.y < 0;
    if (upto[k] > from || !before_throat) {
      if (upto[k] > from) simplify(from, upto[k]);
      r.waypoints.push_back(ps.before);
      r.waypoints.push_back(ps.mid);
    } else if (ps.centre > from) {
      simplify(from, ps.centre);  // ends at the throat's cell
    }
    from = std::max(from, ps.centre);
    if (k + 1 == passages.size() || after[k] < upto[k + 1]) {
      r.waypoints.push_back(ps.after);
      from = after[k];
    }
  }
  if (from + 1 < cells.size()) simplify(from, cells.size() - 1);
}

/** Cells within this many cells of a start or goal cell, squared: passable
 *  when free, however near an obstacle (a robot parked against a wall). */
double nearCells2(double radius, double res) { return (radius / res + 1) * (radius / res + 1); }

}  // namespace

std::optional<Route> GlobalPlanner::plan(const TPoint2D& s, const TPoint2D& g) const {
  const Cell s_cell = startOrGoalCell(map_, nx_, ny_, free_, s, "start");
  const Cell g_cell = startOrGoalCell(map_, nx_, ny_, free_, g, "goal");
  const int sx = s_cell.first, sy = s_cell.second, gx = g_cell.first, gy = g_cell.second;
  auto r = planWith(sx, sy, gx, gy, s, g, radius_);
  if (!r && floor_ < radius_) {
    // No way keeps plan_clearance: the widest way's clearance (just below
    // its bottleneck, so that the bottleneck's cells pass), at least floor_.
    const double widest = widestWay(sx, sy, gx, gy, floor_);
    if (widest <= floor_) return std::nullopt;
    r = planWith(sx, sy, gx, gy, s, g, std::max(floor_, std::min(radius_, widest - 1e-4)));
    if (!r) r = planWith(sx, sy, gx, gy, s, g, floor_);
  }
  if (!r) return r;
  return drivableRoute(std::move(*r), s, g, sx, sy, gx, gy);
}

Route GlobalPlanner::drivableRoute(Route r, const TPoint2D& s, const TPoint2D& g, int sx, int sy,
                                   int gx, int gy) const {
  if (polygon_.empty() || !footprint_on_) return r;
  const FootprintRoute fr = footprintRoute(footprint_margin_);
  // Not checked near start and goal: a robot parked against a wall, a goal
  // beside one (as the A* search admits them).
  const double skip = fr.turnRadius();
  std::vector<TPoint2D> pts{s};
  pts.insert(pts.end(), r.waypoints.begin(), r.waypoints.end());
  if (fr.drivable(pts, skip)) return r;
  const auto way = fr.search({sx, sy}, {gx, gy}, skip);
  if (!way) return r;  // none: the circle's route (the recoveries' maneuvers remain)
  Route out;
  out.cells = way->cells;
  out.waypoints = way->vertices;
  out.waypoints.back() = g;
  out.radius = std::min(r.radius, floor_);
  out.footprint = true;
  TPoint2D prev = s;
  for (const auto& w : out.waypoints) {
    out.length += std::hypot(w.x - prev.x, w.y - prev.y);
    prev = w;
  }
  return out;
}

double GlobalPlanner::widestWay(int sx, int sy, int gx, int gy, double floor) const {
  // Cells near start and goal count as clear (planWith admits them at any
  // radius >= floor, their disc growing with it).
  const double near2 = nearCells2(floor, res_);
  auto value = [&](int x, int y) -> double {
    if (x < 0 || y < 0 || x >= nx_ || y >= ny_) return -1;
    const size_t i = static_cast<size_t>(y) * nx_ + x;
    if (!free_[i]) return -1;
    const double ds = double(x - sx) * (x - sx) + double(y - sy) * (y - sy);
    const double dg = double(x - gx) * (x - gx) + double(y - gy) * (y - gy);
    if (ds <= near2 || dg <= near2) return 1e9;
    return dist_[i] > floor ? dist_[i] : -1;
  };
  // Maximin Dijkstra: the best bottleneck known per cell, widest first.
  std::vector<float> best(static_cast<size_t>(nx_) * ny_, -1.f);
  using Item = std::pair<float, int32_t>;
  std::priority_queue<Item> open;
  const auto idx = [&](int x, int y) { return static_cast<int32_t>(y * nx_ + x); };
  best[idx(sx, sy)] = 1e9f;
  open.push({1e9f, idx(sx, sy)});
  const int dx[8] = {1, -1, 0, 0, 1, 1, -1, -1}, dy[8] = {0, 0, 1, -1, 1, -1, 1, -1};
  while (!open.empty()) {
    const auto [b, i] = open.top();
    open.pop();
    if (b < best[i]) continue;
    const int x = i % nx_, y = i / nx_;
    if (x == gx && y == gy) return std::min<double>(b, 1e6);
    for (int k = 0; k < 8; ++k) {
      double v = std::min<double>(b, value(x + dx[k], y + dy[k]));
      // a diagonal step needs both cells beside it (as in the A* search)
      if (k >= 4) v = std::min({v, value(x + dx[k], y), value(x, y + dy[k])});
      const int32_t j = idx(x + dx[k], y + dy[k]);
      if (v <= floor || v <= best[j]) continue;
      best[j] = static_cast<float>(v);
      open.push({best[j], j});
    }
  }
  return 0;
}

std::optional<Route> GlobalPlanner::planWith(int sx, int sy, int gx, int gy, const TPoint2D& s,
                                             const TPoint2D& g, double radius) const {
  // Start and goal may lie closer to a wall than the robot's radius (a robot
  // parked against a wall): cells within the radius of them that are free
  // are passable, at a high cost, so the route can leave and reach them.
  const double near2 = nearCells2(radius, res_);
  auto passable = [&](int x, int y) {
    if (cellPassable(x, y, radius)) return true;
    if (x < 0 || y < 0 || x >= nx_ || y >= ny_) return false;
    if (!free_[static_cast<size_t>(y) * nx_ + x]) return false;
    const double ds = double(x - sx) * (x - sx) + double(y - sy) * (y - sy);
    const double dg = double(x - gx) * (x - gx) + double(y - gy) * (y - gy);
    return ds <= near2 || dg <= near2;
  };
  auto clear = [&](int x, int y) { return cellPassable(x, y, radius); };
  const SearchGrid grid{nx_, ny_, res_, influence_, weight_, dist_};
  const auto cells = aStarCells(grid, {sx, sy}, {gx, gy}, passable, clear);
  if (!cells) return std::nullopt;
  Route r;
  r.radius = radius;
  for (const auto& [x, y] : *cells) r.cells.push_back({map_.idx2x(x), map_.idx2y(y)});
  const auto passages = findPassages(*this, *cells, r.cells, dist_, nx_, radius + passage_margin_,
                                     radius, passage_approach_);
  auto sight = [&](int x0, int y0, int x1, int y1) { return lineOfSight(x0, y0, x1, y1, radius); };
  addWaypoints(*cells, passages, passage_approach_, sight, r);
  if (r.waypoints.empty()) r.waypoints.push_back(g);
  r.waypoints.back() = g;
  TPoint2D prev = s;
  for (const auto& w : r.waypoints) {
    r.length += std::hypot(w.x - prev.x, w.y - prev.y);
    prev = w;
  }
  return r;
}

namespace {

/** The route from the robot at `from` on: to its nearest point on the
 *  route, then the route's vertices after it (the part behind the robot,
 *  and a segment from the robot back to a corner it has passed, are not
 *  its way ahead). */
std::vector<TPoint2D> routeAhead(const Route& route, const TPoint2D& from) {
  std::vector<TPoint2D> line;
  if (!route.cells.empty()) line.push_back(route.cells.front());
  line.insert(line.end(), route.waypoints.begin(), route.waypoints.end());
  std::vector<TPoint2D> ahead{from};
  if (line.size() < 2) {
    ahead.insert(ahead.end(), line.begin(), line.end());
    return ahead;
  }
  const PolylinePoint at = nearestOnPolyline(line, from.x, from.y);
  const TPoint2D& a = line[at.segment];
  const TPoint2D& b = line[at.segment + 1];
  ahead.push_back({a.x + at.u * (b.x - a.x), a.y + at.u * (b.y - a.y)});
  ahead.insert(ahead.end(), line.begin() + static_cast<long>(at.segment) + 1, line.end());
  return ahead;
}

/** Whether `route` (none: blocked) is blocked on `marked` (`map` with what
 *  was seen marked) for the robot at `from`. A footprint route is checked
 *  with the footprint; a circle's with the circle at the clearance it
 *  keeps, all of it (replan_new_only off), or ahead of the robot where the
 *  marks leave less than the map did. */
bool routeBlocked(const GlobalPlanner& marked, const mrpt::maps::COccupancyGridMap2D& map,
                  const std::optional<Route>& route, const TPoint2D& from, double robot_radius,
                  double skip, const NavigationParams& p, bool footprint_route) {
  if (!route) return true;
  std::vector<TPoint2D> ahead{from};
  if (footprint_route || p.replan_new_only)
    ahead = routeAhead(*route, from);
  else
    ahead.insert(ahead.end(), route->waypoints.begin(), route->waypoints.end());
  if (route->footprint) return !marked.footprintClear(ahead, skip);
  if (!p.replan_new_only) return !marked.polylineClear(ahead, skip, route->radius);
  return !marked.polylineClearOf(GlobalPlanner(map, robot_radius, p), ahead, skip, route->radius);
}

}  // namespace

std::optional<Route> replanAroundSeen(const mrpt::maps::COccupancyGridMap2D& map,
                                      const std::vector<TPoint2D>& seen, const TPoint2D& from,
                                      const TPoint2D& goal, const std::optional<Route>& route,
                                      double robot_radius, double skip, const NavigationParams& p,
                                      const std::vector<TPoint2D>& keep_out,
                                      const std::vector<Point2>& footprint) {
  mrpt::maps::COccupancyGridMap2D marked = map;
  auto mark = [&](const TPoint2D& q) {
    if (q.x > marked.getXMin() && q.x < marked.getXMax() && q.y > marked.getYMin() &&
        q.y < marked.getYMax())
      marked.setPos(q.x, q.y, 0.0f);
  };
  // With route_footprint or replan_new_only: a hit on or beside what the
  // map shows is that obstacle seen again: its mark would only grow it by
  // a cell (a route through a gap the map leaves just room for would be
  // blocked by its own posts).
  const auto nx = static_cast<int>(map.getSizeX()), ny = static_cast<int>(map.getSizeY());
  auto mapped = [&](const TPoint2D& q) {
    const int ix = map.x2idx(q.x), iy = map.y2idx(q.y);
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int x = ix + dx, y = iy + dy;
        if (x >= 0 && y >= 0 && x < nx && y < ny && map.getCell(x, y) <= kFreeThreshold)
          return true;
      }
    return false;
  };
  const bool footprint_route = p.route_footprint && !footprint.empty();
  const bool seen_again = footprint_route || p.replan_new_only;
  for (const auto& q : seen)
    if (!seen_again || !mapped(q)) mark(q);
  for (const auto& q : keep_out) mark(q);
  GlobalPlanner gp(marked, robot_radius, p);
  gp.setFootprint(footprint);
  if (routeBlocked(gp, map, route, from, robot_radius, skip, p, footprint_route) &&
      gp.isFree(from.x, from.y) && gp.isFree(goal.x, goal.y))
    return gp.plan(from, goal);
  return std::nullopt;
}

bool RouteReplanner::due(size_t k, bool people) const {
  const auto every =
      static_cast<size_t>(std::max(1.0, std::round((people || detour_ ? 0.5 : 2.0) * rate_)));
  return k > 0 && k % every == 0;
}

bool RouteReplanner::recovered(const TPoint2D& at) {
  if (avoid_after_ <= 0) return false;
  auto it = std::find_if(places_.begin(), places_.end(), [&](const Place& q) {
    return std::hypot(q.at.x - at.x, q.at.y - at.y) <= 2 * avoid_radius_;
  });
  if (it == places_.end()) it = places_.insert(places_.end(), Place{at, 0});
  if (++it->recoveries == avoid_after_) fresh_ = true;
  return it->recoveries == avoid_after_;
}

void RouteReplanner::newGoal() {
  places_.clear();
  fresh_ = false;
}

std::vector<TPoint2D> RouteReplanner::avoided() const {
  std::vector<TPoint2D> out;
  for (const auto& q : places_)
    if (avoid_after_ > 0 && q.recoveries >= avoid_after_) out.push_back(q.at);
  return out;
}

std::vector<TPoint2D> RouteReplanner::keepOut(const TPoint2D& from, const TPoint2D& goal,
                                              double resolution) const {
  std::vector<TPoint2D> out;
  const double r = avoid_radius_, step = std::max(resolution / 2, 0.01);
  for (const auto& c : avoided()) {
    if (std::hypot(from.x - c.x, from.y - c.y) <= r + resolution ||
        std::hypot(goal.x - c.x, goal.y - c.y) <= r + resolution)
      continue;
    for (double dy = -r; dy <= r + 1e-9; dy += step)
      for (double dx = -r; dx <= r + 1e-9; dx += step)
        if (std::hypot(dx, dy) <= r) out.push_back({c.x + dx, c.y + dy});
  }
  return out;
}

std::optional<Route> RouteReplanner::step(bool people, const mrpt::maps::COccupancyGridMap2D& map,
                                          const std::vector<TPoint2D>& seen, const TPoint2D& from,
                                          const TPoint2D& goal, const std::optional<Route>& route,
                                          double robot_radius, double skip,
                                          const NavigationParams& p,
                                          const std::vector<Point2>& footprint) {
  // the person is gone, or a place has just become one to avoid: plan anew
  const bool fresh = (detour_ && !people) || fresh_;
  fresh_ = false;
  auto r = replanAroundSeen(map, seen, from, goal, fresh ? std::nullopt : route, robot_radius, skip,
                            p, keepOut(from, goal, map.getResolution()), footprint);
  if (r) detour_ = people;
  return r;
}

}  // namespace carenav::navigation
