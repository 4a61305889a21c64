// Footprint maneuvers (maneuver.h): through random gap mouths from random
// skewed poses, every plan's sweep touches nothing and ends on the route
// beyond the gap facing its way; a robot that may not reverse never does.
#include <carenav/navigation/maneuver.h>

#include "fixtures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace carenav::navigation {
namespace {

using test::GapScene;

/** The clutter benchmark's robot at the walker's limits: 0.51 x 0.43 m. */
RobotParams clutterRobot() { return test::fastRobotAt(0.5); }

/** Checks every 5 mm of the footprint's corner travel along the step. */
bool sweepTouches(const LocalCostmap& map, const TPose2D& from, const ManeuverStep& s,
                  double lever) {
  const double travel = s.length + std::abs(s.turn) * lever;
  const int n = std::max(1, static_cast<int>(std::ceil(travel / 0.005)));
  for (int i = 0; i <= n; ++i) {
    const double f = double(i) / n;
    if (map.check(applyPrimitive(from, s.dir, f * s.length, f * s.turn)).collision) return true;
  }
  return false;
}

TEST(ManeuverPlanner, FindsAWayThroughAGapMouthFromSkewedPosesAndTouchesNothing) {
  NavigationParams nav;
  const RobotParams r = clutterRobot();
  const double lever = std::hypot(0.255, 0.215);
  ManeuverParams mp;
  const ManeuverPlanner planner(mp, r);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> gap(0.49, 0.65), ux(-0.5, 0.2), uy(-0.3, 0.3),
      uphi(-1.0, 1.0);
  int tried = 0, found = 0, reversed = 0;
  for (int scene = 0; scene < 40; ++scene) {
    const GapScene g(gap(rng));
    LocalCostmap map(nav, Footprint(r.footprint, nav.resolution));
    map.build({0, 0}, g.obs);
    // Skewed before the mouth, then driven on until wedged: the front
    // 3-6 cm from a post.
    TPose2D start{ux(rng), uy(rng), uphi(rng)};
    for (int k = 0; k < 200; ++k) {
      const FootprintCheck c = map.check(start, 0.1);
      if (c.collision || c.outside || c.clearance < 0.06) break;
      start = applyPrimitive(start, 1, 0.005, 0);
    }
    const FootprintCheck c0 = map.check(start, 0.1);
    if (c0.collision || c0.outside || c0.clearance < 0.03 || start.x > g.gx) continue;
    ++tried;
    const TPose2D goal{g.gx + 0.6, 0, 0};
    const auto m = planner.plan(map, start, goal);
    if (!m) continue;
    ++found;
    TPose2D at = start;
    for (const auto& s : m->steps) {
      EXPECT_FALSE(sweepTouches(map, at, s, lever)) << "scene " << scene;
      const TPose2D next = applyPrimitive(at, s.dir, s.length, s.turn);
      EXPECT_NEAR(next.x, s.end.x, 1e-6);
      EXPECT_NEAR(next.y, s.end.y, 1e-6);
      reversed += s.dir < 0;
      at = s.end;
    }
    EXPECT_LE(std::hypot(at.x - goal.x, at.y - goal.y), mp.goal_radius + 1e-9);
    EXPECT_LE(std::abs(std::remainder(at.phi - goal.phi, 2 * M_PI)),
              mrpt::DEG2RAD(mp.goal_deg) + 1e-9);
  }
  EXPECT_GE(tried, 30);
  EXPECT_GE(found, tried * 9 / 10) << found << " of " << tried;
  EXPECT_GT(reversed, 0);  // some starts need a step back
}

TEST(ManeuverPlanner, NeverReversesWhereItMayNotAndFindsNothingThroughAWall) {
  NavigationParams nav;
  RobotParams r = clutterRobot();
  const GapScene g(0.55);
  LocalCostmap map(nav, Footprint(r.footprint, nav.resolution));
  map.build({0, 0}, g.obs);
  // Skewed before the mouth: a robot that may not reverse, or may not
  // there, never does.
  const TPose2D start{0.2, 0.12, 0.6};
  ASSERT_FALSE(map.check(start).collision);
  const TPose2D goal{1.2, 0, 0};
  for (const bool can_reverse : {true, false}) {
    r.v_min = can_reverse ? -0.5 : 0.0;
    const ManeuverPlanner planner(ManeuverParams{}, r);
    for (const bool gate : {false, true}) {
      const auto m = planner.plan(map, start, goal, [&](const TPose2D&) { return !gate; });
      if (!m) continue;
      for (const auto& s : m->steps) EXPECT_FALSE(s.dir < 0 && (gate || !can_reverse));
    }
  }
  // A wall across the gap: no maneuver.
  std::vector<TPoint2D> wall = g.obs;
  for (double y = -3.0; y <= 3.0; y += 0.01) wall.push_back({g.gx, y});
  LocalCostmap closed(nav, Footprint(r.footprint, nav.resolution));
  closed.build({0, 0}, wall);
  ManeuverParams few;
  few.max_nodes = 3000;
  EXPECT_FALSE(ManeuverPlanner(few, r).plan(closed, start, goal));
}

TEST(ManeuverPlanner, LeavesAContactWithoutComingNearerAndRefusesAPointInside) {
  // Driven on until its front is 1 cm from a post (within the padding: in
  // contact for the cost map), the robot still gets a maneuver, and no pose
  // of it comes nearer than that; with a post's point inside its outline it
  // gets none.
  NavigationParams nav;
  const RobotParams r = clutterRobot();
  const GapScene g(0.55);
  LocalCostmap map(nav, Footprint(r.footprint, nav.resolution));
  map.build({0, 0}, g.obs);
  TPose2D start{-0.5, 0.3, 0.5};
  while (map.outlineClearance(applyPrimitive(start, 1, 0.002, 0)) > 0.01)
    start = applyPrimitive(start, 1, 0.002, 0);
  ASSERT_TRUE(map.check(start).collision);
  const double d0 = map.outlineClearance(start);
  ASSERT_GT(d0, 0.0);
  const auto m = ManeuverPlanner(ManeuverParams{}, r).plan(map, start, {g.gx + 0.6, 0, 0});
  ASSERT_TRUE(m);
  TPose2D at = start;
  for (const auto& s : m->steps) {
    for (int i = 1; i <= 50; ++i)
      EXPECT_GE(map.outlineClearance(applyPrimitive(at, s.dir, s.length * i / 50, s.turn * i / 50)),
                d0 - 0.011);
    at = s.end;
  }
  std::vector<TPoint2D> inside = g.obs;
  inside.push_back({start.x, start.y});
  LocalCostmap touched(nav, Footprint(r.footprint, nav.resolution));
  touched.build({0, 0}, inside);
  EXPECT_FALSE(ManeuverPlanner(ManeuverParams{}, r).plan(touched, start, {g.gx + 0.6, 0, 0}));
}

}  // namespace
}  // namespace carenav::navigation
