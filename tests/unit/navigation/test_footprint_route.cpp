// Routes the rectangular footprint can drive (GlobalPlanner::setFootprint),
// checked by an independent sweep of the rectangle over the map's cells;
// and replanning that drops a route only for what the map does not show
// (replan_new_only), over the same random post fields.
#include <carenav/navigation/global_planner.h>

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>

namespace carenav::navigation {
namespace {

// The clutter benchmark's robot: 0.51 x 0.43 m.
const std::vector<Point2> kRect = {
    {0.255, 0.215}, {-0.255, 0.215}, {-0.255, -0.215}, {0.255, -0.215}};
constexpr double kInscribed = 0.215;

/** Marks the box [x0, x1] x [y0, y1] occupied on `g`. */
void box(mrpt::maps::COccupancyGridMap2D& g, double x0, double y0, double x1, double y1) {
  for (double x = x0 + 0.0125; x < x1; x += 0.025)
    for (double y = y0 + 0.0125; y < y1; y += 0.025) g.setPos(x, y, 0.05f);
}

/** A 6 x 3 m room with `posts` square posts of 0.15 m at random between
 *  x = 1.2 and 4.8. */
mrpt::maps::COccupancyGridMap2D postField(std::mt19937& rng, int posts) {
  mrpt::maps::COccupancyGridMap2D g(0, 6, 0, 3, 0.05);
  g.fill(0.95f);
  box(g, 0, 0, 6, 0.1);
  box(g, 0, 2.9, 6, 3);
  box(g, 0, 0, 0.1, 3);
  box(g, 5.9, 0, 6, 3);
  std::uniform_real_distribution<double> ux(1.2, 4.8), uy(0.1, 2.9);
  for (int i = 0; i < posts; ++i) {
    const double x = std::round(ux(rng) / 0.05) * 0.05, y = std::round(uy(rng) / 0.05) * 0.05;
    box(g, x - 0.075, y - 0.075, x + 0.075, y + 0.075);
  }
  return g;
}

/** The rectangle at (x, y, th), sampled every centimetre over its area,
 *  comes within `margin` of an occupied cell's square. */
bool touches(const mrpt::maps::COccupancyGridMap2D& g, double x, double y, double th,
             double margin) {
  const double c = std::cos(th), s = std::sin(th), res = g.getResolution();
  for (double u = -0.255; u <= 0.255 + 1e-9; u += 0.01)
    for (double v = -0.215; v <= 0.215 + 1e-9; v += 0.01) {
      const double px = x + c * u - s * v, py = y + s * u + c * v;
      const int ix = g.x2idx(px), iy = g.y2idx(py);
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int qx = ix + dx, qy = iy + dy;
          if (qx < 0 || qy < 0 || qx >= int(g.getSizeX()) || qy >= int(g.getSizeY())) return true;
          if (g.getCell(qx, qy) > 0.5f) continue;
          const double cx = g.idx2x(qx), cy = g.idx2y(qy);
          const double ex = std::max(0.0, std::abs(px - cx) - res / 2);
          const double ey = std::max(0.0, std::abs(py - cy) - res / 2);
          if (std::hypot(ex, ey) < margin) return true;
        }
    }
  return false;
}

/** The robot drives `pts` forward, each segment at its heading, turning on
 *  the spot at each vertex; poses within `skip` of the first and last point
 *  are not checked. True when no checked pose touches. */
bool drivable(const mrpt::maps::COccupancyGridMap2D& g, const std::vector<TPoint2D>& pts,
              double skip, double margin) {
  auto checked = [&](double x, double y) {
    return std::hypot(x - pts.front().x, y - pts.front().y) > skip &&
           std::hypot(x - pts.back().x, y - pts.back().y) > skip;
  };
  double prev = std::nan("");
  for (size_t i = 0; i + 1 < pts.size(); ++i) {
    const double dx = pts[i + 1].x - pts[i].x, dy = pts[i + 1].y - pts[i].y;
    const double len = std::hypot(dx, dy);
    if (len < 1e-9) continue;
    const double th = std::atan2(dy, dx);
    if (!std::isnan(prev) && checked(pts[i].x, pts[i].y)) {
      const double turn = std::remainder(th - prev, 2 * M_PI);
      for (double a = 0; a <= 1; a += 0.05)
        if (touches(g, pts[i].x, pts[i].y, prev + a * turn, margin)) return false;
    }
    for (double d = 0; d <= len; d += 0.01) {
      const double x = pts[i].x + dx * d / len, y = pts[i].y + dy * d / len;
      if (checked(x, y) && touches(g, x, y, th, margin)) return false;
    }
    prev = th;
  }
  return true;
}

TEST(FootprintRoute, RoutesThroughPostFieldsAreOnesTheRectangleCanDrive) {
  // 40 random post fields. The inscribed circle's route may cross a gap at
  // a slant or turn where the 0.51 x 0.43 m rectangle cannot; with the
  // footprint set, every route the planner marks as planned for it is
  // drivable (independent 1 cm sweep, 1 cm margin: the planner keeps 3 cm),
  // and more routes are drivable than without it (when written: 24 of the
  // 33 worlds with a route against 13, 12 searched).
  NavigationParams p;
  p.route_footprint = true;
  std::mt19937 rng(18);
  std::uniform_int_distribution<int> count(12, 30);
  const TPoint2D start{0.6, 1.5}, goal{5.4, 1.5};
  const double skip = std::hypot(0.255, 0.215) + p.route_footprint_margin;
  int worlds = 0, circle_ok = 0, rect_ok = 0, searched = 0;
  for (int w = 0; w < 40; ++w) {
    const auto g = postField(rng, count(rng));
    const GlobalPlanner circle(g, kInscribed, p);
    GlobalPlanner rect(g, kInscribed, p);
    rect.setFootprint(kRect);
    const auto rc = circle.plan(start, goal);
    const auto rr = rect.plan(start, goal);
    ASSERT_EQ(rc.has_value(), rr.has_value()) << "world " << w;
    if (!rc) continue;
    ++worlds;
    std::vector<TPoint2D> pc{start}, pr{start};
    pc.insert(pc.end(), rc->waypoints.begin(), rc->waypoints.end());
    pr.insert(pr.end(), rr->waypoints.begin(), rr->waypoints.end());
    const bool c_ok = drivable(g, pc, skip, 0.01), r_ok = drivable(g, pr, skip, 0.01);
    circle_ok += c_ok;
    rect_ok += r_ok;
    if (rr->footprint) {
      ++searched;
      EXPECT_TRUE(r_ok) << "world " << w << ": a route planned for the footprint touches";
      EXPECT_NEAR(rr->waypoints.back().x, goal.x, 1e-9);
      EXPECT_TRUE(rect.footprintClear(pr, skip)) << "world " << w;
    } else {
      EXPECT_EQ(c_ok, r_ok) << "world " << w;
    }
  }
  std::cout << worlds << " worlds with a route: drivable " << circle_ok << " (circle), " << rect_ok
            << " (footprint; " << searched << " searched)\n";
  EXPECT_GE(worlds, 30);
  EXPECT_GE(searched, 8);
  EXPECT_GE(rect_ok, circle_ok + 8);
}

TEST(FootprintRoute, HitsOnWhatTheMapShowsDoNotBlockARouteNewObstaclesDo) {
  // A route through the wider of two gaps with just room for the
  // rectangle (0.58 m; the other, farther round, 0.56 m): the lidar's hits
  // on the gap's own wall (a cell outside it, by quantisation) leave it
  // (marked, they would narrow it below the other gap, and the route
  // would be planned through that one); a box on the route blocks it and
  // it is planned again, through the other gap.
  NavigationParams p;
  p.route_footprint = true;
  mrpt::maps::COccupancyGridMap2D g(0, 6, 0, 4, 0.05);
  g.fill(0.95f);
  box(g, 2.9, 0, 3.1, 1.7);
  box(g, 2.9, 2.3, 3.1, 3.05);
  box(g, 2.9, 3.6, 3.1, 4);
  GlobalPlanner gp(g, kInscribed, p);
  gp.setFootprint(kRect);
  const auto r = gp.plan({1, 2}, {5, 2});
  ASSERT_TRUE(r);
  for (const auto& c : r->cells) EXPECT_LT(c.y, 2.6) << "through the lower gap";
  std::vector<TPoint2D> hits;
  for (double y = 1.5; y <= 1.72; y += 0.01) hits.push_back({2.88, y}), hits.push_back({3.12, y});
  for (double y = 2.28; y <= 2.5; y += 0.01) hits.push_back({2.88, y}), hits.push_back({3.12, y});
  for (double x = 2.9; x <= 3.1; x += 0.01) hits.push_back({x, 1.72}), hits.push_back({x, 2.28});
  EXPECT_FALSE(replanAroundSeen(g, hits, {1, 2}, {5, 2}, r, kInscribed, 0.5, p, {}, kRect));
  for (double y = 1.9; y <= 2.1; y += 0.02) hits.push_back({4.0, y});
  const auto again = replanAroundSeen(g, hits, {1, 2}, {5, 2}, r, kInscribed, 0.5, p, {}, kRect);
  ASSERT_TRUE(again);
  bool upper = false;
  for (const auto& c : again->cells) upper = upper || (std::abs(c.x - 3) < 0.1 && c.y > 3);
  EXPECT_TRUE(upper) << "around the box, through the upper gap";
}

/** What a lidar returns of the map's obstacles: a point on each occupied
 *  cell's square, put up to a cell off at random (a pose known to a few
 *  centimetres; each draw differs, as the obstacle memory does from one
 *  replanning to the next). */
std::vector<TPoint2D> mapSeenAgain(const mrpt::maps::COccupancyGridMap2D& g, std::mt19937& rng) {
  std::uniform_real_distribution<double> off(-0.05, 0.05);
  std::vector<TPoint2D> hits;
  for (unsigned iy = 0; iy < g.getSizeY(); ++iy)
    for (unsigned ix = 0; ix < g.getSizeX(); ++ix)
      if (g.getCell(ix, iy) < 0.5f)
        hits.push_back({g.idx2x(ix) + off(rng), g.idx2y(iy) + off(rng)});
  return hits;
}

/** A 0.2 m box of hits at `c`. */
void boxHits(std::vector<TPoint2D>& hits, const TPoint2D& c) {
  for (double dy = -0.1; dy <= 0.1 + 1e-9; dy += 0.02)
    for (double dx = -0.1; dx <= 0.1 + 1e-9; dx += 0.02) hits.push_back({c.x + dx, c.y + dy});
}

TEST(RouteReplanning, TheMapSeenAgainKeepsTheRouteANewBoxAheadDropsIt) {
  // 40 random post fields; a route planned with the map's posts as the
  // lidar saw them, and checked, the robot at a third of it, with the posts
  // as seen a moment later (another draw). With replan_new_only the route
  // stays in every world (without it, it was dropped in most: a cell's
  // noise narrows a tight gap below the clearance the route was planned
  // with, and the route is planned anew, maybe another way). A box of
  // 0.2 m on the route ahead drops it, and the new route keeps clear of
  // the box; the same box behind the robot does not. (When written: 25
  // worlds with a route, dropped without replan_new_only in 22, a box ahead
  // dropped it in 20.)
  NavigationParams on, off;
  on.replan_new_only = true;
  off.replan_new_only = false;
  std::mt19937 rng(16);
  std::uniform_int_distribution<int> count(12, 30);
  const TPoint2D start{0.6, 1.5}, goal{5.4, 1.5};
  const double skip = std::hypot(0.255, 0.215) + 0.2;
  int worlds = 0, dropped_off = 0, ahead_dropped = 0;
  for (int w = 0; w < 40; ++w) {
    const auto g = postField(rng, count(rng));
    const auto seen = mapSeenAgain(g, rng), later = mapSeenAgain(g, rng);
    const auto route = replanAroundSeen(g, seen, start, goal, std::nullopt, kInscribed, skip, on);
    const auto route_off =
        replanAroundSeen(g, seen, start, goal, std::nullopt, kInscribed, skip, off);
    if (!route || !route_off || route->cells.size() < 60 || route_off->cells.size() < 60) continue;
    ++worlds;
    const auto& cells = route->cells;
    const TPoint2D from = cells[cells.size() / 3], before = cells[cells.size() / 3 - 20];
    const TPoint2D ahead = cells[cells.size() / 3 + 20];
    EXPECT_FALSE(replanAroundSeen(g, later, from, goal, route, kInscribed, skip, on))
        << "world " << w << ": dropped for the map seen again";
    const TPoint2D from_off = route_off->cells[route_off->cells.size() / 3];
    dropped_off +=
        replanAroundSeen(g, later, from_off, goal, route_off, kInscribed, skip, off).has_value();
    auto hits = later;
    boxHits(hits, before);
    EXPECT_FALSE(replanAroundSeen(g, hits, from, goal, route, kInscribed, skip, on))
        << "world " << w << ": dropped for a box behind the robot";
    hits = later;
    boxHits(hits, ahead);
    const auto again = replanAroundSeen(g, hits, from, goal, route, kInscribed, skip, on);
    if (!again) continue;  // no way round the box: the route stays (the recoveries remain)
    ++ahead_dropped;
    for (const auto& c : again->cells)
      EXPECT_GT(std::max(std::abs(c.x - ahead.x), std::abs(c.y - ahead.y)), 0.1 + kInscribed - 0.05)
          << "world " << w << ": the new route crosses the box";
  }
  std::cout << worlds << " worlds: without replan_new_only the route was dropped in " << dropped_off
            << "; a box ahead dropped it in " << ahead_dropped << "\n";
  EXPECT_GE(worlds, 20);
  EXPECT_GE(dropped_off, worlds / 2);
  EXPECT_GE(ahead_dropped, worlds * 2 / 3);
}

}  // namespace
}  // namespace carenav::navigation
