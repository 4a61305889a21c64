// The Navigator's own behaviours (beyond the planners and the supervisor):
// turning in place when localisation asks for it (HOBBIT, [Puente14, App. Fig. 8]).
#include <carenav/navigation/navigator.h>

#include <mrpt/obs/CObservation2DRangeScan.h>

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

TEST(Navigator, TheCyclesPoseIsTheOdometryCarriedForwardToItsTime) {
  // Odometry read 0.1 s before the cycle (the sensors' last frame) while
  // driving at 0.4 m/s: the robot is 4 cm nearer to the wall ahead by now.
  std::vector<TPoint2D> wall;
  for (double y = -1; y <= 1; y += 0.02) wall.push_back({1.5, y});
  auto clearanceAt = [&](double now) {
    Navigator n(goalParams(), longRobot());
    n.setOdometry({0, 0, 0}, {0.4, 0}, 1.0);
    n.addObstaclePoints(wall, 1.0);
    return n.cycle(now).clearance;
  };
  // (The clearance is measured on the 5 cm grid: 0.25 s, 10 cm.)
  const double at_once = clearanceAt(1.0), later = clearanceAt(1.25);
  EXPECT_NEAR(at_once, 1.0, 0.03);
  EXPECT_NEAR(at_once - later, 0.1, 0.03);
  // Never carried forward past odom_timeout: the supervisor stops then.
  EXPECT_NEAR(at_once - clearanceAt(3.0), 0.4 * NavigationParams{}.odom_timeout, 0.06);
}

// ------------------------------------------------- moving obstacles (people)

TEST(FreeSpaceHistoryTest, AnObstacleWhereFreeSpaceWasIsMovingAWallIsNot) {
  FreeSpaceHistory h(0.05, 5.0);
  // Ten scans see the floor at (1, 0) free.
  for (int k = 0; k < 10; ++k) h.markFree(1.0, 0.0, 0.1 * k);
  EXPECT_TRUE(h.recentlyFree(1.0, 0.0, 1.0, 1.5, 0.3)) << "a person stepping in there moves";
  EXPECT_FALSE(h.recentlyFree(1.0, 0.0, 3.0, 1.5, 0.3)) << "standing 2 s later: static";
  // A wall's edge cell flickers: free, hit, free, hit... never a stretch.
  for (int k = 0; k < 10; ++k) {
    if (k % 2)
      h.markHit(2.0, 0.0, 0.1 * k);
    else
      h.markFree(2.0, 0.0, 0.1 * k);
  }
  EXPECT_FALSE(h.recentlyFree(2.0, 0.0, 1.0, 1.5, 0.3));
  EXPECT_FALSE(h.recentlyFree(3.0, 0.0, 1.0, 1.5, 0.3)) << "never seen";
}

TEST(FreeSpaceHistoryTest, AThinPostsEdgeCellGrazedFreeIsNotMovingAPersonIs) {
  FreeSpaceHistory h(0.05, 5.0);
  // A post's edge cell: hit for 2 s while the robot approaches, then grazed
  // by rays passing its free part for 0.6 s (the robot turned), then hit again.
  for (int k = 0; k < 20; ++k) h.markHit(1.0, 0.0, 0.1 * k);
  for (int k = 20; k < 26; ++k) h.markFree(1.0, 0.0, 0.1 * k);
  h.markHit(1.0, 0.0, 2.6);
  EXPECT_FALSE(h.recentlyFree(1.0, 0.0, 2.6, 1.5, 0.3, 10.0)) << "hit 0.1 s before: static";
  EXPECT_TRUE(h.recentlyFree(1.0, 0.0, 2.6, 1.5, 0.3, 0.0)) << "without the rule: moving";
  // Open floor, never hit, seen free for 0.6 s: a person stepping in moves.
  for (int k = 20; k < 26; ++k) h.markFree(2.0, 0.0, 0.1 * k);
  h.markHit(2.0, 0.0, 2.6);
  EXPECT_TRUE(h.recentlyFree(2.0, 0.0, 2.6, 1.5, 0.3, 10.0));
  // ... and a cell last hit 20 s before its free stretch counts as open floor again.
  h.markHit(3.0, 0.0, 0.0);
  for (int k = 200; k < 206; ++k) h.markFree(3.0, 0.0, 0.1 * k);
  EXPECT_TRUE(h.recentlyFree(3.0, 0.0, 20.6, 1.5, 0.3, 10.0));
}

TEST(FreeSpaceHistoryTest, TheCellDiagonalToAPostsCornerIsNotMovingAPersonBesideAWallIs) {
  const double r = 0.05;
  // Cell centres: a post's corner cell at (1.025, 0.025), hit all along;
  // every cell around it seen free for 0.6 s by rays passing the corner;
  // then range noise puts one hit of the corner in the diagonal cell.
  FreeSpaceHistory h(r, 5.0);
  for (int k = 0; k < 6; ++k)
    for (int dy = -2; dy <= 2; ++dy)
      for (int dx = -2; dx <= 2; ++dx)
        if (dx != 1 || dy != 1) h.markFree(0.975 + dx * r, -0.025 + dy * r, 0.1 * k);
  for (int k = 0; k <= 6; ++k) h.markHit(1.025, 0.025, 0.1 * k);
  h.markHit(0.975, -0.025, 0.6);
  EXPECT_FALSE(h.movedIn(0.975, -0.025, 0.6, 1.5, 0.3)) << "the post's own noise";
  // Pruned as the Navigator prunes (hits kept for the window), the corner
  // cell, never seen free and last hit 0.1 s ago, is still there a cycle later.
  h.prune(0.7, 2.5, 1.5);
  h.markHit(0.975, -0.025, 0.7);
  EXPECT_FALSE(h.movedIn(0.975, -0.025, 0.7, 1.5, 0.3)) << "after a prune";
  // The same without the post (its cell seen free as well): moved in.
  FreeSpaceHistory open(r, 5.0);
  for (int k = 0; k < 6; ++k)
    for (int dy = -2; dy <= 2; ++dy)
      for (int dx = -2; dx <= 2; ++dx) open.markFree(0.975 + dx * r, -0.025 + dy * r, 0.1 * k);
  open.markHit(0.975, -0.025, 0.6);
  EXPECT_TRUE(open.movedIn(0.975, -0.025, 0.6, 1.5, 0.3));
  // A person beside a wall (cells y < 0 are the wall, hit all along): the
  // body's cells one cell off the wall moved in, the one against it not.
  FreeSpaceHistory wall(r, 5.0);
  for (int k = 0; k < 6; ++k)
    for (int iy = 0; iy < 6; ++iy)
      for (int ix = 0; ix < 6; ++ix) wall.markFree(0.025 + ix * r, 0.025 + iy * r, 0.1 * k);
  for (int k = 0; k <= 6; ++k)
    for (int ix = 0; ix < 6; ++ix) wall.markHit(0.025 + ix * r, -0.025, 0.1 * k);
  wall.markHit(0.125, 0.025, 0.6);
  wall.markHit(0.125, 0.075, 0.6);
  EXPECT_FALSE(wall.movedIn(0.125, 0.025, 0.6, 1.5, 0.3));
  EXPECT_TRUE(wall.movedIn(0.125, 0.075, 0.6, 1.5, 0.3));
  // A person walking in: the cell behind its new front was free for 1 s,
  // then flickered (hit, free once, hit) under the body's jitter; it was hit
  // only after the new front cell was seen free: no static obstacle.
  FreeSpaceHistory walk(r, 5.0);
  for (int k = 0; k <= 10; ++k)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) walk.markFree(1.025 + dx * r, 0.025 + dy * r, 0.1 * k);
  walk.markHit(1.075, 0.025, 1.05);
  walk.markFree(1.075, 0.025, 1.1);
  walk.markHit(1.075, 0.025, 1.15);
  walk.markHit(1.025, 0.025, 1.2);
  EXPECT_TRUE(walk.movedIn(1.025, 0.025, 1.2, 1.5, 0.3));
}

namespace {

/** A 2D lidar scan at the robot's origin: 181 beams over 180 deg hitting a
 *  wall at x = 3 m, and the obstacle `blob_x` ahead across |y| < 0.15 m when
 *  `blob` is set. */
mrpt::obs::CObservation2DRangeScan scanWith(bool blob, double blob_x) {
  mrpt::obs::CObservation2DRangeScan s;
  s.aperture = static_cast<float>(M_PI);
  s.rightToLeft = true;
  s.maxRange = 10;
  s.resizeScan(181);
  for (size_t i = 0; i < 181; ++i) {
    const double a = -M_PI / 2 + M_PI * static_cast<double>(i) / 180;
    double r = std::abs(std::cos(a)) > 0.2 ? 3.0 / std::cos(a) : 9.0;
    if (r < 0) r = 9.0;
    if (blob && std::cos(a) > 0 && std::abs(blob_x * std::tan(a)) < 0.15) r = blob_x / std::cos(a);
    s.setScanRange(i, static_cast<float>(std::min(r, 9.0)));
    s.setScanRangeValidity(i, true);
  }
  return s;
}

}  // namespace

TEST(Navigator, APersonSteppingIntoTheWayStopsTheRobotEarlierThanABox) {
  // The same obstacle 0.6 m ahead of the front: stepping in where the lidar
  // saw free floor (a person), it is grown by predict_speed x predict_time and
  // the robot must not drive on as fast; a box that was always there leaves room.
  auto run = [](bool seen_free_before) {
    Navigator n(goalParams(), longRobot());
    n.setRoute({{0, 0}, {5, 0}}, {5, 0, 0});
    for (int k = 0; k < 10; ++k) {
      const double t = 0.1 * k;
      n.setOdometry({0, 0, 0}, {0, 0}, t);
      n.addObservation(scanWith(!seen_free_before, 1.1), {0, 0, 0}, t);
      n.cycle(t);
    }
    n.setOdometry({0, 0, 0}, {0.3, 0}, 1.0);
    n.addObservation(scanWith(true, 1.1), {0, 0, 0}, 1.0);
    const auto c = n.cycle(1.0);
    return std::make_pair(c, n.moving().size());
  };
  const auto [box, box_moving] = run(false);
  const auto [person, person_moving] = run(true);
  EXPECT_EQ(box_moving, 0u);
  EXPECT_GE(person_moving, 3u);
  EXPECT_GT(box.decision.cmd.v, 0.05) << "0.6 m of room before a static box: " << box.plan.note;
  EXPECT_LT(person.decision.cmd.v, box.decision.cmd.v) << person.plan.note;
  // With prediction off the person is just another obstacle.
  NavigationParams off = goalParams();
  off.predict_speed = 0;
  Navigator n(off, longRobot());
  n.setRoute({{0, 0}, {5, 0}}, {5, 0, 0});
  for (int k = 0; k < 10; ++k) {
    n.setOdometry({0, 0, 0}, {0, 0}, 0.1 * k);
    n.addObservation(scanWith(false, 1.1), {0, 0, 0}, 0.1 * k);
    n.cycle(0.1 * k);
  }
  n.setOdometry({0, 0, 0}, {0.3, 0}, 1.0);
  n.addObservation(scanWith(true, 1.1), {0, 0, 0}, 1.0);
  n.cycle(1.0);
  EXPECT_TRUE(n.moving().empty());
}

TEST(Navigator, TheSupervisorJudgesMrptPtgFromTheRobotsState) {
  // mrpt-ptg plans its commands as taken at once. Driving at 1.5 m/s with
  // 2 m/s^2 of braking the robot needs 0.64 m to stop (0.56 m braking, 7.5
  // cm of latency); a wall 1 m ahead of its centre leaves 0.4 m past its
  // front and safe distance. The planner proposes a turn towards the goal
  // on its left, which is fine from a standstill but sweeps the front into
  // the wall while the robot still slides on: the supervisor, judging the
  // command from the robot's measured speed, stops it. From a standstill
  // at the same place the same turn passes.
  RobotParams r = longRobot();
  r.v_max = 2.0;
  r.w_max = 4.0;
  r.acc_v = 2.0;
  r.acc_w = 4.0;
  NavigationParams p;
  p.plugin = "mrpt-ptg";
  std::vector<TPoint2D> wall;
  for (double y = -2; y <= 2; y += 0.02) wall.push_back({1.0, y});
  auto decide = [&](double v) {
    Navigator n(p, r);
    n.setOdometry({0, 0, 0}, {v, 0}, 1.0);
    n.addObstaclePoints(wall, 1.0);
    n.setRoute({{0, 0}, {0, 3}}, {0, 3, M_PI / 2});
    return n.cycle(1.0).decision;
  };
  const SafetyDecision fast = decide(1.5);
  EXPECT_EQ(fast.action, SafetyAction::Stop) << fast.reason;
  EXPECT_EQ(fast.rule, SafetyRule::CannotBrake) << fast.reason;
  const SafetyDecision still = decide(0.0);
  EXPECT_EQ(still.action, SafetyAction::Pass) << still.reason;
  EXPECT_GT(std::abs(still.cmd.w), 0.5) << "the turn towards the goal";
}
