// The safety supervisor's rules as invariants, and the global route.
#include <carenav/common/errors.h>
#include <carenav/navigation/global_planner.h>
#include <carenav/navigation/safety.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace carenav::navigation {
namespace {

RobotParams robot() {
  RobotParams r;
  r.footprint = {{0.25, 0.325}, {-0.45, 0.325}, {-0.45, -0.325}, {0.25, -0.325}};
  r.v_max = 0.3;
  r.v_min = -0.15;
  r.w_max = 0.75;
  r.acc_v = 0.5;
  r.acc_w = 1.0;
  r.safe_distance = 0.325;
  return r;
}

SafetyInput fresh(const LocalCostmap& map, Twist cmd) {
  SafetyInput in;
  in.now = 10;
  in.last_scan_time = 9.95;
  in.last_odom_time = 9.99;
  in.plan.ok = true;
  in.plan.cmd = cmd;
  in.map = &map;
  return in;
}

TEST(Safety, ATurnOnTheSpotKeepsTheSafeDistanceAtTheCorner) {
  // A post beside the front-left corner: turning left sweeps the corner into
  // it. The braking margin is of swept distance (the corner's travel), so a
  // turn that would stop short of the post but within safe_distance of it
  // is slowed or stopped; turning right, away from it, passes.
  NavigationParams p;
  RobotParams r = robot();
  r.safe_distance = 0.1;
  const SafetySupervisor sup(p, r);
  LocalCostmap map(p, Footprint(r.footprint, p.resolution));
  // The corner (0.25, 0.325) is 0.41 m from the origin; a post 0.12 m along
  // its arc, turning left (contact after ~0.29 rad, braking from 0.75 rad/s
  // at 1 rad/s^2 takes 0.28 rad: the corner stops ~0.004 m short).
  const double a = std::atan2(0.325, 0.25) + 0.12 / std::hypot(0.25, 0.325);
  const double R = std::hypot(0.25, 0.325);
  map.build({0, 0}, {{R * std::cos(a), R * std::sin(a)}});
  const SafetyDecision left = sup.apply(fresh(map, {0, 0.75}));
  EXPECT_LT(std::abs(left.cmd.w), 0.75) << "slowed or stopped: " << left.reason;
  EXPECT_NE(left.action, SafetyAction::Pass);
  const SafetyDecision right = sup.apply(fresh(map, {0, -0.75}));
  EXPECT_EQ(right.action, SafetyAction::Pass) << right.reason;
}

TEST(Safety, StaleSensorsOdometryOrIntentStop) {
  NavigationParams p;
  const SafetySupervisor sup(p, robot());
  LocalCostmap map(p, Footprint(robot().footprint, p.resolution));
  map.build({0, 0}, {});
  SafetyInput in = fresh(map, {0.3, 0});
  EXPECT_EQ(sup.apply(in).action, SafetyAction::Pass);
  in.last_scan_time = 10 - p.sensor_timeout - 0.01;
  auto d = sup.apply(in);
  EXPECT_EQ(d.action, SafetyAction::Stop);
  EXPECT_EQ(d.cmd.v, 0);
  EXPECT_EQ(d.rule, SafetyRule::StaleSensor);
  in.last_scan_time.reset();  // never had a scan
  EXPECT_EQ(sup.apply(in).action, SafetyAction::Stop);
  in = fresh(map, {0.3, 0});
  in.last_odom_time = 10 - p.odom_timeout - 0.01;
  EXPECT_EQ(sup.apply(in).rule, SafetyRule::StaleOdometry);
  // Walker: the user's command must be fresh and non-zero.
  in = fresh(map, {0.3, 0});
  in.needs_intent = true;
  in.user = Twist{0.3, 0};
  in.last_intent_time = 9.9;
  EXPECT_EQ(sup.apply(in).action, SafetyAction::Pass);
  in.last_intent_time = 10 - p.intent_timeout - 0.01;
  EXPECT_EQ(sup.apply(in).rule, SafetyRule::StaleIntent);
  in.last_intent_time = 9.9;
  in.user = Twist{0.0, 0.0};
  EXPECT_EQ(sup.apply(in).rule, SafetyRule::UserStopped);
  // No admissible trajectory.
  in = fresh(map, {0.3, 0});
  in.plan.ok = false;
  in.plan.mark(PlanStatus::NoAdmissible);
  EXPECT_EQ(sup.apply(in).action, SafetyAction::Stop);
  EXPECT_EQ(sup.apply(in).rule, SafetyRule::NoPlan);
  EXPECT_EQ(sup.apply(in).reason, "no admissible trajectory");  // the planner's note
}

TEST(Safety, NeverCommandsAVelocityThatCannotBrakeBeforeASeenObstacle) {
  // Random clutter and random commands: whatever the planner asks, the
  // supervisor's output brakes (proportionally, at the robot's limits)
  // safe_distance before the first contact along its arc.
  NavigationParams p;
  const RobotParams r = robot();
  const SafetySupervisor sup(p, r);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(-1, 1);
  size_t slowed = 0, stopped = 0, passed = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::vector<TPoint2D> obs;
    const int n = static_cast<int>(rng() % 6);
    for (int k = 0; k < n; ++k) {
      // Posts between 0.4 and 2.5 m away, not under the robot.
      const double a = U(rng) * M_PI, d = 0.6 + std::abs(U(rng)) * 1.9;
      obs.push_back({d * std::cos(a), d * std::sin(a)});
    }
    LocalCostmap map(p, Footprint(r.footprint, p.resolution));
    map.build({0, 0}, obs);
    const Twist asked{0.3 * U(rng) + 0.05, 0.75 * U(rng)};
    const SafetyDecision d = sup.apply(fresh(map, asked));
    passed += d.action == SafetyAction::Pass;
    slowed += d.action == SafetyAction::Slow;
    stopped += d.action == SafetyAction::Stop;
    EXPECT_LE(d.cmd.v, r.v_max + 1e-12);
    EXPECT_GE(d.cmd.v, r.v_min - 1e-12);
    EXPECT_LE(std::abs(d.cmd.w), r.w_max + 1e-12);
    if (d.cmd.v == 0 && d.cmd.w == 0) continue;
    // Same curvature as asked (never steers somewhere else).
    EXPECT_NEAR(d.cmd.v * std::clamp(asked.w, -r.w_max, r.w_max),
                d.cmd.w * std::clamp(asked.v, r.v_min, r.v_max), 1e-9);
    const double ttc = sup.timeToCollision(map, {0, 0, 0}, d.cmd, 30);
    EXPECT_TRUE(canBrake(d.cmd, ttc, r, r.safe_distance * 0.999))
        << "trial " << trial << ": (" << d.cmd.v << ", " << d.cmd.w << ") ttc " << ttc;
  }
  // The scenes exercise every branch.
  EXPECT_GT(passed, 10u);
  EXPECT_GT(slowed, 5u);
  EXPECT_GT(stopped, 0u);
}

TEST(Safety, SlowsTowardsAWallAndStopsAtTheSafeDistance) {
  NavigationParams p;
  p.footprint_padding = 0.05;  // the numbers below count contact from 5 cm
  const RobotParams r = robot();
  const SafetySupervisor sup(p, r);
  std::vector<TPoint2D> wall;
  for (double y = -2; y <= 2; y += 0.02) wall.push_back({1.0, y});
  LocalCostmap map(p, Footprint(r.footprint, p.resolution));
  map.build({0, 0}, wall);
  // Contact counts from footprint_padding (0.05 m) on. Front edge 0.75 m
  // from the wall: 0.3 m/s needs 0.09 m to stop, plus the 0.325 m margin:
  // allowed.
  EXPECT_EQ(sup.apply(fresh(map, {0.3, 0})).action, SafetyAction::Pass);
  // 0.3 m from the wall (inside the margin): stop; backing away is fine.
  SafetyInput in = fresh(map, {0.3, 0});
  in.pose = {0.45, 0, 0};
  EXPECT_EQ(sup.apply(in).action, SafetyAction::Stop);
  in.plan.cmd = {-0.1, 0};
  EXPECT_EQ(sup.apply(in).action, SafetyAction::Pass);
  // 0.55 m from the wall (0.5 m to contact): 0.3 m/s stops within 0.09 m, 0.415 m with the
  // margin: passes.
  in.pose = {0.2, 0, 0};
  in.plan.cmd = {0.3, 0};
  EXPECT_EQ(sup.apply(in).action, SafetyAction::Pass);
  // 0.45 m from the wall (0.4 m to contact): capped so that v^2 / 2a <= 0.4 - 0.325.
  in.pose = {0.3, 0, 0};
  const auto d = sup.apply(in);
  EXPECT_EQ(d.action, SafetyAction::Slow);
  EXPECT_LT(d.cmd.v, 0.3);
  EXPECT_GT(d.cmd.v, 0.05);
  EXPECT_LE(d.cmd.v * d.cmd.v / (2 * r.acc_v), 0.4 - r.safe_distance + 0.01);
}

/** A 10 x 6 m map: two rooms joined by a door in a wall at x = 5. */
mrpt::maps::COccupancyGridMap2D twoRooms(double door_width, bool unknown_gap) {
  mrpt::maps::COccupancyGridMap2D g(0, 10, 0, 6, 0.05);
  g.fill(0.95f);
  auto wall = [&](double x0, double y0, double x1, double y1, float p) {
    for (double x = x0; x <= x1; x += 0.025)
      for (double y = y0; y <= y1; y += 0.025) g.setPos(x, y, p);
  };
  wall(0, 0, 10, 0.1, 0.05f);
  wall(0, 5.9, 10, 6, 0.05f);
  wall(0, 0, 0.1, 6, 0.05f);
  wall(9.9, 0, 10, 6, 0.05f);
  // Dividing wall with a door centred at y = 1.5.
  wall(4.95, 0, 5.05, 1.5 - door_width / 2, 0.05f);
  wall(4.95, 1.5 + door_width / 2, 5.05, 6, 0.05f);
  // A gap of unknown space in the wall near the top (never seen).
  if (unknown_gap) wall(4.95, 4.0, 5.05, 5.0, 0.5f);
  return g;
}

TEST(GlobalPlanner, PassesADoorAndNeverRoutesThroughUnknownSpace) {
  NavigationParams p;
  const auto g = twoRooms(1.0, true);
  const GlobalPlanner gp(g, 0.25, p);
  const auto r = gp.plan({2, 4.5}, {8, 4.5});
  ASSERT_TRUE(r.has_value());
  // The straight line crosses the unknown gap; the route goes through the door.
  bool through_door = false;
  for (const auto& c : r->cells) {
    EXPECT_TRUE(gp.isFree(c.x, c.y));
    if (std::abs(c.x - 5) < 0.1) {
      EXPECT_LT(c.y, 2.1) << c.y;
      through_door = true;
    }
  }
  EXPECT_TRUE(through_door);
  EXPECT_GT(r->length, 8.0);  // the detour, not the 6 m straight line
  EXPECT_GE(r->waypoints.size(), 2u);
  EXPECT_NEAR(r->waypoints.back().x, 8, 1e-9);
  // Every cell keeps the robot's radius from anything not free, except near
  // the start and goal.
  for (const auto& c : r->cells) EXPECT_GT(gp.clearance(c.x, c.y), 0.25);
}

TEST(GlobalPlanner, NoRouteThroughADoorNarrowerThanTheRobot) {
  NavigationParams p;
  const auto g = twoRooms(0.5, false);
  const GlobalPlanner gp(g, 0.325, p);
  EXPECT_FALSE(gp.plan({2, 3}, {8, 3}).has_value());
  const GlobalPlanner small(g, 0.1, p);
  EXPECT_TRUE(small.plan({2, 3}, {8, 3}).has_value());
  EXPECT_THROW(gp.plan({2, 3}, {20, 3}), InputError);  // outside the map
  EXPECT_THROW(gp.plan({2, 3}, {5, 3}), InputError);   // on the wall
}

TEST(GlobalPlanner, WithoutRoomToSpareTakesTheWidestPassageNotTheNearest) {
  // twoRooms' door at y = 1.5 on the straight way and a second door at
  // y = `upper_y`, farther round; both narrower than the robot's diameter
  // plus 2 x plan_clearance. The route used to fall back to the footprint's
  // padding and take the nearest door, however tight; it takes the widest.
  NavigationParams p;
  p.plan_clearance = 0.2;  // footprint_padding 0.02
  const double robot = 0.22;
  for (const double upper_y : {3.0, 4.0, 4.5}) {
    for (const bool wider_up : {true, false}) {
      auto g = twoRooms(wider_up ? 0.55 : 0.75, false);
      for (double x = 4.95; x <= 5.05; x += 0.025)
        for (double y = -0.5; y <= 0.5; y += 0.025)
          if (std::abs(y) < (wider_up ? 0.75 : 0.55) / 2) g.setPos(x, upper_y + y, 0.95f);
      const GlobalPlanner gp(g, robot, p);
      const double low = gp.clearance(5, 1.5), up = gp.clearance(5, upper_y);
      ASSERT_LT(std::max(low, up), robot + p.plan_clearance) << "both doors too narrow to spare";
      ASSERT_GT(std::abs(up - low), 0.04);
      const auto r = gp.plan({2, 1.5}, {8, 1.5});
      ASSERT_TRUE(r.has_value()) << upper_y;
      bool upper = false;
      for (const auto& c : r->cells) upper = upper || (std::abs(c.x - 5) < 0.1 && c.y > 2.5);
      EXPECT_EQ(upper, wider_up) << "door at " << upper_y;
      EXPECT_GT(r->radius, std::min(low, up));
      EXPECT_LE(r->radius, std::max(low, up));
      EXPECT_TRUE(gp.polylineClear(r->waypoints, 0.3, r->radius));
    }
  }
  // One door only, narrower than robot + plan_clearance: taken, keeping the
  // most it allows; narrower than robot + footprint_padding: no route.
  const GlobalPlanner one(twoRooms(0.55, false), robot, p);
  const auto r = one.plan({2, 1.5}, {8, 1.5});
  ASSERT_TRUE(r.has_value());
  EXPECT_GT(r->radius, robot + p.footprint_padding);
  const GlobalPlanner tight(twoRooms(0.45, false), robot, p);
  EXPECT_FALSE(tight.plan({2, 1.5}, {8, 1.5}).has_value());
}

/** Two walls across a 10 x 3 m corridor at x = 5 and x = 6, each with a
 *  0.9 m door centred at y = 1.5: two narrow passages 1 m apart. */
mrpt::maps::COccupancyGridMap2D twoDoors() {
  mrpt::maps::COccupancyGridMap2D g(0, 10, 0, 3, 0.05);
  g.fill(0.95f);
  auto wall = [&](double x0, double y0, double x1, double y1) {
    for (double x = x0; x <= x1; x += 0.025)
      for (double y = y0; y <= y1; y += 0.025) g.setPos(x, y, 0.05f);
  };
  wall(0, 0, 10, 0.1);
  wall(0, 2.9, 10, 3);
  for (const double x : {5.0, 6.0}) {
    wall(x - 0.05, 0, x + 0.05, 1.05);
    wall(x - 0.05, 1.95, x + 0.05, 3);
  }
  return g;
}

TEST(GlobalPlanner, PassagesCloserThanTheirApproachNeverSendTheRobotBack) {
  // Each passage adds a waypoint passage_approach before and after its
  // throat. The second door's "before" lies behind the first door's
  // "after", and a robot standing within passage_approach of a throat has
  // its "before" behind it: a route through them went back and forth, and
  // the robot turned round to reach a waypoint it had passed. Nearer to a
  // throat than its approach point, the route goes into the throat.
  NavigationParams p;
  const auto g = twoDoors();
  const GlobalPlanner gp(g, 0.25, p);
  for (const double x0 : {2.0, 4.7, 5.3}) {
    const auto r = gp.plan({x0, 1.5}, {8, 1.5});
    ASSERT_TRUE(r.has_value()) << x0;
    double last = x0;
    for (const auto& w : r->waypoints) {
      EXPECT_GT(w.x, last - 0.02) << "from x = " << x0 << ": a waypoint behind the one before";
      last = std::max(last, w.x);
    }
    EXPECT_TRUE(gp.polylineClear(r->waypoints, 0.3)) << x0;
  }
}

/** twoRooms() with a second 1 m door in the dividing wall, centred at y = 4.5. */
mrpt::maps::COccupancyGridMap2D twoDoorsInAWall() {
  auto g = twoRooms(1.0, false);
  for (double x = 4.95; x <= 5.05; x += 0.025)
    for (double y = 4.0; y <= 5.0; y += 0.025) g.setPos(x, y, 0.95f);
  return g;
}

/** The least distance from `p` to the route's cells. */
double routeDistance(const Route& r, const TPoint2D& p) {
  double d = 1e9;
  for (const auto& c : r.cells) d = std::min(d, std::hypot(c.x - p.x, c.y - p.y));
  return d;
}

TEST(RouteReplanner, PlansAroundAPlaceWhereRecoveriesKeepBeginning) {
  // The robot keeps getting stuck at the lower door (the clutter
  // benchmark's timeouts: 4-16 recoveries at one gap's mouth, the route
  // replanned through it each time, as nothing the robot saw blocked it).
  // After avoid_after recoveries there, the route goes through the other door.
  NavigationParams p;
  const auto g = twoDoorsInAWall();
  const GlobalPlanner gp(g, 0.25, p);
  const TPoint2D from{2, 1.5}, goal{8, 1.5}, door{5, 1.5};
  const auto first = gp.plan(from, goal);
  ASSERT_TRUE(first.has_value());
  ASSERT_LT(routeDistance(*first, door), 0.1);
  RouteReplanner rp(10, 2, 0.2);
  EXPECT_FALSE(rp.recovered({4.8, 1.45}));
  // One recovery: the route is still clear, it stays.
  EXPECT_FALSE(rp.step(false, g, {}, from, goal, first, 0.25, 0.5, p).has_value());
  EXPECT_TRUE(rp.recovered({4.9, 1.6}));  // within 2 x 0.2 m of the first: the same place
  ASSERT_EQ(rp.avoided().size(), 1u);
  const auto second = rp.step(false, g, {}, from, goal, first, 0.25, 0.5, p);
  ASSERT_TRUE(second.has_value());
  EXPECT_GT(routeDistance(*second, rp.avoided()[0]), 0.2 + 0.25);
  bool upper = false;
  for (const auto& c : second->cells) upper = upper || (std::abs(c.x - 5) < 0.1 && c.y > 3.9);
  EXPECT_TRUE(upper);
  // Later replans keep clear of it too (the upper route is clear: kept).
  EXPECT_FALSE(rp.step(false, g, {}, from, goal, second, 0.25, 0.5, p).has_value());
  // A new goal forgets it.
  rp.newGoal();
  EXPECT_TRUE(rp.avoided().empty());
}

TEST(RouteReplanner, KeepsTheRouteWhenNoneAvoidsThePlaceOrAvoidingIsOff) {
  NavigationParams p;
  const auto g = twoRooms(1.0, false);  // one door only
  const GlobalPlanner gp(g, 0.25, p);
  const TPoint2D from{2, 1.5}, goal{8, 1.5};
  const auto route = gp.plan(from, goal);
  ASSERT_TRUE(route.has_value());
  RouteReplanner rp(10, 2, 0.2);
  rp.recovered({5, 1.5});
  rp.recovered({5, 1.5});
  EXPECT_FALSE(rp.step(false, g, {}, from, goal, route, 0.25, 0.5, p).has_value());
  // A place at the robot itself (it could not leave it) or at the goal is not avoided.
  RouteReplanner at_start(10, 1, 0.2);
  at_start.recovered(from);
  const auto same = at_start.step(false, g, {}, from, goal, route, 0.25, 0.5, p);
  ASSERT_TRUE(same.has_value());  // planned anew, through the same door
  EXPECT_NEAR(same->length, route->length, 1e-6);
  RouteReplanner off(10, 0, 0.2);
  for (int i = 0; i < 5; ++i) EXPECT_FALSE(off.recovered({5, 1.5}));
  EXPECT_TRUE(off.avoided().empty());
}

}  // namespace
}  // namespace carenav::navigation
