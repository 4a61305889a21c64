#include <carenav/common/errors.h>
#include <carenav/navigation/global_planner.h>
#include <carenav/navigation/local_map.h>

#include <cmath>
#include <queue>
#include <sstream>

namespace carenav::navigation {

GlobalPlanner::GlobalPlanner(const mrpt::maps::COccupancyGridMap2D& map, double robot_radius,
                             const NavigationParams& p, double free_threshold)
    : map_(map),
      nx_(static_cast<int>(map.getSizeX())),
      ny_(static_cast<int>(map.getSizeY())),
      res_(map.getResolution()),
      radius_(robot_radius + p.plan_clearance),
      influence_(robot_radius + p.plan_clearance + 0.5),
      weight_(p.plan_cost_weight) {
  free_.resize(static_cast<size_t>(nx_) * ny_);
  for (int y = 0; y < ny_; ++y)
    for (int x = 0; x < nx_; ++x)
      free_[static_cast<size_t>(y) * nx_ + x] = map.getCell(x, y) > free_threshold ? 1 : 0;
  const auto d2 = squaredDistanceTransform(free_, nx_, ny_);
  dist_.resize(d2.size());
  for (size_t i = 0; i < d2.size(); ++i)
    dist_[i] = std::isinf(d2[i]) ? 1e6f : static_cast<float>(std::sqrt(d2[i]) * res_);
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

bool GlobalPlanner::cellPassable(int ix, int iy) const {
  if (ix < 0 || iy < 0 || ix >= nx_ || iy >= ny_) return false;
  const size_t i = static_cast<size_t>(iy) * nx_ + ix;
  return free_[i] && dist_[i] > radius_;
}

bool GlobalPlanner::isPassable(double x, double y) const {
  return cellPassable(map_.x2idx(x), map_.y2idx(y));
}

bool GlobalPlanner::lineOfSight(int x0, int y0, int x1, int y1) const {
  // Samples every half cell along the segment.
  const double len = std::hypot(x1 - x0, y1 - y0);
  const int n = std::max(1, static_cast<int>(std::ceil(len * 2)));
  for (int k = 0; k <= n; ++k) {
    const int x = static_cast<int>(std::lround(x0 + (x1 - x0) * double(k) / n));
    const int y = static_cast<int>(std::lround(y0 + (y1 - y0) * double(k) / n));
    if (!cellPassable(x, y)) return false;
  }
  return true;
}

bool GlobalPlanner::polylineClear(const std::vector<TPoint2D>& pts, double skip) const {
  if (pts.empty()) return true;
  const TPoint2D s0 = pts.front();
  for (size_t i = 0; i + 1 < pts.size(); ++i) {
    const double len = std::hypot(pts[i + 1].x - pts[i].x, pts[i + 1].y - pts[i].y);
    const int n = std::max(1, static_cast<int>(std::ceil(len / (res_ / 2))));
    for (int k = 0; k <= n; ++k) {
      const double x = pts[i].x + (pts[i + 1].x - pts[i].x) * k / n;
      const double y = pts[i].y + (pts[i + 1].y - pts[i].y) * k / n;
      if (std::hypot(x - s0.x, y - s0.y) < skip) continue;
      if (!isPassable(x, y)) return false;
    }
  }
  return true;
}

std::optional<Route> GlobalPlanner::plan(const TPoint2D& s, const TPoint2D& g) const {
  auto cellOf = [&](const TPoint2D& p, const char* what) {
    const int ix = map_.x2idx(p.x), iy = map_.y2idx(p.y);
    std::ostringstream m;
    m << what << " (" << p.x << ", " << p.y << ")";
    if (ix < 0 || iy < 0 || ix >= nx_ || iy >= ny_) {
      m << " is outside the map";
      throw InputError(m.str());
    }
    if (!free_[static_cast<size_t>(iy) * nx_ + ix]) {
      m << " is not on free space of the map (occupied or unknown)";
      throw InputError(m.str());
    }
    return std::pair<int, int>{ix, iy};
  };
  const auto [sx, sy] = cellOf(s, "start");
  const auto [gx, gy] = cellOf(g, "goal");
  // Start and goal may lie closer to a wall than the robot's radius (a robot
  // parked against a wall): cells within the radius of them that are free
  // are passable, at a high cost, so the route can leave and reach them.
  const double near2 = (radius_ / res_ + 1) * (radius_ / res_ + 1);
  auto passable = [&](int x, int y) {
    if (cellPassable(x, y)) return true;
    if (x < 0 || y < 0 || x >= nx_ || y >= ny_) return false;
    if (!free_[static_cast<size_t>(y) * nx_ + x]) return false;
    const double ds = double(x - sx) * (x - sx) + double(y - sy) * (y - sy);
    const double dg = double(x - gx) * (x - gx) + double(y - gy) * (y - gy);
    return ds <= near2 || dg <= near2;
  };
  const size_t n = static_cast<size_t>(nx_) * ny_;
  std::vector<float> cost(n, std::numeric_limits<float>::infinity());
  std::vector<int32_t> parent(n, -1);
  std::vector<uint8_t> closed(n, 0);
  using Item = std::pair<float, int32_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
  auto idx = [&](int x, int y) { return static_cast<int32_t>(y * nx_ + x); };
  auto h = [&](int x, int y) { return static_cast<float>(std::hypot(x - gx, y - gy) * res_); };
  cost[idx(sx, sy)] = 0;
  open.push({h(sx, sy), idx(sx, sy)});
  const int dx[8] = {1, -1, 0, 0, 1, 1, -1, -1}, dy[8] = {0, 0, 1, -1, 1, -1, 1, -1};
  bool found = false;
  while (!open.empty()) {
    const auto [f, i] = open.top();
    open.pop();
    if (closed[i]) continue;
    closed[i] = 1;
    const int x = i % nx_, y = i / nx_;
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
      const double step = (k >= 4 ? M_SQRT2 : 1.0) * res_;
      const double d = dist_[j];
      double penalty = d < influence_ ? weight_ * (influence_ - d) / influence_ : 0;
      if (!cellPassable(ax, ay)) penalty += 10;  // inside the radius near start/goal
      const float c = cost[i] + static_cast<float>(step * (1 + penalty));
      if (c < cost[j]) {
        cost[j] = c;
        parent[j] = i;
        open.push({c + h(ax, ay), j});
      }
    }
  }
  if (!found) return std::nullopt;
  Route r;
  std::vector<std::pair<int, int>> cells;
  for (int32_t i = idx(gx, gy); i >= 0; i = parent[i]) cells.emplace_back(i % nx_, i / nx_);
  std::reverse(cells.begin(), cells.end());
  for (const auto& [x, y] : cells) r.cells.push_back({map_.idx2x(x), map_.idx2y(y)});
  // Corners: from each anchor, the farthest cell still in line of sight.
  size_t anchor = 0;
  while (anchor + 1 < cells.size()) {
    size_t next = anchor + 1;
    while (next + 1 < cells.size() && lineOfSight(cells[anchor].first, cells[anchor].second,
                                                  cells[next + 1].first, cells[next + 1].second))
      ++next;
    r.waypoints.push_back(r.cells[next]);
    anchor = next;
  }
  if (r.waypoints.empty()) r.waypoints.push_back(g);
  r.waypoints.back() = g;
  TPoint2D prev = s;
  for (const auto& w : r.waypoints) {
    r.length += std::hypot(w.x - prev.x, w.y - prev.y);
    prev = w;
  }
  return r;
}

}  // namespace carenav::navigation
