// Footprint maneuvers (maneuver.h): Hybrid A* [Dolgov10] over short
// primitives on the local cost map.
#include <carenav/navigation/maneuver.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <queue>
#include <unordered_map>

namespace carenav::navigation {

namespace {

/** Least spacing of the footprint checks along a primitive (m of travel of
 *  the footprint's farthest corner): the next check is as far on as the
 *  clearance above the floor allows (the outline moves no more than the
 *  corner), at least this; so the sweep comes at most this much nearer
 *  than the floor between two checks. */
constexpr double kMinSpacing = 0.01;

}  // namespace

/** Distances to go ignoring the heading but not the obstacles ([Dolgov10]'s
 *  "holonomic with obstacles" heuristic): a Dijkstra over the cost map's
 *  cells from the goal, through cells whose distance to the nearest
 *  obstacle cell leaves room for the footprint's inscribed circle (less a
 *  cell: where the robot's centre can stand at some heading, the cell
 *  passes), within `radius` of `centre`. Infinity: no way. */
class DistanceToGoal {
 public:
  DistanceToGoal(const LocalCostmap& map, const TPoint2D& goal, const TPoint2D& centre,
                 double radius)
      : map_(map), n_(map.size()), res_(map.resolution()), o_(map.origin()) {
    const double inf = std::numeric_limits<double>::infinity();
    d_.assign(static_cast<size_t>(n_) * n_, inf);
    const double need = map.footprint().inscribed - res_;
    auto passable = [&](int ix, int iy) {
      const double x = o_.x + (ix + 0.5) * res_, y = o_.y + (iy + 0.5) * res_;
      return std::hypot(x - centre.x, y - centre.y) <= radius + res_ && map_.distance(x, y) >= need;
    };
    const int gx = cell(goal.x, o_.x), gy = cell(goal.y, o_.y);
    if (!in(gx, gy)) return;
    using Item = std::pair<double, int>;
    std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
    d_[idx(gx, gy)] = 0;
    open.push({0, static_cast<int>(idx(gx, gy))});
    while (!open.empty()) {
      const auto [d, i] = open.top();
      open.pop();
      if (d > d_[static_cast<size_t>(i)]) continue;
      const int ix = i % n_, iy = i / n_;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int jx = ix + dx, jy = iy + dy;
          if ((dx == 0 && dy == 0) || !in(jx, jy) || !passable(jx, jy)) continue;
          const double nd = d + res_ * ((dx != 0 && dy != 0) ? M_SQRT2 : 1.0);
          if (nd < d_[idx(jx, jy)]) {
            d_[idx(jx, jy)] = nd;
            open.push({nd, static_cast<int>(idx(jx, jy))});
          }
        }
    }
  }
  /** m still to go from (x, y), less the cells' quantisation; infinity: none. */
  double at(double x, double y) const {
    const int ix = cell(x, o_.x), iy = cell(y, o_.y);
    if (!in(ix, iy)) return std::numeric_limits<double>::infinity();
    return std::max(0.0, d_[idx(ix, iy)] - 2 * res_);
  }

 private:
  int cell(double v, double o) const { return static_cast<int>(std::floor((v - o) / res_)); }
  bool in(int ix, int iy) const { return ix >= 0 && iy >= 0 && ix < n_ && iy < n_; }
  size_t idx(int ix, int iy) const { return static_cast<size_t>(iy) * n_ + ix; }
  const LocalCostmap& map_;
  int n_;
  double res_;
  TPoint2D o_;
  std::vector<double> d_;
};

namespace {

/** A pose the search reached: the step that led there (its `end` the
 *  pose), the cost so far, the clearance there (capped), the node before
 *  it, and the last direction driven (1, -1; 0 before any). */
struct SearchNode {
  ManeuverStep step;
  double g = 0, clearance = 0;
  int parent = -1, dir = 0;
};

/** The steps from the start to node `i`, consecutive equal ones merged (a
 *  run of straights, of arcs of one curvature, of turns one way). */
std::vector<ManeuverStep> stepsTo(const std::vector<SearchNode>& nodes, int i) {
  std::vector<ManeuverStep> steps;
  for (int k = i; nodes[static_cast<size_t>(k)].parent >= 0;
       k = nodes[static_cast<size_t>(k)].parent)
    steps.push_back(nodes[static_cast<size_t>(k)].step);
  std::reverse(steps.begin(), steps.end());
  std::vector<ManeuverStep> merged;
  for (const auto& s : steps) {
    if (!merged.empty() && merged.back().dir == s.dir &&
        std::abs(merged.back().turn * s.length - s.turn * merged.back().length) < 1e-9 &&
        (s.dir != 0 || merged.back().turn * s.turn > 0)) {
      merged.back().length += s.length;
      merged.back().turn += s.turn;
      merged.back().end = s.end;
    } else {
      merged.push_back(s);
    }
  }
  return merged;
}

}  // namespace

const ParamTable<ManeuverParams>& ManeuverParams::table() {
  using P = ManeuverParams;
  static const auto t =
      ParamTable<P>()
          .flag("enabled", &P::enabled,
                "recoveries first look for a footprint maneuver (forward and reverse arcs, "
                "turns on the spot) to the route further on; off: back out, turn and wait only")
          .real("reach", &P::reach, "m", 0.2, 5,
                "a maneuver ends this far along the route past the robot's nearest point on it")
          .real("goal_radius", &P::goal_radius, "m", 0.01, 1,
                "... within this of that point (farther points are tried when its footprint "
                "touches something)")
          .real("goal_deg", &P::goal_deg, "deg", 1, 180, "... facing the route's way within this")
          .real("step", &P::step, "m", 0.02, 1, "length of one straight or arc primitive")
          .real("turn_deg", &P::turn_deg, "deg", 1, 90,
                "heading change of an arc primitive and of a turn on the spot")
          .real("margin", &P::margin, "m", 0, 1,
                "every pose of a primitive, and of its continuation this far, keeps this much "
                "from everything seen (the supervisor's margin for recovery moves)")
          .real("comfort_margin", &P::comfort_margin, "m", 0, 1,
                "tried first, with a quarter of max_nodes: a maneuver that keeps this much "
                "leaves room for the error of driving it (when none is found: margin)")
          .real("reverse_cost", &P::reverse_cost, "", 1, 100,
                "a metre reversed costs this many metres forward")
          .real("switch_cost", &P::switch_cost, "m", 0, 10,
                "extra cost of changing between driving forward and reversing")
          .real("clearance_cost", &P::clearance_cost, "", 0, 100,
                "extra cost per metre of a primitive that passes at no clearance (falling to "
                "0 at clearance_influence)")
          .real("clearance_influence", &P::clearance_influence, "m", 0.01, 2,
                "clearance beyond this costs nothing")
          .real("radius", &P::radius, "m", 0.5, 10, "the search stays within this of the start")
          .real("greed", &P::greed, "", 1, 10,
                "weight of the distance still to go in the search (1: the cheapest maneuver; "
                "more: a maneuver found sooner, costing at most this times the cheapest)")
          .integer("max_nodes", &P::max_nodes, "", 100, 1000000,
                   "primitives expanded at most per search (bounds its time)");
  return t;
}

TPose2D applyPrimitive(const TPose2D& p, int dir, double length, double turn) {
  if (dir == 0) return {p.x, p.y, std::atan2(std::sin(p.phi + turn), std::cos(p.phi + turn))};
  return integrateArc(p, dir * length, turn, 1.0);
}

ManeuverPlanner::ManeuverPlanner(const ManeuverParams& p, const RobotParams& robot)
    : p_(p), r_(robot) {
  for (const auto& q : r_.footprint) lever_ = std::max(lever_, std::hypot(q.x, q.y));
  const double a = mrpt::DEG2RAD(p_.turn_deg);
  for (const int dir : {1, -1}) {
    if (dir < 0 && !(r_.v_min < 0)) continue;
    for (const double turn : {0.0, a, -a}) prims_.push_back({dir, p_.step, turn});
  }
  prims_.push_back({0, 0, a});
  prims_.push_back({0, 0, -a});
}

ManeuverPlanner::Sweep ManeuverPlanner::sweep(const LocalCostmap& map, const TPose2D& from,
                                              double from_clearance, const Primitive& m,
                                              double floor, double margin) const {
  // The primitive, then its continuation by `margin` (what the supervisor
  // checks beyond a command's stop); s is the corner's travel along it.
  const double travel = m.length + std::abs(m.turn) * lever_;
  const double total = travel + margin;
  Sweep out{p_.clearance_influence, 0};
  double s = 0, c = from_clearance;
  while (s < total) {
    double next = s + std::max(kMinSpacing, c - floor);
    if (s < travel && next > travel) next = travel;  // the primitive's end is checked
    s = std::min(next, total);
    const double f = s / travel;
    const TPose2D q = applyPrimitive(from, m.dir, f * m.length, f * m.turn);
    const FootprintCheck k = map.check(q, p_.clearance_influence);
    if (k.outside) return {-1, 0};
    c = k.clearance;
    // In contact (a robot wedged within the padding): the outline's own
    // distance, which must not fall below the start's.
    if (k.collision) c = floor < margin ? map.outlineClearance(q) : -1;
    if (c < floor) return {-1, 0};
    if (s <= travel) out.least = std::min(out.least, c);
    if (s == travel) out.end = c;
  }
  return out;
}

std::optional<Maneuver> ManeuverPlanner::plan(const LocalCostmap& map, const TPose2D& start,
                                              const TPose2D& goal,
                                              const ReverseGate& reverse_ok) const {
  const DistanceToGoal togo(map, {goal.x, goal.y}, {start.x, start.y}, p_.radius);
  // The comfortable search gets a quarter of the expansions: where none
  // keeps that much it fails after its whole budget, before the second.
  if (p_.comfort_margin > p_.margin)
    if (auto m = search(map, start, goal, togo, reverse_ok, p_.comfort_margin, p_.max_nodes / 4))
      return m;
  return search(map, start, goal, togo, reverse_ok, p_.margin, p_.max_nodes);
}

std::optional<Maneuver> ManeuverPlanner::search(const LocalCostmap& map, const TPose2D& start,
                                                const TPose2D& goal, const DistanceToGoal& togo,
                                                const ReverseGate& reverse_ok, double margin,
                                                int max_nodes) const {
  const double kres = p_.step / 2, a = mrpt::DEG2RAD(p_.turn_deg);
  const int nh = std::max(1, static_cast<int>(std::lround(2 * M_PI / a)));
  auto key = [&](const TPose2D& q) {
    const auto ix = static_cast<int64_t>(std::floor(q.x / kres)) & 0xfffff;
    const auto iy = static_cast<int64_t>(std::floor(q.y / kres)) & 0xfffff;
    const int64_t ih = ((std::lround(q.phi / (2 * M_PI) * nh) % nh) + nh) % nh;
    return (ix << 40) | (iy << 20) | ih;
  };
  auto h = [&](const TPose2D& q) {
    return p_.greed * std::max(0.0, togo.at(q.x, q.y) - p_.goal_radius);
  };
  auto atGoal = [&](const TPose2D& q) {
    return std::hypot(goal.x - q.x, goal.y - q.y) <= p_.goal_radius &&
           std::abs(angleDiff(q.phi, goal.phi)) <= mrpt::DEG2RAD(p_.goal_deg);
  };
  // Every pose keeps `margin` to everything; a robot wedged nearer than
  // that (within the padding too: nothing inside its outline) may move
  // with what it has.
  const FootprintCheck c0 = map.check(start, p_.clearance_influence);
  if (c0.outside) return std::nullopt;
  const double floor =
      c0.collision ? 0.999 * map.outlineClearance(start) : std::min(margin, c0.clearance);
  if (!(floor > 0)) return std::nullopt;
  std::vector<SearchNode> nodes{
      {{0, 0, 0, start}, 0.0, c0.collision ? floor : c0.clearance, -1, 0}};
  std::unordered_map<int64_t, double> best{{key(start), 0.0}};
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
  open.push({h(start), 0});
  size_t expanded = 0;
  std::vector<Primitive> cand;
  while (!open.empty() && expanded < static_cast<size_t>(max_nodes)) {
    const int i = open.top().second;
    open.pop();
    const SearchNode cur = nodes[static_cast<size_t>(i)];
    const TPose2D& at = cur.step.end;
    if (cur.g > best[key(at)] + 1e-9) continue;  // a cheaper way here was found
    if (atGoal(at)) return Maneuver{stepsTo(nodes, i), cur.g, expanded};
    ++expanded;
    // The primitives, and a turn on the spot onto the goal's lattice of
    // headings (goal heading plus whole turn_deg steps) for a robot off it:
    // the narrow gap is only passed near the goal's heading.
    cand.assign(prims_.begin(), prims_.end());
    const double off = std::remainder(at.phi - goal.phi, a);
    if (std::abs(off) > 1e-6) {
      cand.push_back({0, 0, -off});
      cand.push_back({0, 0, off > 0 ? a - off : -a - off});
    }
    for (const Primitive& m : cand) {
      const TPose2D q = applyPrimitive(at, m.dir, m.length, m.turn);
      if (std::hypot(q.x - start.x, q.y - start.y) > p_.radius) continue;
      double g = cur.g + (m.dir < 0 ? p_.reverse_cost : 1.0) * m.length +
                 std::abs(m.turn) * (m.dir == 0 ? lever_ : 0.0);
      if (m.dir != 0 && cur.dir != 0 && m.dir != cur.dir) g += p_.switch_cost;
      const int64_t kq = key(q);
      const auto it = best.find(kq);
      if (it != best.end() && it->second <= g) continue;
      if (m.dir < 0 && reverse_ok && !reverse_ok(q)) continue;
      const double hq = h(q);
      if (!std::isfinite(hq)) continue;  // no way on from there
      const Sweep sw = sweep(map, at, cur.clearance, m, floor, margin);
      if (sw.least < 0) continue;
      const double c = sw.least;
      const double travel = m.length + std::abs(m.turn) * lever_;
      g += p_.clearance_cost * travel * (1 - c / p_.clearance_influence);
      if (it != best.end() && it->second <= g) continue;
      best[kq] = g;
      nodes.push_back({{m.dir, m.length, m.turn, q}, g, sw.end, i, m.dir != 0 ? m.dir : cur.dir});
      open.push({g + hq, static_cast<int>(nodes.size() - 1)});
    }
  }
  return std::nullopt;
}

}  // namespace carenav::navigation
