// Places of repeated recoveries, and routes that keep clear of them.
#include <carenav/navigation/failed_places.h>
#include <carenav/navigation/global_planner.h>

#include <gtest/gtest.h>

#include <cmath>

namespace carenav::navigation {
namespace {

/** The clutter benchmark's 0.51 x 0.43 m footprint. */
Footprint clutterFootprint() {
  return Footprint({{0.255, 0.215}, {-0.255, 0.215}, {-0.255, -0.215}, {0.255, -0.215}}, 0.05);
}

TEST(FailedPlaces, APlaceIsAvoidedFromItsSecondRecovery) {
  FailedPlaces f(FailedPlacesParams{}, clutterFootprint());
  EXPECT_FALSE(f.add({1.0, 1.0, 0}));
  EXPECT_EQ(f.avoided(), 0u);
  EXPECT_TRUE(f.avoidedPoints(0.05).empty());
  // Another place (farther than the circumscribed radius, 0.334 m): its first.
  EXPECT_FALSE(f.add({1.5, 1.0, 0}));
  // Back at the first place, a little aside and turned: its second.
  EXPECT_TRUE(f.add({1.1, 1.1, M_PI / 2}));
  EXPECT_EQ(f.avoided(), 1u);
  EXPECT_FALSE(f.add({1.05, 1.1, M_PI / 2}));  // a third: still avoided, not newly
  EXPECT_EQ(f.avoided(), 1u);
  // The points: from the robot's centre to its front edge, along its heading
  // at the latest recovery there (the gap it was trying to enter).
  const auto pts = f.avoidedPoints(0.05);
  ASSERT_GE(pts.size(), 2u);
  EXPECT_NEAR(pts.front().x, 1.05, 1e-9);
  EXPECT_NEAR(pts.front().y, 1.1, 1e-9);
  EXPECT_NEAR(pts.back().x, 1.05, 1e-9);
  EXPECT_NEAR(pts.back().y, 1.1 + 0.255, 1e-9);
  for (size_t i = 1; i < pts.size(); ++i)
    EXPECT_LE(std::hypot(pts[i].x - pts[i - 1].x, pts[i].y - pts[i - 1].y), 0.05 + 1e-9);
  f.clear();
  EXPECT_EQ(f.avoided(), 0u);
}

TEST(FailedPlaces, NeverWhenOffAndBoundedInPlaces) {
  FailedPlacesParams off;
  off.avoid_after = 0;
  FailedPlaces never(off, clutterFootprint());
  for (int i = 0; i < 5; ++i) EXPECT_FALSE(never.add({0, 0, 0}));
  EXPECT_EQ(never.avoided(), 0u);
  EXPECT_TRUE(never.avoidedPoints(0.05).empty());

  FailedPlacesParams once;
  once.avoid_after = 1;
  FailedPlaces f(once, clutterFootprint());
  for (size_t i = 0; i < 3 * FailedPlaces::kMaxPlaces; ++i)
    EXPECT_TRUE(f.add({static_cast<double>(i), 0, 0}));
  EXPECT_EQ(f.avoided(), FailedPlaces::kMaxPlaces);  // the oldest were dropped
}

/** A 10 x 6 m map: a wall at x = 5 with two 1 m doors, at y = 1.5 and 4.5. */
mrpt::maps::COccupancyGridMap2D twoDoors() {
  mrpt::maps::COccupancyGridMap2D g(0, 10, 0, 6, 0.05);
  g.fill(0.95f);
  auto wall = [&](double x0, double y0, double x1, double y1) {
    for (double x = x0; x <= x1; x += 0.025)
      for (double y = y0; y <= y1; y += 0.025) g.setPos(x, y, 0.05f);
  };
  wall(0, 0, 10, 0.1);
  wall(0, 5.9, 10, 6);
  wall(0, 0, 0.1, 6);
  wall(9.9, 0, 10, 6);
  wall(4.95, 0, 5.05, 1.0);
  wall(4.95, 2.0, 5.05, 4.0);
  wall(4.95, 5.0, 5.05, 6);
  return g;
}

/** The y where the route's cells cross the wall. */
double crossingY(const Route& r) {
  for (const auto& c : r.cells)
    if (std::abs(c.x - 5) < 0.05) return c.y;
  return -1;
}

TEST(FailedPlaces, TheRouteTakesTheOtherDoorAfterTwoRecoveriesInOne) {
  NavigationParams p;
  const auto map = twoDoors();
  const Footprint fp = clutterFootprint();
  const GlobalPlanner gp(map, fp.inscribed, p);
  const auto first = gp.plan({2, 1.5}, {8, 1.5});
  ASSERT_TRUE(first.has_value());
  EXPECT_NEAR(crossingY(*first), 1.5, 0.3);
  // Wedged twice at the near door's entry, facing it.
  FailedPlaces f(FailedPlacesParams{}, fp);
  f.add({4.6, 1.45, 0});
  const TPoint2D from{3.8, 1.5}, goal{8, 1.5};
  EXPECT_FALSE(replanAroundSeen(map, f.avoidedPoints(0.05), from, goal, first, fp.inscribed, 0.5, p)
                   .has_value());  // one recovery: the route stays
  f.add({4.65, 1.55, 0.1});
  const auto other =
      replanAroundSeen(map, f.avoidedPoints(0.05), from, goal, first, fp.inscribed, 0.5, p);
  ASSERT_TRUE(other.has_value());
  EXPECT_NEAR(crossingY(*other), 4.5, 0.3);
  // Both doors failed: no way left, the route stays as it was.
  f.add({4.6, 4.5, 0});
  f.add({4.6, 4.5, 0});
  EXPECT_FALSE(replanAroundSeen(map, f.avoidedPoints(0.05), from, goal, other, fp.inscribed, 0.5, p)
                   .has_value());
}

}  // namespace
}  // namespace carenav::navigation
