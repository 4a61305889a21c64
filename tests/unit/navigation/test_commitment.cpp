// Commitment in clutter: goal-dwa keeps its turn on the spot and drives
// forward, leaving backing up to the recoveries.
#include <carenav/navigation/local_planner.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fixtures.h"

namespace carenav::navigation {
namespace {

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

namespace carenav::navigation {

TEST(Lookahead, ACornerPassedAsideCountsAsReachedOnceTheRobotIsAbeam) {
  // A route turning 90 deg left at (2, 0); the robot passes 0.25 m right of
  // the corner (farther than `reached`, 0.15 m).
  const std::vector<TPoint2D> path{{0, 0}, {2, 0}, {2, 2}};
  const double corner = 10 * M_PI / 180;
  // Still 0.5 m before it: the corner is the target.
  TPoint2D t = lookaheadPoint(path, 1.5, -0.25, 1.0, corner);
  EXPECT_NEAR(t.x, 2.0, 1e-9);
  EXPECT_NEAR(t.y, 0.0, 1e-9);
  // Abeam of it (its nearest point on the route less than `reached`
  // before the corner): the target moves on along the next leg instead of
  // turning the robot back to the corner.
  t = lookaheadPoint(path, 1.9, -0.25, 1.0, corner);
  EXPECT_NEAR(t.x, 2.0, 1e-9);
  EXPECT_GT(t.y, 0.5);
}

}  // namespace carenav::navigation
