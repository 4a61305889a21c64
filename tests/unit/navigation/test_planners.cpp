// Local planners (user-intent DWA, goal DWA) and the dynamic window, with the
// walker's settings of [Rosa17, Table 5.1].
#include <carenav/common/errors.h>
#include <carenav/navigation/local_planner.h>

#include <gtest/gtest.h>

#include <cmath>

#include "fixtures.h"

namespace carenav::navigation {
namespace {

using test::walkerRobot;

NavigationParams walkerNav() {
  NavigationParams p;
  p.plugin = "user-intent-dwa";
  p.sim_time = 7.0;
  p.sim_step = 0.1;
  p.window_time = 0.5;
  return p;
}

struct Scene {
  RobotParams robot = walkerRobot();
  NavigationParams nav = walkerNav();
  Footprint fp{robot.footprint, nav.resolution};
  LocalCostmap map{nav, fp};
  explicit Scene(const std::vector<TPoint2D>& obstacles) { map.build({0, 0}, obstacles); }
  PlannerInput input(Twist user, Twist current) const {
    PlannerInput in;
    in.pose = {0, 0, 0};
    in.current = current;
    in.map = &map;
    in.user = user;
    return in;
  }
};

std::vector<TPoint2D> segment(TPoint2D a, TPoint2D b) {
  std::vector<TPoint2D> out;
  const double len = std::hypot(b.x - a.x, b.y - a.y);
  for (double s = 0; s <= len; s += 0.02)
    out.push_back({a.x + (b.x - a.x) * s / len, a.y + (b.y - a.y) * s / len});
  return out;
}

TEST(Arc, IntegrationIsExact) {
  const TPose2D p = integrateArc({0, 0, 0}, 1.0, M_PI / 2, 1.0);  // quarter circle, r = 2/pi
  EXPECT_NEAR(p.x, 2 / M_PI, 1e-12);
  EXPECT_NEAR(p.y, 2 / M_PI, 1e-12);
  EXPECT_NEAR(p.phi, M_PI / 2, 1e-12);
  const TPose2D q = integrateArc({1, 2, M_PI}, 0.5, 0, 2.0);
  EXPECT_NEAR(q.x, 0, 1e-12);
  EXPECT_NEAR(q.y, 2, 1e-12);
}

TEST(Rollout, BeyondTheHorizonContactIsStillFoundAndClosedCirclesEnd) {
  NavigationParams p;
  const RobotParams r = test::walkerRobot();
  Footprint fp(r.footprint, p.resolution);
  LocalCostmap map(p, fp);
  // A slow arc (radius 0.4 m): the 1 s horizon covers 0.5 rad of it.
  const Twist slow{0.2, 0.5};
  map.build({0, 0}, {});
  Trajectory free = rollout(map, {0, 0, 0}, slow, 1.0, 0.1, 0.3, 4.0);
  EXPECT_TRUE(free.admissible());
  EXPECT_TRUE(std::isinf(free.contact_time)) << "a closed circle in free space never touches";
  // A post on the far side of that circle: met after about half a turn,
  // beyond the horizon (contact only), at the right time.
  map.build({0, 0}, {{0.0, 0.8}});
  const Trajectory post = rollout(map, {0, 0, 0}, slow, 1.0, 0.1, 0.3, 4.0);
  EXPECT_TRUE(post.admissible()) << "no contact within the horizon";
  EXPECT_GT(post.contact_time, 1.0);
  EXPECT_LT(post.contact_time, M_PI / 0.5);
  EXPECT_NEAR(post.free_distance, post.contact_time * (0.2 + 0.5 * fp.circumscribed), 1e-9);
}

TEST(DynamicWindow, SeedSettingsGiveTwelveForwardAndTwelveBackward) {
  const Window w = dynamicWindow({0, 0}, walkerRobot(), walkerNav());
  EXPECT_NEAR(w.v_lo, -0.15, 1e-12);  // v_min reached within 0.5 s at 0.5 m/s^2
  EXPECT_NEAR(w.v_hi, 0.25, 1e-12);   // 0 + 0.5 * 0.5
  EXPECT_NEAR(w.w_lo, -0.5, 1e-12);
  const auto s = sampleWindow(w, walkerNav());
  size_t fwd = 0, back = 0;
  for (const auto& t : s) {
    fwd += t.v > 0 && std::abs(t.w) < 1e-9;
    back += t.v < 0 && std::abs(t.w) < 1e-9;
    EXPECT_GE(t.v, w.v_lo - 1e-12);
    EXPECT_LE(t.v, w.v_hi + 1e-12);
  }
  EXPECT_GE(fwd, 11u);  // 12 forward values, one of them may be 0
  EXPECT_GE(back, 11u);
}

TEST(UserIntentDwa, FreePathPassesTheUserCommandUnchanged) {
  Scene sc({});
  auto dwa = makeUserIntentDwa(sc.nav, sc.robot);
  for (const Twist u : {Twist{0.3, 0.0}, Twist{0.2, 0.3}, Twist{0.25, -0.2}, Twist{-0.1, 0.0}}) {
    const auto out = dwa->plan(sc.input(u, u));
    ASSERT_TRUE(out.ok) << out.note;
    EXPECT_DOUBLE_EQ(out.cmd.v, u.v);
    EXPECT_DOUBLE_EQ(out.cmd.w, u.w);
  }
}

TEST(UserIntentDwa, WallAheadIsRefusedEvenWhenPushed) {
  // A closed door across a 3 m corridor; the user keeps pushing straight at
  // full speed for 20 s (closed loop, perfect kinematics).
  auto wall = segment({2.0, -1.5}, {2.0, 1.5});
  for (const auto& side : {segment({-3, -1.5}, {2.0, -1.5}), segment({-3, 1.5}, {2.0, 1.5})})
    wall.insert(wall.end(), side.begin(), side.end());
  const RobotParams robot = walkerRobot();
  const NavigationParams nav = walkerNav();
  const Footprint fp(robot.footprint, nav.resolution);
  auto dwa = makeUserIntentDwa(nav, robot);
  TPose2D pose{0, 0, 0};
  Twist current{0.3, 0};
  for (int k = 0; k < 200; ++k) {
    LocalCostmap map(nav, fp);
    map.build({pose.x, pose.y}, wall);
    ASSERT_FALSE(map.check(pose).collision) << "hit the wall at t " << k * 0.1;
    const auto out = dwa->plan([&] {
      PlannerInput in;
      in.pose = pose;
      in.current = current;
      in.map = &map;
      in.user = Twist{0.3, 0};
      return in;
    }());
    current = out.ok ? out.cmd : Twist{};
    pose = integrateArc(pose, current.v, current.w, 0.1);
  }
  EXPECT_LT(pose.x + 0.25, 2.0);         // the front stays short of the wall
  EXPECT_GT(pose.x + 0.25, 1.0);         // after coming reasonably close
  EXPECT_LT(std::abs(current.v), 0.02);  // and it has stopped there
}

TEST(UserIntentDwa, DeviatesAroundAnObstacleAndComesBackToTheUsersHeading) {
  // Closed loop with perfect kinematics: a user walks heading 0 (steering
  // back with w_u = 1.5 * heading error, as a person does); a box stands
  // 2 m ahead over the left edge of the walker's way.
  std::vector<TPoint2D> box;
  for (double x = 2.4; x <= 2.8; x += 0.02)
    for (double y = 0.15; y <= 0.6; y += 0.02) box.push_back({x, y});
  const RobotParams robot = walkerRobot();
  const NavigationParams nav = walkerNav();
  const Footprint fp(robot.footprint, nav.resolution);
  auto dwa = makeUserIntentDwa(nav, robot);
  TPose2D pose{0, 0, 0};
  Twist current{0.3, 0};
  double min_y = 0, max_turn = 0;
  size_t deviating = 0;
  for (int k = 0; k < 200; ++k) {  // 20 s at 10 Hz
    LocalCostmap map(nav, fp);
    map.build({pose.x, pose.y}, box);
    ASSERT_FALSE(map.check(pose).collision) << "collided at x " << pose.x;
    PlannerInput in;
    in.pose = pose;
    in.current = current;
    in.map = &map;
    const Twist user{0.3, 1.5 * std::atan2(std::sin(-pose.phi), std::cos(-pose.phi))};
    in.user = user;
    const auto out = dwa->plan(in);
    ASSERT_TRUE(out.ok) << out.note << " at x " << pose.x;
    deviating += std::hypot(out.cmd.v - user.v, out.cmd.w - user.w) > 0.05;
    current = out.cmd;
    pose = integrateArc(pose, current.v, current.w, 0.1);
    min_y = std::min(min_y, pose.y);
    max_turn = std::max(max_turn, std::abs(pose.phi));
  }
  EXPECT_GT(pose.x, 4.0);      // went past the box
  EXPECT_LT(min_y, -0.15);     // by stepping right of it (its left edge was 0.175 m too far left)
  EXPECT_GT(min_y, -0.6);      // no more than needed
  EXPECT_GT(deviating, 3u);    // the walker overrode the user for a while
  EXPECT_LT(deviating, 150u);  // and not all the time
  EXPECT_LT(std::abs(pose.phi), mrpt::DEG2RAD(5.0));  // back on the user's heading
  EXPECT_GT(max_turn, mrpt::DEG2RAD(3.0));
}

TEST(UserIntentDwa, StopsWhenTheUserLetsGoAndWhenBoxedIn) {
  Scene free_scene({});
  auto dwa = makeUserIntentDwa(free_scene.nav, free_scene.robot);
  auto out = dwa->plan(free_scene.input({0, 0}, {0.2, 0}));
  EXPECT_TRUE(out.ok);
  EXPECT_EQ(out.cmd.v, 0);
  EXPECT_EQ(out.cmd.w, 0);
  EXPECT_EQ(out.status, PlanStatus::UserStopped);
  // An obstacle inside the footprint: nothing is admissible.
  Scene boxed({{-0.1, 0.0}});
  auto dwa2 = makeUserIntentDwa(boxed.nav, boxed.robot);
  out = dwa2->plan(boxed.input({0.3, 0}, {0, 0}));
  EXPECT_FALSE(out.ok);
  EXPECT_EQ(out.admissible, 0u);
  EXPECT_GT(out.evaluated, 24u);
}

TEST(GoalDwa, HeadsForTheRouteAndTurnsInPlaceWhenItIsBehind) {
  RobotParams r = walkerRobot();
  r.v_min = 0;
  NavigationParams p;
  p.plugin = "goal-dwa";
  Footprint fp(r.footprint, p.resolution);
  LocalCostmap map(p, fp);
  map.build({0, 0}, {});
  auto dwa = makeGoalDwa(p, r);
  PlannerInput in;
  in.pose = {0, 0, 0};
  in.map = &map;
  in.current = {0.2, 0};
  in.path = {{0, 0}, {1, 1}, {2, 2}};  // 45 deg to the left
  auto out = dwa->plan(in);
  ASSERT_TRUE(out.ok) << out.note;
  EXPECT_GT(out.cmd.w, 0.1);
  EXPECT_GT(out.cmd.v, 0);
  // Route behind the robot: turn on the spot.
  in.current = {0, 0};
  in.path = {{0, 0}, {-2, 0.1}};
  out = dwa->plan(in);
  ASSERT_TRUE(out.ok) << out.note;
  EXPECT_EQ(out.cmd.v, 0);
  EXPECT_NE(out.cmd.w, 0);
  EXPECT_EQ(out.status, PlanStatus::TurnInPlace);
  // At the goal with its heading: stop.
  in.path = {{0.1, 0}};
  in.goal = TPose2D{0.1, 0, 0};
  out = dwa->plan(in);
  EXPECT_TRUE(out.ok);
  EXPECT_EQ(out.status, PlanStatus::GoalReached);
  EXPECT_EQ(out.cmd.v, 0);
}

TEST(GoalDwa, LookaheadGoesToAPassagesApproachPointInsteadOfCuttingIt) {
  // From (0, 0) to the approach point (2, 0.6), then along a door's axis y =
  // 0.6: a 17 deg corner at the approach point.
  const std::vector<TPoint2D> path{{0, 0}, {2, 0.6}, {3, 0.6}, {4, 0.6}};
  // Cutting: 1 m ahead of a robot 0.5 m before the corner lies past it.
  const TPoint2D cut = lookaheadPoint(path, 1.52, 0.46, 1.0);
  EXPECT_GT(cut.x, 2.2);
  // Stopping at corners over 10 deg: the corner itself.
  const TPoint2D stop = lookaheadPoint(path, 1.52, 0.46, 1.0, mrpt::DEG2RAD(10.0));
  EXPECT_NEAR(stop.x, 2.0, 1e-9);
  EXPECT_NEAR(stop.y, 0.6, 1e-9);
  // Within `reached` of it: on along the axis.
  const TPoint2D on = lookaheadPoint(path, 1.9, 0.57, 1.0, mrpt::DEG2RAD(10.0), 0.15);
  EXPECT_GT(on.x, 2.5);
  EXPECT_NEAR(on.y, 0.6, 1e-9);
  // A gentle bend (under the threshold) is cut as before.
  const std::vector<TPoint2D> gentle{{0, 0}, {2, 0.1}, {4, 0.1}};
  EXPECT_GT(lookaheadPoint(gentle, 1.5, 0.07, 1.0, mrpt::DEG2RAD(10.0)).x, 2.2);
}

TEST(PlannerRegistry, KnowsThePluginsByNameAndRejectsOthers) {
  const auto& reg = PlannerRegistry::instance();
  EXPECT_EQ(reg.create("user-intent-dwa", walkerNav(), walkerRobot())->name(), "user-intent-dwa");
  EXPECT_EQ(reg.create("goal-dwa", walkerNav(), walkerRobot())->name(), "goal-dwa");
  try {
    reg.create("teb", walkerNav(), walkerRobot());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("goal-dwa"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace carenav::navigation
