#include <carenav/navigation/safety.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace carenav::navigation {

const char* safetyActionName(SafetyAction a) {
  switch (a) {
    case SafetyAction::Pass:
      return "pass";
    case SafetyAction::Slow:
      return "slow";
    case SafetyAction::Stop:
      return "stop";
  }
  return "?";
}

double SafetySupervisor::timeToCollision(const LocalCostmap& map, const TPose2D& pose,
                                         const Twist& cmd, double horizon) const {
  const Trajectory tr = rollout(map, pose, cmd, horizon, sim_step_ / 2, 0.0);
  if (tr.collides) return tr.time_to_collision;
  if (tr.leaves_map) return tr.time_to_collision;  // unknown beyond: treat as an obstacle
  return std::numeric_limits<double>::infinity();
}

namespace {

/** Already in contact (within footprint_padding) where the robot stands: a
 *  command that moves it away, its footprint's distance to the obstacles
 *  never shrinking along the sweep of `horizon` s, passes (1); anything
 *  else stops (0). The distances are from the outline to the sensed points
 *  themselves (LocalCostmap::outlineClearance): an obstacle inside the
 *  footprint, or a static map's or a moving obstacle's cell under its
 *  outline, cannot tell a move towards it from one away, so nothing passes then. */
double moveAwayScale(const LocalCostmap& map, const TPose2D& pose, const Twist& c, double horizon,
                     double step) {
  const double d0 = map.outlineClearance(pose);
  if (d0 <= 0) return 0.0;
  for (double t = step / 2; t <= horizon + 1e-9; t += step / 2)
    if (map.outlineClearance(integrateArc(pose, c.v, c.w, t)) < d0 - 1e-6) return 0.0;
  return 1.0;
}

/** s the braking rule looks ahead for `c`: its stop time at the full
 *  command, halved, plus the margin and one step. */
double brakingHorizon(const LocalCostmap& map, const Twist& c, const RobotParams& r, double step,
                      double margin) {
  const double m = std::max(std::abs(c.v) / r.acc_v, std::abs(c.w) / r.acc_w);
  return m / 2 + marginTime(c, margin, map.footprint().circumscribed) + step;
}

}  // namespace

double brakingScale(const LocalCostmap& map, const TPose2D& pose, const Twist& c,
                    const RobotParams& r, double step, double margin) {
  if (c.v == 0 && c.w == 0) return 1;
  // Look as far ahead along the arc as braking from this command needs.
  const double m = std::max(std::abs(c.v) / r.acc_v, std::abs(c.w) / r.acc_w);
  const double margin_t = marginTime(c, margin, map.footprint().circumscribed);
  const double horizon = brakingHorizon(map, c, r, step, margin);
  const Trajectory tr = rollout(map, pose, c, horizon, step / 2, 0.0);
  if (tr.collides && map.check(pose).collision) return moveAwayScale(map, pose, c, horizon, step);
  // leaving the map: unknown beyond, treated as an obstacle
  const double ttc =
      tr.collides || tr.leaves_map ? tr.time_to_collision : std::numeric_limits<double>::infinity();
  if (!std::isfinite(ttc)) return 1;
  // Braking from s (v, w) covers the arc of s^2 m / 2 seconds at the full
  // command; it must end margin_t before the contact: s^2 <= 2 (ttc - margin_t) / m.
  // One rollout step less: the contact time is only known to a step.
  const double room = ttc - margin_t - step / 2;
  return room <= 0 ? 0.0 : std::min(1.0, std::sqrt(2 * room / m));
}

bool canStopFrom(const LocalCostmap& map, const TPose2D& pose, const MotionState& st,
                 const Twist& c, const RobotParams& r, double margin) {
  const double R = map.footprint().circumscribed;
  const double brake_at = st.latency + st.period + marginTime(c, margin, R);
  const CommandMotion motion(pose, st, c, r, brake_at);
  // A check every cell of sweep (path plus a corner's travel) and where
  // the robot stops.
  const double end = motion.settled(), dt = 0.01;
  TPose2D last = pose;
  double swept = 0;
  if (map.check(pose, 0.0).collision) return false;
  for (double t = dt;; t += dt) {
    const double tt = std::min(t, end);
    const TPose2D p = motion.pose(tt);
    const double dphi = std::remainder(p.phi - last.phi, 2 * M_PI);
    swept += std::hypot(p.x - last.x, p.y - last.y) + std::abs(dphi) * R;
    last = p;
    if (swept >= map.resolution() || tt >= end) {
      const FootprintCheck k = map.check(p, 0.0);  // contact only
      if (k.outside || k.collision) return false;
      swept = 0;
    }
    if (tt >= end) return true;
  }
}

double brakingScale(const LocalCostmap& map, const TPose2D& pose, const Twist& c,
                    const RobotParams& r, double step, double margin, const MotionState* st) {
  if (!st) return brakingScale(map, pose, c, r, step, margin);
  if (c.v == 0 && c.w == 0) return 1;
  if (map.check(pose, 0.0).collision)
    return moveAwayScale(map, pose, c, brakingHorizon(map, c, r, step, margin), step);
  if (canStopFrom(map, pose, *st, c, r, margin)) return 1;
  // The largest scale that still stops in time (bisection; 0 when none does).
  double lo = 0, hi = 1;
  for (int i = 0; i < 6; ++i) {
    const double mid = (lo + hi) / 2;
    if (canStopFrom(map, pose, *st, {c.v * mid, c.w * mid}, r, margin))
      lo = mid;
    else
      hi = mid;
  }
  return lo;
}

SafetyDecision SafetySupervisor::apply(const SafetyInput& in) const {
  SafetyDecision d;
  auto stop = [&](SafetyRule rule, const std::string& why) {
    d.cmd = {};
    d.action = SafetyAction::Stop;
    d.rule = rule;
    d.reason = why;
    return d;
  };
  if (!in.last_scan_time || in.now - *in.last_scan_time > p_.sensor_timeout)
    return stop(SafetyRule::StaleSensor, "stale sensor data");
  if (!in.last_odom_time || in.now - *in.last_odom_time > p_.odom_timeout)
    return stop(SafetyRule::StaleOdometry, "stale odometry");
  if (in.needs_intent) {
    if (!in.last_intent_time || !in.user || in.now - *in.last_intent_time > p_.intent_timeout)
      return stop(SafetyRule::StaleIntent, "stale user command");
    if (std::abs(in.user->v) < p_.intent_deadband && std::abs(in.user->w) < p_.intent_deadband)
      return stop(SafetyRule::UserStopped, "user stopped");
  }
  if (!in.plan.ok)
    return stop(SafetyRule::NoPlan,
                in.plan.note.empty() ? "no admissible trajectory" : in.plan.note);
  if (!in.map) return stop(SafetyRule::NoLocalMap, "no local map");
  Twist c = in.plan.cmd;
  c.v = std::clamp(c.v, r_.v_min, r_.v_max);
  c.w = std::clamp(c.w, -r_.w_max, r_.w_max);
  if (c.v == 0 && c.w == 0) {
    d.cmd = c;
    d.action = SafetyAction::Pass;
    return d;
  }
  const double margin = in.plan.margin >= 0 ? in.plan.margin : r_.safe_distance;
  const double s =
      brakingScale(*in.map, in.pose, c, r_, sim_step_, margin, in.motion ? &*in.motion : nullptr);
  if (s <= 1e-3) return stop(SafetyRule::CannotBrake, "cannot brake before the obstacle ahead");
  d.cmd = {c.v * s, c.w * s};
  d.action = s < 1 ? SafetyAction::Slow : SafetyAction::Pass;
  if (s < 1 || c.v != in.plan.cmd.v || c.w != in.plan.cmd.w) {
    d.action = SafetyAction::Slow;
    d.rule = s < 1 ? SafetyRule::Braking : SafetyRule::Limits;
    d.reason =
        s < 1 ? "slowed to brake before the obstacle ahead" : "clamped to the robot's limits";
  }
  return d;
}

}  // namespace carenav::navigation
