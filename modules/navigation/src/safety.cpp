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
  const Trajectory tr = rollout(map, pose, cmd, horizon, p_.sim_step / 2, 0.0);
  if (tr.collides) return tr.time_to_collision;
  if (tr.leaves_map) return tr.time_to_collision;  // unknown beyond: treat as an obstacle
  return std::numeric_limits<double>::infinity();
}

SafetyDecision SafetySupervisor::apply(const SafetyInput& in) const {
  SafetyDecision d;
  auto stop = [&](const std::string& why) {
    d.cmd = {};
    d.action = SafetyAction::Stop;
    d.reason = why;
    return d;
  };
  if (!in.last_scan_time || in.now - *in.last_scan_time > p_.sensor_timeout)
    return stop("stale sensor data");
  if (!in.last_odom_time || in.now - *in.last_odom_time > p_.odom_timeout)
    return stop("stale odometry");
  if (in.needs_intent) {
    if (!in.last_intent_time || !in.user || in.now - *in.last_intent_time > p_.intent_timeout)
      return stop("stale user command");
    if (std::abs(in.user->v) < p_.intent_deadband && std::abs(in.user->w) < p_.intent_deadband)
      return stop("user stopped");
  }
  if (!in.plan.ok) return stop(in.plan.note.empty() ? "no admissible trajectory" : in.plan.note);
  if (!in.map) return stop("no local map");
  Twist c = in.plan.cmd;
  c.v = std::clamp(c.v, r_.v_min, r_.v_max);
  c.w = std::clamp(c.w, -r_.w_max, r_.w_max);
  if (c.v == 0 && c.w == 0) {
    d.cmd = c;
    d.action = SafetyAction::Pass;
    return d;
  }
  // Look as far ahead along the arc as braking from this command needs.
  const double av = std::abs(c.v), aw = std::abs(c.w);
  const double m = std::max(av / r_.acc_v, aw / r_.acc_w);  // stop time at full command
  const double margin_t = av > 0 ? r_.safe_distance / av : 0.0;
  const double horizon = m / 2 + margin_t + p_.sim_step;
  const double ttc = timeToCollision(*in.map, in.pose, c, horizon);
  double s = 1;
  if (std::isfinite(ttc)) {
    // Braking from s (v, w) covers the arc of s^2 m / 2 seconds at the full
    // command; it must end margin_t before the contact: s^2 <= 2 (ttc - margin_t) / m.
    // One rollout step less: the contact time is only known to a step.
    const double room = ttc - margin_t - p_.sim_step / 2;
    s = room <= 0 ? 0.0 : std::min(1.0, std::sqrt(2 * room / m));
  }
  if (s <= 1e-3) return stop("cannot brake before the obstacle ahead");
  d.cmd = {c.v * s, c.w * s};
  d.action = s < 1 ? SafetyAction::Slow : SafetyAction::Pass;
  if (s < 1 || c.v != in.plan.cmd.v || c.w != in.plan.cmd.w) {
    d.action = SafetyAction::Slow;
    d.reason =
        s < 1 ? "slowed to brake before the obstacle ahead" : "clamped to the robot's limits";
  }
  return d;
}

}  // namespace carenav::navigation
