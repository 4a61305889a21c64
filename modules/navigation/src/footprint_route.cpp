// Routes a rectangular robot can drive (footprint_route.h).
#include "footprint_route.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <unordered_map>

namespace carenav::navigation {

namespace {

/** Headings of the search: 7.5 deg apart, so that a gap at any angle is
 *  met within 3.75 deg of square (a 0.51 x 0.43 m robot then needs 3 cm
 *  more than its width, not 11 cm as at 16 headings). */
constexpr int kHeadings = 48;
/** rad, the most a check on the spot turns between two samples. */
constexpr double kTurnSample = 5.0 * M_PI / 180;

double heading(int h) { return 2 * M_PI * h / kHeadings; }
/** Weight of the distance to go (weighted A*: a way found sooner, at most
 *  this many times the cheapest; the maneuvers' search uses the same). */
constexpr float kGreed = 2.0f;

}  // namespace

FootprintRoute::FootprintRoute(const RouteGrid& g, const std::vector<Point2>& polygon,
                               double margin, int max_expansions)
    : g_(g), fp_(polygon, g.res), margin_(margin), max_expansions_(max_expansions) {}

double FootprintRoute::clearance(double x, double y) const {
  const double fx = (x - g_.x_min) / g_.res - 0.5, fy = (y - g_.y_min) / g_.res - 0.5;
  const int ix = static_cast<int>(std::floor(fx)), iy = static_cast<int>(std::floor(fy));
  const double tx = fx - ix, ty = fy - iy;
  auto at = [&](int x, int y) -> double {
    return inside(x, y) ? (*g_.dist)[idx(x, y)] : 0.0;  // off the grid: not free
  };
  const double d = (1 - ty) * ((1 - tx) * at(ix, iy) + tx * at(ix + 1, iy)) +
                   ty * ((1 - tx) * at(ix, iy + 1) + tx * at(ix + 1, iy + 1));
  return d - g_.res / 2;
}

bool FootprintRoute::fits(double x, double y, double th) const {
  // Far from everything any heading fits (the interpolation errs by less
  // than a cell).
  if (clearance(x, y) >= fp_.circumscribed + margin_ + g_.res) return true;
  const double c = std::cos(th), s = std::sin(th);
  auto groupClear = [&](const std::vector<Footprint::Group>& groups,
                        const std::vector<TPoint2D>& pts) {
    for (const auto& gr : groups) {
      const double gx = x + c * gr.centre.x - s * gr.centre.y;
      const double gy = y + s * gr.centre.x + c * gr.centre.y;
      if (clearance(gx, gy) >= gr.radius + margin_ + g_.res) continue;
      for (size_t i = gr.begin; i < gr.end; ++i) {
        const double px = x + c * pts[i].x - s * pts[i].y;
        const double py = y + s * pts[i].x + c * pts[i].y;
        if (clearance(px, py) < margin_) return false;
      }
    }
    return true;
  };
  return groupClear(fp_.boundary_groups, fp_.boundary) &&
         groupClear(fp_.interior_groups, fp_.interior);
}

bool FootprintRoute::turnFits(double x, double y, double a, double b) const {
  const double d = std::remainder(b - a, 2 * M_PI);
  const int n = std::max(1, static_cast<int>(std::ceil(std::abs(d) / kTurnSample)));
  for (int k = 1; k <= n; ++k)
    if (!fits(x, y, a + d * k / n)) return false;
  return true;
}

bool FootprintRoute::drivable(const std::vector<TPoint2D>& pts, double skip) const {
  if (pts.size() < 2) return true;
  const TPoint2D& s = pts.front();
  const TPoint2D& e = pts.back();
  auto checked = [&](double x, double y) {
    return std::hypot(x - s.x, y - s.y) > skip && std::hypot(x - e.x, y - e.y) > skip;
  };
  double prev = std::numeric_limits<double>::quiet_NaN();
  for (size_t i = 0; i + 1 < pts.size(); ++i) {
    const double dx = pts[i + 1].x - pts[i].x, dy = pts[i + 1].y - pts[i].y;
    const double len = std::hypot(dx, dy);
    if (len < 1e-9) continue;
    const double th = std::atan2(dy, dx);
    if (!std::isnan(prev) && checked(pts[i].x, pts[i].y) && !turnFits(pts[i].x, pts[i].y, prev, th))
      return false;
    const int n = std::max(1, static_cast<int>(std::ceil(len / (g_.res / 2))));
    for (int k = 1; k <= n; ++k) {
      const double x = pts[i].x + dx * k / n, y = pts[i].y + dy * k / n;
      if (checked(x, y) && !fits(x, y, th)) return false;
    }
    prev = th;
  }
  return true;
}

std::vector<float> FootprintRoute::distancesTo(Cell goal, Cell start, double skip) const {
  const float inf = std::numeric_limits<float>::infinity();
  std::vector<float> d(static_cast<size_t>(g_.nx) * g_.ny, inf);
  const double need = fp_.inscribed + margin_;
  auto near = [&](int x, int y, Cell c) {
    return std::hypot(x - c.first, y - c.second) * g_.res <= skip;
  };
  auto passable = [&](int x, int y) {
    if (!inside(x, y) || !(*g_.free)[idx(x, y)]) return false;
    return (*g_.dist)[idx(x, y)] >= need || near(x, y, goal) || near(x, y, start);
  };
  using Item = std::pair<float, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
  d[idx(goal.first, goal.second)] = 0;
  open.push({0.f, static_cast<int>(idx(goal.first, goal.second))});
  while (!open.empty()) {
    const auto [dc, i] = open.top();
    open.pop();
    if (dc > d[static_cast<size_t>(i)]) continue;
    const int x = i % g_.nx, y = i / g_.nx;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if ((dx == 0 && dy == 0) || !passable(x + dx, y + dy)) continue;
        const float nd = dc + static_cast<float>(g_.res * ((dx && dy) ? M_SQRT2 : 1.0));
        const size_t j = idx(x + dx, y + dy);
        if (nd < d[j]) d[j] = nd, open.push({nd, static_cast<int>(j)});
      }
  }
  return d;
}

std::optional<FootprintRoute::Way> FootprintRoute::search(Cell start, Cell goal,
                                                          double skip) const {
  if (!inside(start.first, start.second) || !inside(goal.first, goal.second)) return std::nullopt;
  const std::vector<float> togo = distancesTo(goal, start, skip);
  if (!std::isfinite(togo[idx(start.first, start.second)])) return std::nullopt;
  const TPoint2D s0{cx(start.first), cy(start.second)}, g0{cx(goal.first), cy(goal.second)};
  auto unchecked = [&](double x, double y) {
    return std::hypot(x - s0.x, y - s0.y) <= skip || std::hypot(x - g0.x, y - g0.y) <= skip;
  };
  auto cellOf = [&](double x, double y) -> long {
    const int ix = static_cast<int>(std::floor((x - g_.x_min) / g_.res));
    const int iy = static_cast<int>(std::floor((y - g_.y_min) / g_.res));
    return inside(ix, iy) ? static_cast<long>(idx(ix, iy)) : -1;
  };
  const double step = 2 * g_.res;  // m, one straight primitive
  // Nodes: continuous poses, at most one kept per (cell, heading) [Dolgov10].
  std::vector<Node> nodes;
  std::unordered_map<int64_t, float> best;
  using Item = std::pair<float, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
  auto push = [&](double x, double y, int h, float gk, int parent) {
    const long c = cellOf(x, y);
    if (c < 0 || !std::isfinite(togo[static_cast<size_t>(c)])) return;
    const int64_t k = static_cast<int64_t>(c) * kHeadings + h;
    const auto it = best.find(k);
    if (it != best.end() && it->second <= gk) return;
    best[k] = gk;
    nodes.push_back({x, y, h, gk, parent});
    open.push({gk + kGreed * togo[static_cast<size_t>(c)], static_cast<int>(nodes.size() - 1)});
  };
  for (int h = 0; h < kHeadings; ++h) push(s0.x, s0.y, h, 0.f, -1);
  const double turn_cost = fp_.circumscribed * 2 * M_PI / kHeadings;  // the corner's travel
  int expanded = 0, found = -1;
  while (!open.empty() && expanded < max_expansions_) {
    const int i = open.top().second;
    open.pop();
    const Node n = nodes[static_cast<size_t>(i)];
    const long c = cellOf(n.x, n.y);
    if (n.g > best[static_cast<int64_t>(c) * kHeadings + n.h]) continue;  // a cheaper way here
    if (std::hypot(n.x - g0.x, n.y - g0.y) <= step) {
      found = i;
      break;
    }
    ++expanded;
    // A straight step along the heading.
    const double th = heading(n.h);
    const double x = n.x + step * std::cos(th), y = n.y + step * std::sin(th);
    const long c2 = cellOf(x, y);
    if (c2 >= 0 && (*g_.free)[static_cast<size_t>(c2)] &&
        (unchecked(x, y) || (fits(x, y, th) && fits((n.x + x) / 2, (n.y + y) / 2, th)))) {
      const double d = (*g_.dist)[static_cast<size_t>(c2)];
      const double pen = d < g_.influence ? g_.weight * (g_.influence - d) / g_.influence : 0;
      push(x, y, n.h, n.g + static_cast<float>(step * (1 + pen)), i);
    }
    // A turn on the spot to a neighbouring heading.
    for (const int dh : {1, kHeadings - 1}) {
      const int h2 = (n.h + dh) % kHeadings;
      if (unchecked(n.x, n.y) || turnFits(n.x, n.y, th, heading(h2)))
        push(n.x, n.y, h2, n.g + static_cast<float>(turn_cost), i);
    }
  }
  if (found < 0) return std::nullopt;
  return wayTo(nodes, found, s0, g0);
}

FootprintRoute::Way FootprintRoute::wayTo(const std::vector<Node>& nodes, int found,
                                          const TPoint2D& start, const TPoint2D& goal) const {
  // Back from the goal: the poses, and a vertex where the robot turns.
  std::vector<int> chain;
  for (int k = found; k >= 0; k = nodes[static_cast<size_t>(k)].parent) chain.push_back(k);
  std::reverse(chain.begin(), chain.end());
  Way w;
  std::vector<TPoint2D> turns{start};
  for (size_t q = 0; q < chain.size(); ++q) {
    const Node& n = nodes[static_cast<size_t>(chain[q])];
    const TPoint2D p{n.x, n.y};
    if (w.cells.empty() || w.cells.back().x != p.x || w.cells.back().y != p.y) w.cells.push_back(p);
    const bool turning = q + 1 < chain.size() && nodes[static_cast<size_t>(chain[q + 1])].h != n.h;
    if (q > 0 && turning && (turns.back().x != p.x || turns.back().y != p.y)) turns.push_back(p);
  }
  w.cells.push_back(goal);
  turns.push_back(goal);
  w.vertices = simplify(turns);
  w.vertices.erase(w.vertices.begin());  // the start
  return w;
}

std::vector<TPoint2D> FootprintRoute::simplify(const std::vector<TPoint2D>& turns) const {
  // A vertex is dropped when the segment that skips it passes where the
  // robot turns freely (any heading fits, with margin), so that neither
  // the shortcut nor the turns at its ends can touch anything.
  const double free_turn = fp_.circumscribed + margin_ + g_.res;
  auto open = [&](const TPoint2D& a, const TPoint2D& b) {
    const double len = std::hypot(b.x - a.x, b.y - a.y);
    const int n = std::max(1, static_cast<int>(std::ceil(len / (g_.res / 2))));
    for (int k = 0; k <= n; ++k)
      if (clearance(a.x + (b.x - a.x) * k / n, a.y + (b.y - a.y) * k / n) < free_turn) return false;
    return true;
  };
  std::vector<TPoint2D> out;
  for (const TPoint2D& p : turns) {
    while (out.size() >= 2 && open(out[out.size() - 2], p)) out.pop_back();
    out.push_back(p);
  }
  return out;
}

}  // namespace carenav::navigation
