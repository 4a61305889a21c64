// Commitment in clutter: a replanned route keeps the gap it chose, and
// goal-dwa keeps its turn on the spot and drives forward.
#include <carenav/navigation/global_planner.h>
#include <carenav/navigation/local_planner.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fixtures.h"

namespace carenav::navigation {
namespace {

/** A 10 x 6 m room split by a wall at x = 5 with two doors, centred at
 *  y = 2 and y = 4, of the given widths. */
mrpt::maps::COccupancyGridMap2D twoDoors(double lower, double upper) {
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
  wall(4.95, 0, 5.05, 2 - lower / 2);
  wall(4.95, 2 + lower / 2, 5.05, 4 - upper / 2);
  wall(4.95, 4 + upper / 2, 5.05, 6);
  return g;
}

/** y where the route crosses the wall at x = 5. */
double crossing(const Route& r) {
  for (const auto& c : r.cells)
    if (std::abs(c.x - 5) < 0.05) return c.y;
  return -1;
}

TEST(GlobalPlanner, AReplannedRouteKeepsTheGapItChoseAndTakesOnlyGapsThatFit) {
  NavigationParams p;
  // Two equal doors, the way through each as long: the route being
  // replaced decides.
  const auto g = twoDoors(0.9, 0.9);
  const GlobalPlanner gp(g, 0.25, p);
  const TPoint2D a{2, 3}, b{8, 3};
  const auto up = gp.plan(a, b, {{2, 3}, {5, 4}, {8, 3}});
  const auto down = gp.plan(a, b, {{2, 3}, {5, 2}, {8, 3}});
  ASSERT_TRUE(up && down);
  EXPECT_NEAR(crossing(*up), 4.0, 0.2);
  EXPECT_NEAR(crossing(*down), 2.0, 0.2);
  // Kept by the old route, but a door too narrow for the robot (0.4 m for a
  // 0.25 m radius): the new route takes the door that fits.
  const auto narrow = twoDoors(0.4, 0.9);
  const GlobalPlanner gn(narrow, 0.25, p);
  const auto r = gn.plan(a, b, {{2, 3}, {5, 2}, {8, 3}});
  ASSERT_TRUE(r.has_value());
  EXPECT_NEAR(crossing(*r), 4.0, 0.2);
}

TEST(GlobalPlanner, APostsHitsOneCellOffItDoNotMoveTheRoute) {
  NavigationParams p;
  p.plan_clearance = 0;
  // A post of 0.15 m at (5, 3) in an empty room; the route passes it with
  // 2 cm to spare beyond the radius.
  mrpt::maps::COccupancyGridMap2D g(0, 10, 0, 6, 0.05);
  g.fill(0.95f);
  for (double x = 4.93; x <= 5.07; x += 0.025)
    for (double y = 2.93; y <= 3.07; y += 0.025) g.setPos(x, y, 0.05f);
  const double radius = 0.25;
  const double y = 3.075 + radius + 0.05;
  std::optional<Route> route = Route{};
  route->waypoints = {{9, y}};
  // The lidar's hits on the post's side facing the route, placed one cell
  // beyond the post's cells (noise and the cell they fall in).
  std::vector<TPoint2D> seen;
  for (double x = 4.93; x <= 5.07; x += 0.02) seen.push_back({x, 3.1 + 0.01});
  EXPECT_FALSE(replanAroundSeen(g, seen, {1, y}, {9, y}, route, radius, 0.5, p).has_value());
  // A new obstacle on the route moves it.
  seen.push_back({7, y});
  seen.push_back({7, y + 0.05});
  EXPECT_TRUE(replanAroundSeen(g, seen, {1, y}, {9, y}, route, radius, 0.5, p).has_value());
}

/** A robot of the clutter benchmark's size and the walker's speed. */
RobotParams smallRobot() {
  RobotParams r = test::walkerRobot();
  r.footprint = {{0.255, 0.215}, {-0.255, 0.215}, {-0.255, -0.215}, {0.255, -0.215}};
  r.v_min = -0.5;
  return r;
}

TEST(GoalDwa, KeepsTurningOnTheSpotOneWayWhileTheTargetSwingsAcrossBehindIt) {
  NavigationParams p;
  const RobotParams r = smallRobot();
  LocalCostmap map(p, Footprint(r.footprint, p.resolution));
  map.build({0, 0}, {});
  PlannerInput in;
  in.map = &map;
  in.pose = {0, 0, 0};
  in.current = {0, 0};  // stopped: the window is the same both ways
  const std::vector<TPoint2D> left{{0, 0}, {-2, 0.1}}, right{{0, 0}, {-2, -0.1}};
  // A fresh planner turns to the nearer side of each.
  in.path = left;
  EXPECT_GT(makeGoalDwa(p, r)->plan(in).cmd.w, 0);
  in.path = right;
  EXPECT_LT(makeGoalDwa(p, r)->plan(in).cmd.w, 0);
  // Committed to a left turn, the target swinging 6 deg across behind the
  // robot does not make it turn back.
  auto dwa = makeGoalDwa(p, r);
  for (int k = 0; k < 6; ++k) {
    in.path = k % 2 ? right : left;
    const PlannerOutput o = dwa->plan(in);
    ASSERT_TRUE(o.ok) << o.note;
    EXPECT_EQ(o.status, PlanStatus::TurnInPlace);
    EXPECT_GT(o.cmd.w, 0) << k;
  }
  // When the other side is clearly better (the target 60 deg off it), the
  // robot turns that way.
  in.path = {{0, 0}, {-1, -1.7}};
  EXPECT_LT(dwa->plan(in).cmd.w, 0);
  // Without commitment (k_switch = 0) it flips with the target.
  p.k_switch = 0;
  auto free = makeGoalDwa(p, r);
  in.path = left;
  EXPECT_GT(free->plan(in).cmd.w, 0);
  in.path = right;
  EXPECT_LT(free->plan(in).cmd.w, 0);
}

TEST(GoalDwa, DrivesForwardOnlyAndLeavesBackingUpToTheRecoveries) {
  NavigationParams p;
  const RobotParams r = smallRobot();
  LocalCostmap map(p, Footprint(r.footprint, p.resolution));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-2, 2);
  size_t backward = 0;
  for (int scene = 0; scene < 30; ++scene) {
    std::vector<TPoint2D> posts;
    for (int i = 0; i < 12; ++i) {
      const TPoint2D c{u(rng), u(rng)};
      if (std::hypot(c.x, c.y) > 0.5) posts.push_back(c);
    }
    map.build({0, 0}, posts);
    PlannerInput in;
    in.map = &map;
    in.pose = {0, 0, 0};
    in.current = {0, 0};
    in.path = {{0, 0}, {u(rng), u(rng)}};
    for (const bool reverse : {false, true}) {
      p.reverse = reverse;
      const PlannerOutput o = makeGoalDwa(p, r)->plan(in);
      for (const Trajectory& t : o.trajectories)
        if (t.cmd.v < -1e-9) {
          EXPECT_TRUE(reverse) << "scene " << scene;
          ++backward;
        }
    }
  }
  EXPECT_GT(backward, 0u);  // with `reverse` on, backward candidates are scored
  // Moving backward (after a recovery backed out), it slows down first.
  p.reverse = false;
  map.build({0, 0}, {});
  PlannerInput in;
  in.map = &map;
  in.pose = {0, 0, 0};
  in.current = {-0.5, 0};
  in.path = {{0, 0}, {3, 0}};
  const PlannerOutput o = makeGoalDwa(p, r)->plan(in);
  ASSERT_TRUE(o.ok) << o.note;
  EXPECT_GT(o.cmd.v, -0.5);
}

}  // namespace
}  // namespace carenav::navigation
