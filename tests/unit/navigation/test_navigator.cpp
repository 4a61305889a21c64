// The Navigator's own behaviours (beyond the planners and the supervisor):
// turning in place when localisation asks for it (HOBBIT, seed 004).
#include <carenav/navigation/navigator.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace carenav;
using namespace carenav::navigation;

namespace {

RobotParams longRobot() {
  RobotParams r;
  // 1.0 m long, 0.5 m wide: it cannot turn between walls 0.4 m from its centre.
  r.footprint = {{0.5, 0.25}, {-0.5, 0.25}, {-0.5, -0.25}, {0.5, -0.25}};
  r.v_max = 0.4;
  r.w_max = 1.0;
  r.safe_distance = 0.1;
  return r;
}

NavigationParams goalParams() {
  NavigationParams p;
  p.plugin = "goal-dwa";
  return p;
}

/** Walls along y = +-half_width from x = -3 to 6, every 2 cm. */
std::vector<TPoint2D> corridor(double half_width) {
  std::vector<TPoint2D> w;
  for (double x = -3; x <= 6; x += 0.02) {
    w.push_back({x, half_width});
    w.push_back({x, -half_width});
  }
  return w;
}

Navigator::Cycle cycleIn(Navigator& n, const std::vector<TPoint2D>& walls, bool rotate) {
  n.setOdometry({0, 0, 0}, {0, 0}, 1.0);
  n.addObstaclePoints(walls, 1.0);
  n.setRoute({{0, 0}, {5, 0}}, {5, 0, 0});
  n.setRotateRequest(rotate);
  return n.cycle(1.0);
}

}  // namespace

TEST(Navigator, TurnsInPlaceWhenLocalisationAsks) {
  Navigator n(goalParams(), longRobot());
  const auto c = cycleIn(n, corridor(1.5), true);
  EXPECT_TRUE(c.plan.ok) << c.plan.note;
  EXPECT_EQ(c.plan.note, "turn in place to relocalise");
  EXPECT_EQ(c.decision.cmd.v, 0.0);
  EXPECT_GT(std::abs(c.decision.cmd.w), 0.1) << "it must turn";
  EXPECT_FALSE(c.goal_reached);
  // Without the request the same robot drives along its route.
  Navigator m(goalParams(), longRobot());
  const auto d = cycleIn(m, corridor(1.5), false);
  EXPECT_GT(d.decision.cmd.v, 0.0) << d.plan.note;
}

TEST(Navigator, DoesNotTurnWhereTheFootprintCannot) {
  // Walls 0.4 m from the centre: a 1 m long body would hit them turning.
  Navigator n(goalParams(), longRobot());
  const auto c = cycleIn(n, corridor(0.4), true);
  EXPECT_FALSE(c.plan.ok);
  EXPECT_EQ(c.decision.action, SafetyAction::Stop);
  EXPECT_EQ(c.decision.cmd.v, 0.0);
  EXPECT_EQ(c.decision.cmd.w, 0.0);
}

TEST(Navigator, AWalkerIgnoresTheRotateRequest) {
  NavigationParams p;
  p.plugin = "user-intent-dwa";
  Navigator n(p, longRobot());
  n.setOdometry({0, 0, 0}, {0, 0}, 1.0);
  n.addObstaclePoints(corridor(1.5), 1.0);
  n.setUserIntent({0.3, 0}, 1.0);
  n.setRotateRequest(true);
  const auto c = n.cycle(1.0);
  EXPECT_GT(c.decision.cmd.v, 0.0) << "the user drives a walker: " << c.plan.note;
}
