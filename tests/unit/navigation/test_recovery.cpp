// Recovery behaviours (back out along the recent path, turn, wait, give
// up), the planner and the supervisor sharing one notion of admissible, and
// goal-dwa's turns at a fast robot's turn rate.
#include <carenav/navigation/recovery.h>
#include <carenav/navigation/safety.h>

#include "fixtures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace carenav::navigation {
namespace {

using test::fastRobot;
using test::fastRobotAt;

/** Obstacle points every 2 cm from a to b. */
void segment(std::vector<TPoint2D>& out, TPoint2D a, TPoint2D b) {
  const double l = std::hypot(b.x - a.x, b.y - a.y);
  const int n = std::max(1, static_cast<int>(l / 0.02));
  for (int i = 0; i <= n; ++i)
    out.push_back({a.x + (b.x - a.x) * i / n, a.y + (b.y - a.y) * i / n});
}

/** Moves the pose by (v, w) for dt (exact arc). */
TPose2D move(const TPose2D& p, const Twist& c, double dt) { return integrateArc(p, c.v, c.w, dt); }

TEST(Recovery, BacksOutOfADeadEndAlongTheWayItCame) {
  // A 0.6 m wide dead end: the robot drove in along y = 0 and faces its
  // end wall 8 cm ahead; turning sweeps its corners into the side walls.
  NavigationParams nav;
  const RobotParams r = fastRobot();
  RecoveryParams rp;
  Recovery rec(rp, r, nav);
  std::vector<TPoint2D> obs;
  segment(obs, {-3, 0.3}, {0.4, 0.3});
  segment(obs, {-3, -0.3}, {0.4, -0.3});
  segment(obs, {0.35, -0.3}, {0.35, 0.3});
  LocalCostmap map(nav, Footprint(r.footprint, nav.resolution));
  map.build({0, 0}, obs);
  for (double x = -2.0; x <= 0.0 + 1e-9; x += 0.02) rec.recordPose({x, 0, 0});
  PlannerInput in;
  in.map = &map;
  in.pose = {0, 0, 0};
  in.path = {{-2, 0}, {0, 0}, {0, 2}};  // the route goes where the wall is
  PlannerOutput blocked;
  blocked.mark(PlanStatus::NoAdmissible);
  double t = 0;
  // Not yet: blocked for less than stuck_time.
  EXPECT_FALSE(rec.step(t, in, blocked, true, 5.0));
  size_t reversing = 0;
  double min_x = 0;
  for (int k = 0; k < 100; ++k) {
    t += 0.1;
    const auto o = rec.step(t, in, blocked, true, 5.0);
    if (!o) continue;
    ASSERT_TRUE(o->ok) << o->note;
    if (o->cmd.v < 0) {
      ++reversing;
      // Never into an obstacle: the supervisor passes it unchanged.
      EXPECT_GE(brakingScale(map, in.pose, o->cmd, r, nav.sim_step, rp.backup_margin), 1.0);
      SafetyInput s;
      s.now = t;
      s.last_scan_time = s.last_odom_time = t;
      s.plan = *o;
      s.pose = in.pose;
      s.map = &map;
      EXPECT_EQ(SafetySupervisor(nav, r).apply(s).action, SafetyAction::Pass);
    }
    in.pose = move(in.pose, o->cmd, 0.1);
    EXPECT_FALSE(map.check(in.pose).collision) << "t " << t;
    min_x = std::min(min_x, in.pose.x);
    if (rec.takeReplanRequest()) break;
  }
  EXPECT_GT(reversing, 0u);
  EXPECT_LE(min_x, -rp.backup_distance + 0.05);  // backed out about backup_distance
  EXPECT_NEAR(in.pose.y, 0, 0.05);               // along the way it came
  EXPECT_EQ(rec.recoveries(), 1u);
}

TEST(Recovery, ForgetsTheRecordedPathAsTheOdometryErrorSinceGrows) {
  // The recorded path is known free in the odometry frame only while the
  // odometry's error since it was recorded is within backup_margin: a
  // robot that went round a wedge for a while retraced poses recorded long
  // before, and touched a post the real robot had never swept.
  NavigationParams nav;
  const RobotParams r = fastRobot();
  RecoveryParams rp;
  Recovery rec(rp, r, nav);
  for (double x = -2.0; x <= 1e-9; x += 0.02) rec.recordPose({x, 0, 0});
  // 0.02 m/m and 0.01 rad/m at the corner (0.335 m): 1.29 m of travel for 3 cm.
  ASSERT_FALSE(rec.path().empty());
  EXPECT_NEAR(rec.path().front().x, -1.29, 0.05);
  // Turning on the spot back and forth, 12 rad: 0.02 rad/rad at the corner.
  for (int k = 0; k < 20; ++k) rec.recordPose({0, 0, k % 2 ? 0.3 : -0.3});
  EXPECT_LE(rec.path().size(), 1u);
  // Without an error model the whole path_memory stays.
  rp.odom_error_d = rp.odom_error_w = rp.odom_error_wd = 0;
  Recovery exact(rp, r, nav);
  for (double x = -2.0; x <= 1e-9; x += 0.02) exact.recordPose({x, 0, 0});
  for (int k = 0; k < 20; ++k) exact.recordPose({0, 0, k % 2 ? 0.3 : -0.3});
  EXPECT_NEAR(exact.path().front().x, -2.0, 0.03);
}

TEST(Recovery, NeverReversesIntoAnObstacleOverRandomScenes) {
  // Random recorded paths and random posts, some behind the robot on its
  // way back: every back-out command passes the supervisor unchanged (it
  // brakes backup_margin before any seen obstacle) and a post on the way
  // back within the braking distance means no back-out at all.
  NavigationParams nav;
  const RobotParams r = fastRobot();
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(-1, 1);
  size_t offered = 0, refused = 0;
  for (int trial = 0; trial < 200; ++trial) {
    Recovery rec(RecoveryParams{}, r, nav);
    // a path curving in towards the origin, heading along it
    const double curv = 0.6 * U(rng);
    TPose2D p{0, 0, 0};
    std::vector<TPose2D> back;
    for (int i = 0; i < 100; ++i) {
      back.push_back(p);
      p = move(p, {-1, -curv}, 0.02);  // walk backwards from the end
    }
    for (auto it = back.rbegin(); it != back.rend(); ++it) rec.recordPose(*it);
    std::vector<TPoint2D> obs;
    const int n = static_cast<int>(rng() % 6);
    for (int k = 0; k < n; ++k) {
      // posts around, behind the robot half of the time
      const double a = (trial % 2 ? M_PI : 0) + U(rng) * M_PI / 2,
                   d = 0.28 + std::abs(U(rng)) * 0.3;
      obs.push_back({d * std::cos(a), d * std::sin(a)});
    }
    LocalCostmap map(nav, Footprint(r.footprint, nav.resolution));
    map.build({0, 0}, obs);
    if (map.check({0, 0, 0}).collision) continue;
    const auto c = rec.backOutCommand(map, {0, 0, 0});
    if (!c) {
      ++refused;
      continue;
    }
    ++offered;
    EXPECT_LT(c->v, 0);
    EXPECT_GE(c->v, r.v_min - 1e-12);
    const SafetySupervisor sup(nav, r);
    const double ttc = sup.timeToCollision(map, {0, 0, 0}, *c, 30);
    EXPECT_TRUE(canBrake(*c, ttc, r, RecoveryParams{}.backup_margin * 0.999))
        << "trial " << trial << ": (" << c->v << ", " << c->w << ") ttc " << ttc;
  }
  EXPECT_GT(offered, 50u);
  (void)refused;  // refusals are checked below, with a post right behind
  // A post right behind, on the way back: no back-out.
  Recovery rec(RecoveryParams{}, r, nav);
  for (double x = -2.0; x <= 1e-9; x += 0.02) rec.recordPose({x, 0, 0});
  LocalCostmap map(nav, Footprint(r.footprint, nav.resolution));
  map.build({0, 0}, {{-0.30, 0.0}});  // 4.5 cm behind the rear: less than braking + the margin
  EXPECT_FALSE(rec.backOutCommand(map, {0, 0, 0}));
  // ... nor for a robot that cannot reverse.
  RobotParams fwd = r;
  fwd.v_min = 0;
  Recovery rec2(RecoveryParams{}, fwd, nav);
  for (double x = -2.0; x <= 1e-9; x += 0.02) rec2.recordPose({x, 0, 0});
  LocalCostmap empty(nav, Footprint(r.footprint, nav.resolution));
  empty.build({0, 0}, {});
  EXPECT_FALSE(rec2.backOutCommand(empty, {0, 0, 0}));
}

TEST(Recovery, GivesUpWithAReasonAfterMaxAttempts) {
  NavigationParams nav;
  const RobotParams r = fastRobot();
  RecoveryParams rp;
  rp.max_attempts = 2;
  rp.wait_time = 0.5;
  Recovery rec(rp, r, nav);
  // Boxed in all round: no back-out (no path), no turn: it waits, then gives up.
  std::vector<TPoint2D> obs;
  segment(obs, {-0.3, 0.25}, {0.3, 0.25});
  segment(obs, {-0.3, -0.25}, {0.3, -0.25});
  segment(obs, {0.3, -0.25}, {0.3, 0.25});
  segment(obs, {-0.3, -0.25}, {-0.3, 0.25});
  LocalCostmap map(nav, Footprint(r.footprint, nav.resolution));
  map.build({0, 0}, obs);
  PlannerInput in;
  in.map = &map;
  in.pose = {0, 0, 0};
  in.path = {{0, 0}, {3, 0}};
  PlannerOutput blocked;
  std::optional<PlannerOutput> o;
  for (double t = 0; t < 20 && !rec.gaveUp(); t += 0.1) {
    o = rec.step(t, in, blocked, true, 3.0);
    if (o && o->ok) EXPECT_EQ(o->cmd.v, 0);
  }
  ASSERT_TRUE(rec.gaveUp());
  ASSERT_TRUE(o);
  EXPECT_FALSE(o->ok);
  EXPECT_NE(o->note.find("gave up: boxed in after 2 recoveries"), std::string::npos) << o->note;
}

TEST(Recovery, NoProgressIsSeenThroughARouteReplannedEvery2Seconds) {
  // The robot turns this way and that (the planner always has a command:
  // never blocked) and goes nowhere, while its route is replanned every
  // 2 s, a little longer or shorter each time. The time since the last
  // progress keeps running across the replans: a no-progress recovery
  // starts after progress_time. Real progress on a new route still counts.
  NavigationParams nav;
  const RobotParams r = fastRobot();
  RecoveryParams rp;
  rp.still_time = 0;  // the pose below never changes: standing still is tested on its own
  Recovery rec(rp, r, nav);
  LocalCostmap map(nav, Footprint(r.footprint, nav.resolution));
  map.build({0, 0}, {});
  PlannerInput in;
  in.map = &map;
  in.pose = {0, 0, 0};
  in.path = {{0, 0}, {5, 0}};
  PlannerOutput turning;
  turning.ok = true;
  turning.cmd = {0, 0.5};
  rec.newGoal(0);
  std::optional<double> started;
  for (double t = 0; t < 30 && !started; t += 0.1) {
    const int k = static_cast<int>(std::lround(t * 10));
    if (k > 0 && k % 20 == 0) rec.routeChanged(t);
    const double left = 5.0 + ((k / 20) % 2 ? 0.2 : -0.2);  // each new route a little different
    if (rec.step(t, in, turning, false, left)) started = t;
  }
  ASSERT_TRUE(started) << "no recovery in 30 s";
  EXPECT_NEAR(*started, rp.progress_time, 0.3);
  // A robot that gains 0.1 m/s along each new route is making progress.
  Recovery moving(rp, r, nav);
  moving.newGoal(0);
  for (double t = 0; t < 30; t += 0.1) {
    const int k = static_cast<int>(std::lround(t * 10));
    if (k > 0 && k % 20 == 0) moving.routeChanged(t);
    const double left = 5.0 - 0.1 * t + ((k / 20) % 2 ? 0.2 : -0.2);
    EXPECT_FALSE(moving.step(t, in, turning, false, left)) << "t " << t;
  }
}

TEST(Recovery, AStandStillTurningLeftAndRightStartsARecoveryAfterStillTime) {
  // goal-dwa at a post turned left and right on the spot for 10 s (never
  // blocked: it always had a command) before a no-progress recovery began.
  // A robot that neither moves still_distance nor turns still_deg for
  // still_time recovers then; one that turns on towards its route, or
  // creeps along it, or stands at its goal, does not.
  NavigationParams nav;
  const RobotParams r = fastRobot();
  RecoveryParams rp;
  LocalCostmap map(nav, Footprint(r.footprint, nav.resolution));
  map.build({0, 0}, {});
  PlannerOutput plan;
  plan.ok = true;
  plan.cmd = {0, 0.3};
  struct Case {
    const char* what;
    double w, v, left;  // rad/s turned (sign flips every 0.5 s when dithering), m/s driven
    bool dither, recovers;
  };
  for (const Case& c :
       {Case{"dithering", 0.3, 0, 5, true, true}, Case{"turning on", 0.3, 0, 5, false, false},
        Case{"creeping", 0, 0.03, 5, false, false},
        Case{"at the goal", 0.3, 0, 0.1, true, false}}) {
    SCOPED_TRACE(c.what);
    Recovery rec(rp, r, nav);
    rec.newGoal(0);
    PlannerInput in;
    in.map = &map;
    in.pose = {0, 0, 0};
    in.path = {{0, 0}, {5, 0}};
    std::optional<double> started;
    for (double t = 0; t < 8 && !started; t += 0.1) {
      const int k = static_cast<int>(std::lround(t * 10));
      const double w = c.dither && (k / 5) % 2 ? -c.w : c.w;
      in.pose = move(in.pose, {c.v, w}, 0.1);
      // the route left shrinks only by what was driven (never by 0.3 m here)
      if (rec.step(t, in, plan, false, c.left - in.pose.x)) started = t;
    }
    EXPECT_EQ(started.has_value(), c.recovers);
    if (started) EXPECT_NEAR(*started, rp.still_time, 0.25);
    if (started) EXPECT_NE(rec.phase(), Recovery::Phase::Idle);
  }
}

TEST(PlannerSupervisor, GoalDwaNeverProposesWhatTheSupervisorWouldStopOverRandomScenes) {
  // One notion of admissible: whatever goal-dwa proposes, the supervisor
  // passes unchanged (same footprint, braking model and safe distance).
  for (const double vmax : {0.5, 2.0}) {
    NavigationParams nav;
    const RobotParams r = fastRobotAt(vmax);
    auto planner = makeGoalDwa(nav, r);
    const SafetySupervisor sup(nav, r);
    std::mt19937 rng(17);
    std::uniform_real_distribution<double> U(-1, 1);
    size_t proposals = 0;
    for (int trial = 0; trial < 150; ++trial) {
      std::vector<TPoint2D> obs;
      const int n = 3 + static_cast<int>(rng() % 10);
      for (int k = 0; k < n; ++k) {
        const double x = 0.4 + std::abs(U(rng)) * 2.5, y = 1.5 * U(rng);
        for (double dx = -0.075; dx <= 0.075; dx += 0.05)
          for (double dy = -0.075; dy <= 0.075; dy += 0.05) obs.push_back({x + dx, y + dy});
      }
      LocalCostmap map(nav, Footprint(r.footprint, nav.resolution));
      map.build({0, 0}, obs);
      if (map.check({0, 0, 0}).collision) continue;
      PlannerInput in;
      in.map = &map;
      in.pose = {0, 0, 0.3 * U(rng)};
      in.current = {vmax * std::abs(U(rng)), 0.5 * r.w_max * U(rng)};
      in.path = {{0, 0}, {4, 0}};
      in.goal = TPose2D{4, 0, 0};
      const PlannerOutput plan = planner->plan(in);
      if (!plan.ok) continue;
      ++proposals;
      SafetyInput s;
      s.now = 10;
      s.last_scan_time = 9.95;
      s.last_odom_time = 9.99;
      s.plan = plan;
      s.pose = in.pose;
      s.map = &map;
      const SafetyDecision d = sup.apply(s);
      EXPECT_EQ(d.action, SafetyAction::Pass)
          << "v_max " << vmax << " trial " << trial << ": (" << plan.cmd.v << ", " << plan.cmd.w
          << ") " << d.reason;
    }
    EXPECT_GT(proposals, 100u);
  }
}

TEST(GoalDwa, TurnsToTheRouteAt4RadPerSecondWithoutSpinningPast) {
  // The route turns 90 deg right; the robot (4 rad/s) already spins left at
  // full rate. Heading errors taken after score_time must not wrap: the
  // robot settles on the route's heading instead of spinning for ever.
  NavigationParams nav;
  const RobotParams r = fastRobot();
  auto planner = makeGoalDwa(nav, r);
  LocalCostmap map(nav, Footprint(r.footprint, nav.resolution));
  map.build({0, 0}, {});
  TPose2D pose{0, 0, 0};
  Twist cur{0, 4.0};
  double turned = 0;
  for (int k = 0; k < 60; ++k) {
    PlannerInput in;
    in.map = &map;
    in.pose = pose;
    in.current = cur;
    in.path = {{0, 0}, {0, -3}};
    in.goal = TPose2D{0, -3, -M_PI / 2};
    const PlannerOutput o = planner->plan(in);
    ASSERT_TRUE(o.ok) << o.note;
    // the robot reaches the command within its accelerations in 0.1 s
    auto toward = [](double c, double t, double a) { return c + std::clamp(t - c, -a, a); };
    cur = {toward(cur.v, o.cmd.v, r.acc_v * 0.1), toward(cur.w, o.cmd.w, r.acc_w * 0.1)};
    const TPose2D next = move(pose, cur, 0.1);
    turned += std::abs(cur.w) * 0.1;
    pose = next;
  }
  // heading on the route (down) within 20 deg and moving along it
  EXPECT_LT(std::abs(std::remainder(pose.phi + M_PI / 2, 2 * M_PI)), mrpt::DEG2RAD(20.0));
  EXPECT_LT(pose.y, -0.5);
  EXPECT_LT(turned, 2 * M_PI);  // no full turn: it did not spin past
}

/** The simulator's dynamics (modules/sim): a command takes effect after
 *  `latency`, then v and w move towards it at the robot's accelerations;
 *  integrated every 10 ms. */
struct Base {
  RobotParams r;
  double latency = 0.05;
  TPose2D pose;
  Twist vel, cmd;
  std::vector<std::pair<double, Twist>> pending;  // (time it takes effect, command)
  double t = 0;
  void send(const Twist& c) { pending.push_back({t + latency, c}); }
  /** Advances `dur` s; false as soon as the footprint touches `map`'s obstacles. */
  bool run(const LocalCostmap& map, double dur) {
    const double dt = 0.01;
    for (double e = 0; e < dur - 1e-9; e += dt) {
      while (!pending.empty() && pending.front().first <= t + 1e-9) {
        cmd = pending.front().second;
        pending.erase(pending.begin());
      }
      vel.v += std::clamp(cmd.v - vel.v, -r.acc_v * dt, r.acc_v * dt);
      vel.w += std::clamp(cmd.w - vel.w, -r.acc_w * dt, r.acc_w * dt);
      pose = integrateArc(pose, vel.v, vel.w, dt);
      t += dt;
      if (map.check(pose).collision) return false;
    }
    return true;
  }
};

TEST(Safety, ATurnAt4RadPerSecondIsJudgedFromTheVelocityTheRobotStillHas) {
  // The robot spins left at 4 rad/s (its limit, acc_w 4 rad/s^2: 2 rad to
  // stop); a post stands 0.6 rad of turn ahead of its front-left corner,
  // clear of a straight drive. Taken at once, (0.3, 0) drives straight past
  // the post; the robot still turns for the latency and while it
  // decelerates, and its corner hits the post. From the measured velocity
  // the supervisor stops it (it cannot avoid the contact any more: the
  // planner must not get there, next test).
  NavigationParams nav;
  const RobotParams r = fastRobot();
  std::vector<TPoint2D> post;
  for (double a = 0; a < 2 * M_PI; a += 0.3)
    post.push_back({0.08 + 0.04 * std::cos(a), 0.30 + 0.04 * std::sin(a)});
  LocalCostmap map(nav, Footprint(r.footprint, nav.resolution));
  map.build({0, 0}, post);
  ASSERT_FALSE(map.check({0, 0, 0}).collision);
  const Twist straight{0.3, 0};
  // Taken at once: the supervisor's old rule passes it.
  EXPECT_DOUBLE_EQ(brakingScale(map, {0, 0, 0}, straight, r, nav.sim_step), 1.0);
  // The robot as the simulator moves it: the corner hits the post.
  Base base{r};
  base.vel = base.cmd = {0, 4.0};
  base.send(straight);
  EXPECT_FALSE(base.run(map, 2.0));
  // From the measured velocity (and the last command, 4 rad/s) it cannot.
  MotionState m;
  m.current = m.commanded = {0, 4.0};
  m.latency = 0.05;
  m.period = 0.1;
  EXPECT_FALSE(canStopFrom(map, {0, 0, 0}, m, straight, r, r.safe_distance));
  SafetySupervisor sup(nav, r);
  SafetyInput s;
  s.now = 10;
  s.last_scan_time = 9.95;
  s.last_odom_time = 9.99;
  s.plan.ok = true;
  s.plan.cmd = straight;
  s.pose = {0, 0, 0};
  s.map = &map;
  EXPECT_EQ(sup.apply(s).action, SafetyAction::Pass);  // the command at once
  s.motion = m;
  EXPECT_EQ(sup.apply(s).action, SafetyAction::Stop);
}

/** A random field of 15 cm posts ahead of the robot. */
std::vector<TPoint2D> randomPosts(std::mt19937& rng, int n, double x0, double x1, double y) {
  std::uniform_real_distribution<double> X(x0, x1), Y(-y, y);
  std::vector<TPoint2D> obs;
  for (int k = 0; k < n; ++k) {
    const double x = X(rng), yy = Y(rng);
    for (double dx = -0.075; dx <= 0.075; dx += 0.025)
      for (double dy = -0.075; dy <= 0.075; dy += 0.025) obs.push_back({x + dx, yy + dy});
  }
  return obs;
}

TEST(PlannerSupervisor, FromTheMeasuredVelocityGoalDwaAndTheSupervisorNeverDisagree) {
  // Random cluttered scenes, a robot moving and turning at random (within
  // its limits) with a random last command: goal-dwa rolls its candidates
  // out from that state and the supervisor judges the same motion, so it
  // passes every proposal unchanged. The same proposals judged as if taken
  // at once are no guide: the supervisor from the measured velocity stops
  // or slows some of what an instant-velocity goal-dwa proposes.
  for (const double vmax : {0.5, 2.0}) {
    NavigationParams nav;
    const RobotParams r = fastRobotAt(vmax);
    auto planner = makeGoalDwa(nav, r);
    const SafetySupervisor sup(nav, r);
    std::mt19937 rng(23);
    std::uniform_real_distribution<double> U(-1, 1);
    size_t proposals = 0, instant_disagree = 0;
    for (int trial = 0; trial < 120; ++trial) {
      LocalCostmap map(nav, Footprint(r.footprint, nav.resolution));
      map.build({0, 0}, randomPosts(rng, 3 + static_cast<int>(rng() % 10), 0.3, 2.5, 1.5));
      if (map.check({0, 0, 0}).collision) continue;
      PlannerInput in;
      in.map = &map;
      in.pose = {0, 0, 0.3 * U(rng)};
      in.current = {vmax * std::abs(U(rng)), r.w_max * U(rng)};
      MotionState m;
      m.current = in.current;
      m.commanded = {vmax * std::abs(U(rng)), r.w_max * U(rng)};
      m.latency = 0.05;
      m.period = 0.1;
      in.path = {{0, 0}, {4, 0}};
      in.goal = TPose2D{4, 0, 0};
      SafetyInput s;
      s.now = 10;
      s.last_scan_time = 9.95;
      s.last_odom_time = 9.99;
      s.pose = in.pose;
      s.map = &map;
      s.motion = m;
      // instant-velocity rollouts (no motion in the planner's input)
      s.plan = planner->plan(in);
      if (s.plan.ok && sup.apply(s).action != SafetyAction::Pass) ++instant_disagree;
      in.motion = m;
      s.plan = planner->plan(in);
      if (!s.plan.ok) continue;
      ++proposals;
      const SafetyDecision d = sup.apply(s);
      EXPECT_EQ(d.action, SafetyAction::Pass)
          << "v_max " << vmax << " trial " << trial << ": (" << s.plan.cmd.v << ", " << s.plan.cmd.w
          << ") " << d.reason;
    }
    EXPECT_GT(proposals, 60u) << "v_max " << vmax;
    EXPECT_GT(instant_disagree, 0u) << "v_max " << vmax;
  }
}

/** One closed-loop cycle of 0.1 s: goal-dwa plans from `base`'s state
 *  towards `goal` on the straight route from `start`, the supervisor judges
 *  the plan and `base` moves as the simulator does (latency, accelerations).
 *  The plan's status; `contact` when the footprint touched an obstacle. */
PlanStatus closedLoopCycle(LocalPlanner& planner, const SafetySupervisor& sup,
                           const LocalCostmap& map, Base& base, const TPoint2D& start,
                           const TPoint2D& goal, bool& contact) {
  PlannerInput in;
  in.map = &map;
  in.pose = base.pose;
  in.current = base.vel;
  MotionState m{base.vel, base.cmd, base.latency, 0.1};
  if (!base.pending.empty()) m.commanded = base.pending.back().second;
  in.motion = m;
  in.path = {start, goal};
  in.goal = TPose2D{goal.x, goal.y, 0};
  SafetyInput s;
  s.now = 10;
  s.last_scan_time = 9.95;
  s.last_odom_time = 9.99;
  s.plan = planner.plan(in);
  s.pose = base.pose;
  s.map = &map;
  s.motion = m;
  base.send(sup.apply(s).cmd);
  contact = !base.run(map, 0.1);
  return s.plan.status;
}

/** Closed loop (closedLoopCycle) from where `base` stands to `goal`, at
 *  most `cycles`: the status of the plan that ended it (GoalReached; the
 *  robot stops there) or of the last one (NoAdmissible on a contact). */
PlanStatus driveToGoal(LocalPlanner& planner, const SafetySupervisor& sup, const LocalCostmap& map,
                       Base& base, const TPoint2D& goal, int cycles) {
  const TPoint2D start{base.pose.x, base.pose.y};
  PlanStatus status = PlanStatus::NoAdmissible;
  for (int k = 0; k < cycles; ++k) {
    bool contact = false;
    status = closedLoopCycle(planner, sup, map, base, start, goal, contact);
    if (contact) return PlanStatus::NoAdmissible;
    if (status == PlanStatus::GoalReached) return status;
  }
  return status;
}

TEST(GoalDwa, FromTheMeasuredVelocityNeverTouchesAPostAt2MetresPerSecond) {
  // Closed loop at 2 m/s and 4 rad/s through random post fields: goal-dwa
  // and the supervisor from the robot's state, the robot moved as the
  // simulator does (latency, accelerations). No contact, ever.
  NavigationParams nav;
  const RobotParams r = fastRobot();
  auto planner = makeGoalDwa(nav, r);
  const SafetySupervisor sup(nav, r);
  std::mt19937 rng(5);
  int runs = 0;
  for (int trial = 0; trial < 12; ++trial) {
    LocalCostmap map(nav, Footprint(r.footprint, nav.resolution));
    map.build({0, 0}, randomPosts(rng, 10, 1.0, 3.5, 1.2));
    if (map.check({0, 0, 0}).collision) continue;
    ++runs;
    Base base{r};
    for (int k = 0; k < 40; ++k) {
      bool contact = false;
      closedLoopCycle(*planner, sup, map, base, {0, 0}, {3.8, 0}, contact);
      ASSERT_FALSE(contact) << "trial " << trial << " cycle " << k;
    }
  }
  EXPECT_GT(runs, 8);
}

TEST(GoalDwa, SaysItArrivedOnlyWhenStoppedWellInsideTheTolerance) {
  // A goal 3 m ahead whose heading does not matter. The robot reported it
  // reached as soon as its estimate entered the 0.3 m tolerance, still at
  // full speed: a run judged by where the robot truly is ended 0.30-0.33 m
  // from the goal (localisation error). It aims at half the tolerance and
  // says so once it has (all but) stopped, at the walker's limits and
  // at 2 m/s.
  for (const double vmax : {0.5, 2.0}) {
    NavigationParams nav;
    nav.goal_tolerance = 0.3;
    nav.goal_tolerance_deg = 180;
    const RobotParams r = fastRobotAt(vmax);
    auto planner = makeGoalDwa(nav, r);
    const SafetySupervisor sup(nav, r);
    LocalCostmap map(nav, Footprint(r.footprint, nav.resolution));
    map.build({0, 0}, {});
    const TPoint2D goal{3.0, 0.2};
    Base base{r};
    ASSERT_EQ(driveToGoal(*planner, sup, map, base, goal, 150), PlanStatus::GoalReached)
        << "v_max " << vmax << " at x = " << base.pose.x;
    EXPECT_LT(std::hypot(base.pose.x - goal.x, base.pose.y - goal.y), nav.goal_tolerance / 2)
        << "v_max " << vmax;
    EXPECT_LE(base.vel.v * base.vel.v / (2 * r.acc_v), 0.01 + 1e-9) << "v_max " << vmax;  // stopped
  }
}

TEST(GoalDwa, AGoalItCannotComeCloserToIsReachedWithinTheTolerance) {
  // A wall 0.1 m beyond the goal: the front of the robot and its safe
  // distance keep its centre about 0.25 m short of the goal. Within the
  // tolerance, where nothing goes on towards the goal, it has arrived
  // (aiming at half the tolerance must not make it blocked there).
  NavigationParams nav;
  nav.goal_tolerance = 0.3;
  nav.goal_tolerance_deg = 180;
  const RobotParams r = fastRobotAt(0.5);
  auto planner = makeGoalDwa(nav, r);
  const SafetySupervisor sup(nav, r);
  const TPoint2D goal{2.0, 0};
  std::vector<TPoint2D> wall;
  segment(wall, {goal.x + 0.1, -1}, {goal.x + 0.1, 1});
  LocalCostmap map(nav, Footprint(r.footprint, nav.resolution));
  map.build({0, 0}, wall);
  Base base{r};
  ASSERT_EQ(driveToGoal(*planner, sup, map, base, goal, 150), PlanStatus::GoalReached)
      << "at x = " << base.pose.x;
  const double d = std::hypot(base.pose.x - goal.x, base.pose.y - goal.y);
  EXPECT_LT(d, nav.goal_tolerance);
  EXPECT_GT(d, nav.goal_tolerance / 2);  // else the wall did not hold it back
}

TEST(GoalDwa, ArrivesAtTheGoalAt2MetresPerSecondAndStopsWithinTheTolerance) {
  // The goal 0.65 m away, 6 deg off the heading, a robot at rest that can
  // drive at 2 m/s (2 m/s^2: 1 m to stop). Critics taken 1.5 s ahead put
  // every candidate faster than a crawl beyond the goal, facing back at it:
  // the robot crept and dithered short of it. It arrives no faster than it
  // can stop, and ends within the goal tolerance.
  NavigationParams nav;
  nav.goal_tolerance = 0.3;
  nav.goal_tolerance_deg = 180;
  const RobotParams r = fastRobot();
  auto planner = makeGoalDwa(nav, r);
  const SafetySupervisor sup(nav, r);
  LocalCostmap map(nav, Footprint(r.footprint, nav.resolution));
  map.build({0, 0}, {});
  const TPoint2D goal{0.65 * std::cos(0.1), 0.65 * std::sin(0.1)};
  Base base{r};
  ASSERT_EQ(driveToGoal(*planner, sup, map, base, goal, 100), PlanStatus::GoalReached)
      << "at x = " << base.pose.x;
  base.send({0, 0});
  base.run(map, 2.0);  // braking to a stop
  EXPECT_LT(std::hypot(base.pose.x - goal.x, base.pose.y - goal.y), nav.goal_tolerance);
}

}  // namespace
}  // namespace carenav::navigation

namespace carenav::navigation {
namespace {

/** A 0.15 m post whose centre lies at (x, y) in the frame of `robot`. */
void postAhead(std::vector<TPoint2D>& out, const TPose2D& robot, double x, double y) {
  const double c = std::cos(robot.phi), s = std::sin(robot.phi);
  for (double u = -0.075; u <= 0.075 + 1e-9; u += 0.02)
    for (double v = -0.075; v <= 0.075 + 1e-9; v += 0.02)
      out.push_back({robot.x + c * (x + u) - s * (y + v), robot.y + s * (x + u) + c * (y + v)});
}

/** The wedge at a gap's mouth (the clutter benchmark's timeouts): the robot
 *  came in 40 deg skewed to a route going east, a post 3 cm before the left
 *  half of its front. Forward touches the post; turning right to the route
 *  swings the front into it. */
struct Wedge {
  NavigationParams nav;
  RobotParams r = fastRobotAt(0.5);
  TPose2D pose{0, 0, 0.7};
  std::vector<TPoint2D> obs;
  std::vector<TPoint2D> route{{-1.5, 0}, {0, 0}, {3, 0}};
  Wedge() { postAhead(obs, pose, 0.255 + 0.03 + 0.075, 0.1); }
};

TEST(GoalDwa, SaysItIsWedgedWhenItCanNeitherGoOnNorTurnToTheRoute) {
  Wedge w;
  LocalCostmap map(w.nav, Footprint(w.r.footprint, w.nav.resolution));
  map.build({0, 0}, w.obs);
  PlannerInput in;
  in.map = &map;
  in.pose = w.pose;
  in.path = w.route;
  in.goal = TPose2D{3, 0, 0};
  const PlannerOutput o = makeGoalDwa(w.nav, w.r)->plan(in);
  EXPECT_TRUE(o.wedged) << o.note;
  EXPECT_FALSE(o.ok && std::abs(o.cmd.v) > 1e-6) << "moved " << o.cmd.v;
  // Without the post it turns to the route: not wedged.
  LocalCostmap open(w.nav, Footprint(w.r.footprint, w.nav.resolution));
  open.build({0, 0}, {{-3, 3}});
  in.map = &open;
  EXPECT_FALSE(makeGoalDwa(w.nav, w.r)->plan(in).wedged);
  // Nor when it faces the route (it can go on).
  in.map = &map;
  in.pose = {-0.6, 0, 0};
  EXPECT_FALSE(makeGoalDwa(w.nav, w.r)->plan(in).wedged);
}

TEST(Recovery, BacksOutOfAWedgeUntilItCanTurnAndFacesTheRouteBeforeReplanning) {
  // The robot came up skewed along y = x * tan(0.7) and is wedged (Wedge):
  // backing out by backup_distance and handing back to the planner sent it
  // straight back into the mouth skewed, over and over. It backs out to
  // where its footprint can turn and turns to face the route first (the
  // fallback when no footprint maneuver is found: maneuvers off here).
  Wedge w;
  RecoveryParams rp;
  ManeuverParams no_maneuver;
  no_maneuver.enabled = false;
  Recovery rec(rp, w.r, w.nav, no_maneuver);
  LocalCostmap map(w.nav, Footprint(w.r.footprint, w.nav.resolution));
  map.build({0, 0}, w.obs);
  for (double d = -1.5; d <= 1e-9; d += 0.02)
    rec.recordPose({d * std::cos(0.7), d * std::sin(0.7), 0.7});
  PlannerInput in;
  in.map = &map;
  in.pose = w.pose;
  in.path = w.route;
  PlannerOutput wedged;
  wedged.ok = true;
  wedged.cmd = {0, 0.3};
  wedged.wedged = true;
  double t = 0;
  size_t reversing = 0;
  bool replanned = false;
  for (int k = 0; k < 200 && !replanned; ++k, t += 0.1) {
    const auto o = rec.step(t, in, wedged, true, 5.0);
    if (!o) continue;
    ASSERT_TRUE(o->ok) << o->note;
    reversing += o->cmd.v < 0;
    EXPECT_GE(brakingScale(map, in.pose, o->cmd, w.r, w.nav.sim_step, rp.backup_margin), 1.0);
    in.pose = move(in.pose, o->cmd, 0.1);
    ASSERT_FALSE(map.check(in.pose).collision) << "t " << t;
    replanned = rec.takeReplanRequest();
  }
  ASSERT_TRUE(replanned);
  EXPECT_GT(reversing, 0u);
  // It faces the route (its look-ahead point, 1 m on) within 15 deg.
  const TPoint2D ahead = lookaheadPoint(w.route, in.pose.x, in.pose.y, w.nav.lookahead);
  const double off =
      std::remainder(std::atan2(ahead.y - in.pose.y, ahead.x - in.pose.x) - in.pose.phi, 2 * M_PI);
  EXPECT_LE(std::abs(off), 15.0 * M_PI / 180 + 0.02) << "heading " << in.pose.phi;
  EXPECT_EQ(rec.recoveries(), 1u);
  // The retraced part of the recorded path is cut: it ends where the robot is.
  ASSERT_FALSE(rec.path().empty());
  EXPECT_LT(std::hypot(rec.path().back().x - in.pose.x, rec.path().back().y - in.pose.y), 0.1);
}

/** Drives the recovery of a robot held at `start` (0.1 s cycles, every
 *  command driven by a robot that turns `turn_gain` times what it is told:
 *  slip, a slow controller) until it asks for a replan; every command
 *  passes the supervisor's rule and nothing is touched. Returns the end
 *  pose and whether a maneuver step was among the commands. */
/** A 270 deg lidar 0.12 m ahead of the robot's centre at `p`: 541 rays of
 *  4 m at most, each ending at the first obstacle point it passes within
 *  2 cm of. */
WorldScan lidarScan(const TPose2D& p, const std::vector<TPoint2D>& obs) {
  WorldScan w;
  w.origin = {p.x + 0.12 * std::cos(p.phi), p.y + 0.12 * std::sin(p.phi)};
  for (int k = 0; k <= 540; ++k) {
    const double a = p.phi + (k - 270) * M_PI / 360, c = std::cos(a), s = std::sin(a);
    double len = 4.0;
    for (const auto& o : obs) {
      const double along = (o.x - w.origin.x) * c + (o.y - w.origin.y) * s;
      const double across = -(o.x - w.origin.x) * s + (o.y - w.origin.y) * c;
      if (along > 0 && std::abs(across) < 0.02) len = std::min(len, along);
    }
    w.ends.push_back({w.origin.x + len * c, w.origin.y + len * s});
    w.hit.push_back(len < 4.0 ? 1 : 0);
  }
  return w;
}

std::pair<TPose2D, bool> recoverFrom(Recovery& rec, const LocalCostmap& map, const TPose2D& start,
                                     const std::vector<TPoint2D>& route, const RobotParams& r,
                                     const NavigationParams& nav, double margin,
                                     double turn_gain = 1.0,
                                     const std::vector<TPoint2D>* lidar_sees = nullptr) {
  PlannerInput in;
  in.map = &map;
  in.pose = start;
  in.path = route;
  PlannerOutput wedged;
  wedged.ok = true;
  wedged.wedged = true;
  bool maneuvered = false;
  double t = 0;
  for (int k = 0; k < 600; ++k, t += 0.1) {
    const auto o = rec.step(t, in, wedged, true, 5.0);
    if (rec.takeReplanRequest()) break;
    if (!o) continue;
    EXPECT_TRUE(o->ok) << o->note;
    maneuvered |= o->note.find("maneuver") != std::string::npos;
    EXPECT_GE(brakingScale(map, in.pose, o->cmd, r, nav.sim_step, margin), 1.0) << o->note;
    in.pose = move(in.pose, {o->cmd.v, o->cmd.w * turn_gain}, 0.1);
    EXPECT_FALSE(map.check(in.pose).collision) << "t " << t << " " << o->note;
    rec.recordPose(in.pose);
    if (lidar_sees) rec.addSeen(lidarScan(in.pose, *lidar_sees), t);
  }
  return {in.pose, maneuvered};
}

/** The poses of a robot driven up to the gap's mouth along a line skewed by
 *  `skew`, until its front is within 6 cm of a post; the last one is where
 *  it stands. */
std::vector<TPose2D> driveIntoTheMouth(const LocalCostmap& map, const test::GapScene& g,
                                       double skew) {
  const double y0 = skew > 0 ? -0.1 : 0.1;
  std::vector<TPose2D> came;
  TPose2D p{g.gx - 0.9 * std::cos(skew), y0 - 0.9 * std::sin(skew), skew};
  while (map.check(p, 0.1).clearance >= 0.06 && !map.check(p, 0.1).collision) {
    came.push_back(p);
    p = integrateArc(p, 0.005, 0, 1.0);
  }
  came.push_back(p);
  return came;
}

TEST(Recovery, ManeuversThroughTheGapMouthItIsWedgedInWhereBackingOutStaysBefore) {
  // Skewed at a 0.55 m gap's mouth (the robot is 0.43 m wide), its front
  // 3-6 cm from a post: a footprint maneuver (a step back, turns, and on
  // through) ends on the route beyond the gap, facing its way. Backing out
  // along the way it came leaves it before the gap (the planner's turn).
  const NavigationParams nav;
  const RobotParams r = fastRobotAt(0.5);
  const test::GapScene g(0.55);
  LocalCostmap map(nav, Footprint(r.footprint, nav.resolution));
  map.build({0, 0}, g.obs);
  const std::vector<TPoint2D> route{{-1.5, 0}, {0, 0}, {3, 0}};
  for (const double skew : {0.5, -0.6, 0.8}) {
    std::vector<TPose2D> came = driveIntoTheMouth(map, g, skew);
    const TPose2D p = came.back();
    came.pop_back();
    ASSERT_FALSE(map.check(p).collision) << skew;
    RecoveryParams rp;
    for (const bool maneuvers : {true, false}) {
      ManeuverParams mp;
      mp.enabled = maneuvers;
      Recovery rec(rp, r, nav, mp);
      for (const auto& q : came) rec.recordPose(q);
      const auto [end, maneuvered] = recoverFrom(rec, map, p, route, r, nav, rp.backup_margin);
      EXPECT_EQ(maneuvered, maneuvers) << skew;
      if (maneuvers) {
        EXPECT_GT(end.x, g.gx + 0.3) << "skew " << skew;
        EXPECT_LT(std::abs(end.y), mp.goal_radius + 0.1) << "skew " << skew;
        EXPECT_LT(std::abs(std::remainder(end.phi, 2 * M_PI)), mrpt::DEG2RAD(mp.goal_deg + 10));
      } else {
        EXPECT_LT(end.x, g.gx) << "skew " << skew;
      }
    }
  }
}

TEST(Recovery, AManeuverReversesOverSpaceALidarSawFreeNotOverSpaceNeverSeen) {
  // A wall 8 cm ahead of the robot's front: it can neither go on nor turn
  // on the spot (its front corners sweep into the wall), and the route goes
  // back behind it. It did not drive here along that way (its recorded
  // path is where it stands), so the recorded path allows no reversing; a
  // 270 deg lidar never sees behind the robot, but a scan from a pose it
  // had earlier saw that space free. With the sighting fresh, a maneuver
  // reverses over it and turns to the route; with none, or one older than
  // seen_keep, or with seen_keep 0, nothing reverses.
  const NavigationParams nav;
  const RobotParams r = fastRobotAt(0.5);
  std::vector<TPoint2D> obs;
  segment(obs, {0.335, -1.5}, {0.335, 1.5});
  LocalCostmap map(nav, Footprint(r.footprint, nav.resolution));
  map.build({0, 0}, obs);
  const TPose2D start{0, 0, 0};
  ASSERT_FALSE(map.check(start).collision);
  const std::vector<TPoint2D> route{{0, 0}, {-3, 0}};
  // A scan from (-0.5, -1.2): rays 3 m long all round, the wall's stop at it.
  WorldScan scan;
  scan.origin = {-0.5, -1.2};
  for (int k = 0; k < 720; ++k) {
    const double a = k * M_PI / 360, c = std::cos(a), s = std::sin(a);
    double len = 3.0;
    if (c > 1e-9) len = std::min(len, (0.335 - scan.origin.x) / c);
    scan.ends.push_back({scan.origin.x + len * c, scan.origin.y + len * s});
    scan.hit.push_back(len < 3.0 ? 1 : 0);
  }
  struct Case {
    const char* what;
    double keep, seen_at;
    bool scanned, reverses;
  };
  for (const Case& c :
       {Case{"seen 1 s ago", 30, -1, true, true}, Case{"never seen", 30, -1, false, false},
        Case{"seen 40 s ago", 30, -40, true, false}, Case{"seen_keep 0", 0, -1, true, false}}) {
    RecoveryParams rp;
    rp.seen_keep = c.keep;
    Recovery rec(rp, r, nav);
    rec.recordPose(start);
    if (c.scanned) rec.addSeen(scan, c.seen_at);
    const auto [end, maneuvered] = recoverFrom(rec, map, start, route, r, nav, rp.backup_margin);
    EXPECT_EQ(maneuvered, c.reverses) << c.what;
    if (c.reverses) {
      EXPECT_LT(end.x, -0.5) << c.what;
      EXPECT_GT(std::abs(std::remainder(end.phi, 2 * M_PI)), M_PI / 2) << c.what;
    } else {
      EXPECT_GT(end.x, -0.1) << c.what << ": reversed into space never seen";
    }
  }
}

TEST(Recovery, AManeuverDrivenByARobotThatTurnsTooFarOrTooLittleStillEndsOnItsWay) {
  // A maneuver's steps end at their planned poses (heading fed back), not
  // after their angle and length: a robot that turns half as much again, or 30 % less, than
  // told (slip, a slow controller) ended its steps more and more off
  // and the maneuver was planned again and again, or not finished.
  const NavigationParams nav;
  const RobotParams r = fastRobotAt(0.5);
  const test::GapScene g(0.55);
  LocalCostmap map(nav, Footprint(r.footprint, nav.resolution));
  map.build({0, 0}, g.obs);
  const std::vector<TPoint2D> route{{-1.5, 0}, {0, 0}, {3, 0}};
  std::vector<TPose2D> came = driveIntoTheMouth(map, g, 0.8);
  const TPose2D p = came.back();
  came.pop_back();
  for (const double gain : {0.7, 1.5}) {
    RecoveryParams rp;
    ManeuverParams mp;
    Recovery rec(rp, r, nav, mp);
    for (size_t i = 0; i < came.size(); ++i) {
      rec.recordPose(came[i]);
      if (i % 20 == 0) rec.addSeen(lidarScan(came[i], g.obs), 0);
    }
    const auto [end, maneuvered] =
        recoverFrom(rec, map, p, route, r, nav, rp.backup_margin, gain, &g.obs);
    EXPECT_TRUE(maneuvered) << gain;
    EXPECT_GT(end.x, g.gx + 0.3) << "turn gain " << gain;
    EXPECT_LT(std::abs(end.y), mp.goal_radius + 0.1) << "turn gain " << gain;
  }
}

}  // namespace
}  // namespace carenav::navigation
