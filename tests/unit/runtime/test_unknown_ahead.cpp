// Unknown floor ahead of a moving robot within its braking distance is not
// traversable (carenav/runtime/unknown_ahead.h, docs/navigate.md).
#include <carenav/navigation/navigator.h>
#include <carenav/perception/occupancy.h>
#include <carenav/runtime/unknown_ahead.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace carenav;
using namespace carenav::navigation;

namespace {

RobotParams walker() {
  RobotParams r;
  r.control = "user-intent";
  r.footprint = {{0.25, 0.325}, {-0.45, 0.325}, {-0.45, -0.325}, {0.25, -0.325}};
  r.v_max = 0.3;
  r.v_min = 0;
  r.acc_v = 0.5;
  r.safe_distance = 0.25;
  return r;
}

/** A perception grid around a robot at the origin facing +x: the floor seen
 *  free out to 3 m, except (shadow) x in [0.3, 1.2) m, no evidence there. */
perception::LocalOccupancy gridWithShadow(bool shadow) {
  perception::LocalOccupancy g(200, 0.05, 5.0);
  g.moveTo(mrpt::poses::CPose2D(0, 0, 0));
  for (int f = 0; f < 3; ++f) {
    g.beginFrame();
    for (int i = 0; i < g.cells(); ++i)
      for (int j = 0; j < g.cells(); ++j) {
        const double x = g.centreX(i), y = g.centreY(j);
        if (std::hypot(x, y) > 3.0) continue;
        if (shadow && x >= 0.3 && x < 1.2 && std::abs(y) < 1.0) continue;
        g.addEvidence(i, j, 0.2f);
      }
    g.endFrame();
  }
  return g;
}

UnknownAhead zone() {
  UnknownAheadParams p;  // latency 0.05 s, 10 Hz control and camera
  return UnknownAhead(walker(), p, 0.05);
}

/** One cycle of a walker pushed forward at 0.3 m/s while moving at v, with
 *  the grid's unknown cells ahead as its only obstacles. */
Navigator::Cycle pushedWalker(const perception::LocalOccupancy& g, double v) {
  NavigationParams p;
  p.plugin = "user-intent-dwa";
  Navigator n(p, walker());
  UnknownAhead u = zone();  // no start: the shadow is met while driving
  n.setOdometry({0, 0, 0}, {v, 0}, 1.0);
  n.setPerceivedObstacles(u.cells(g, {0, 0, 0}, v), 1.0);
  n.setUserIntent({0.3, 0}, 1.0);
  return n.cycle(1.0);
}

}  // namespace

TEST(UnknownAhead, BrakingDistanceFromSpeedReactionTimeAndDeceleration) {
  EXPECT_DOUBLE_EQ(brakingDistance(0, 0.5, 0.25), 0.0);
  EXPECT_NEAR(brakingDistance(0.3, 0.5, 0.25), 0.3 * 0.25 + 0.09, 1e-12);
  EXPECT_NEAR(brakingDistance(-0.3, 0.5, 0.25), 0.3 * 0.25 + 0.09, 1e-12) << "reversing too";
  // The zone: safe_distance plus the braking distance with latency + one cycle + one frame.
  EXPECT_NEAR(zone().reach(0.3), 0.25 + 0.165, 1e-12);
}

TEST(UnknownAhead, AShadowJustAheadOfAMovingWalkerIsNotTraversable) {
  const auto shadow = gridWithShadow(true);
  const auto cells = zone().cells(shadow, {0, 0, 0}, 0.3);
  ASSERT_FALSE(cells.empty());
  for (const auto& c : cells) {
    EXPECT_GE(c.x, 0.25);
    EXPECT_LE(c.x, 0.25 + 0.415 + 1e-9) << "only within the braking distance";
    EXPECT_LE(std::abs(c.y), 0.325 + 1e-9) << "only across the footprint";
  }
  const auto c = pushedWalker(shadow, 0.3);
  EXPECT_LT(c.decision.cmd.v, 0.15) << "slowed or stopped before the unknown floor: " << c.plan.note
                                    << " / " << c.decision.reason;
}

TEST(UnknownAhead, TheSameFloorSeenFreeLetsTheWalkerPass) {
  const auto seen = gridWithShadow(false);
  EXPECT_TRUE(zone().cells(seen, {0, 0, 0}, 0.3).empty());
  const auto c = pushedWalker(seen, 0.3);
  EXPECT_GT(c.decision.cmd.v, 0.25) << c.plan.note << " / " << c.decision.reason;
}

TEST(UnknownAhead, TheStartAndFloorTheRobotStoodOnStayKnown) {
  // A grid with no evidence at all: only the zone ahead counts.
  perception::LocalOccupancy g(200, 0.05, 5.0);
  UnknownAhead u = zone();
  const auto before = u.cells(g, {0, 0, 0}, 0.0);
  ASSERT_FALSE(before.empty()) << "standing: safe_distance ahead is still looked at";
  for (const auto& c : before) EXPECT_GT(c.x, 0.25);
  // The start: the footprint and the zone at full speed ahead of it.
  u.stoodOn({0, 0, 0});
  EXPECT_TRUE(u.cells(g, {0, 0, 0}, 0.3).empty());
  // Turned a quarter to the left on the spot: ahead (+y) beyond the old
  // footprint nobody has seen.
  const auto turned = u.cells(g, {0, 0, M_PI / 2}, 0.0);
  ASSERT_FALSE(turned.empty());
  for (const auto& c : turned) EXPECT_GT(c.y, 0.3);
  // Having driven 0.4 m that way and back, its footprint covered them.
  u.stoodOn({0, 0.4, M_PI / 2});
  EXPECT_TRUE(u.cells(g, {0, 0, M_PI / 2}, 0.0).empty());
}
