#include <carenav/common/errors.h>
#include <carenav/navigation/local_planner.h>
#include <carenav/navigation/mrpt_ptg.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace carenav::navigation {

const char* planStatusText(PlanStatus s) {
  switch (s) {
    case PlanStatus::Moving:
      return "";
    case PlanStatus::TurnInPlace:
      return "turn in place";
    case PlanStatus::GoalReached:
      return "goal reached";
    case PlanStatus::NoRoute:
      return "no route";
    case PlanStatus::NoAdmissible:
      return "no admissible trajectory";
    case PlanStatus::NoUserCommand:
      return "no user command";
    case PlanStatus::UserStopped:
      return "user stopped";
  }
  return "?";
}

TPose2D integrateArc(const TPose2D& p, double v, double w, double t) {
  if (std::abs(w) < 1e-9)
    return {p.x + v * t * std::cos(p.phi), p.y + v * t * std::sin(p.phi), p.phi};
  const double phi = p.phi + w * t;
  const double r = v / w;
  const double sp = std::sin(phi), cp = std::cos(phi);
  // the heading wrapped to [-pi, pi] (what atan2(sin, cos) gives, cheaper)
  return {p.x + r * (sp - std::sin(p.phi)), p.y - r * (cp - std::cos(p.phi)),
          phi - 2 * M_PI * std::round(phi / (2 * M_PI))};
}

namespace {

/** The rollout's loop; `poseAt(t, p, sp, cp)` sets the pose at t and the
 *  sine and cosine of its heading. */
template <class PoseAt>
Trajectory rolloutWith(const LocalCostmap& map, const TPose2D& start, const Twist& cmd,
                       double horizon, double step, double clearance_cap, double check_distance,
                       double settled, const PoseAt& poseAt) {
  Trajectory tr;
  tr.cmd = cmd;
  tr.time_to_collision = horizon;
  tr.free_distance = std::numeric_limits<double>::infinity();
  tr.contact_time = std::numeric_limits<double>::infinity();
  tr.clearance = clearance_cap;
  tr.end = start;
  const bool still = cmd.v == 0 && cmd.w == 0 && settled <= 0;
  const int steps = still ? 0 : std::max(1, static_cast<int>(std::ceil(horizon / step - 1e-9)));
  // Beyond the horizon, collisions only, up to check_distance of path (at
  // most 60 s of it).
  int check_steps = steps;
  if (!still && std::abs(cmd.v) * horizon < check_distance)
    check_steps = static_cast<int>(
        std::ceil(std::min(60.0, check_distance / std::max(std::abs(cmd.v), 1e-9)) / step - 1e-9));
  const double sweep = std::abs(cmd.v) + std::abs(cmd.w) * map.footprint().circumscribed;
  for (int k = 0; k <= check_steps; ++k) {
    const double t = k <= steps ? std::min(horizon, k * step) : k * step;
    // Beyond the horizon only contact matters: no clearance wanted (cheaper);
    // and once an arc has closed its circle, the rest repeats it.
    if (k > steps && t - step > settled && std::abs(cmd.w) * (t - step - settled) >= 2 * M_PI)
      break;
    TPose2D p = start;
    double sp = std::sin(start.phi), cp = std::cos(start.phi);
    if (k > 0) poseAt(t, p, sp, cp);
    const FootprintCheck c = map.check(p, k > steps ? 0.0 : clearance_cap, cp, sp);
    if (c.outside) {
      if (k <= steps) tr.leaves_map = true;
      break;
    }
    if (c.collision) {
      // The contact lies between the previous sample and this one.
      const double ttc = std::max(0.0, (k - 1) * step);
      tr.free_distance = ttc * sweep;
      tr.contact_time = ttc;
      if (k <= steps) {
        tr.collides = true;
        tr.clearance = 0;
        tr.time_to_collision = ttc;
      }
      break;
    }
    if (k > steps) continue;
    tr.clearance = std::min(tr.clearance, c.clearance);
    tr.occupancy += map.cellCost(p.x, p.y);
    tr.end = p;
  }
  return tr;
}

}  // namespace

Trajectory rollout(const LocalCostmap& map, const TPose2D& start, const Twist& cmd, double horizon,
                   double step, double clearance_cap, double check_distance) {
  // integrateArc, with the heading's sine and cosine kept for the footprint
  const double s0 = std::sin(start.phi), c0 = std::cos(start.phi);
  const bool straight = std::abs(cmd.w) < 1e-9;
  const double radius = straight ? 0.0 : cmd.v / cmd.w;
  return rolloutWith(map, start, cmd, horizon, step, clearance_cap, check_distance, 0.0,
                     [&](double t, TPose2D& p, double& sp, double& cp) {
                       if (straight) {
                         p = {start.x + cmd.v * t * c0, start.y + cmd.v * t * s0, start.phi};
                         return;
                       }
                       const double phi = start.phi + cmd.w * t;
                       sp = std::sin(phi);
                       cp = std::cos(phi);
                       p = {start.x + radius * (sp - s0), start.y - radius * (cp - c0),
                            phi - 2 * M_PI * std::round(phi / (2 * M_PI))};
                     });
}

Trajectory rollout(const LocalCostmap& map, const CommandMotion& motion, const Twist& cmd,
                   double horizon, double step, double clearance_cap, double check_distance) {
  return rolloutWith(map, motion.pose(0), cmd, horizon, step, clearance_cap, check_distance,
                     motion.settled(), [&](double t, TPose2D& p, double& sp, double& cp) {
                       p = motion.pose(t);
                       sp = std::sin(p.phi);
                       cp = std::cos(p.phi);
                     });
}

CommandMotion::CommandMotion(const TPose2D& start, const MotionState& st, const Twist& cmd,
                             const RobotParams& r, double brake_at) {
  Twist u = st.current;
  Knot k{start, 0.0};
  knots_.push_back(k);
  auto target = [&](double t) {
    if (t + 1e-9 < st.latency) return st.commanded;
    return t + 1e-9 < brake_at ? cmd : Twist{};
  };
  auto toward = [&](double x, double to, double a) {
    return x + std::clamp(to - x, -a * dt_, a * dt_);
  };
  // At most 60 s of ramps (a robot without acceleration limits settles at once).
  for (int i = 0; i < 6000; ++i) {
    const double t = i * dt_;
    const Twist g = target(t);
    const bool later = t + 1e-9 < st.latency || (std::isfinite(brake_at) && t + 1e-9 < brake_at);
    if (!later && std::abs(u.v - g.v) < 1e-9 && std::abs(u.w - g.w) < 1e-9) break;
    u = {r.acc_v > 0 ? toward(u.v, g.v, r.acc_v) : g.v,
         r.acc_w > 0 ? toward(u.w, g.w, r.acc_w) : g.w};
    k.pose = integrateArc(k.pose, u.v, u.w, dt_);
    k.turned += u.w * dt_;
    knots_.push_back(k);
  }
  settle_t_ = (knots_.size() - 1) * dt_;
  final_ = u;
}

TPose2D CommandMotion::pose(double t) const {
  if (t >= settle_t_) return integrateArc(knots_.back().pose, final_.v, final_.w, t - settle_t_);
  const size_t i = static_cast<size_t>(std::max(0.0, t) / dt_ + 0.5);
  return knots_[std::min(i, knots_.size() - 1)].pose;
}

double CommandMotion::turned(double t) const {
  if (t >= settle_t_) return knots_.back().turned + final_.w * (t - settle_t_);
  const size_t i = static_cast<size_t>(std::max(0.0, t) / dt_ + 0.5);
  return knots_[std::min(i, knots_.size() - 1)].turned;
}

bool turnFree(const LocalCostmap& map, const TPose2D& pose, double turn) {
  constexpr double kStep = 0.1;  // rad between footprint samples
  const int n = std::max(1, static_cast<int>(std::ceil(std::abs(turn) / kStep)));
  for (int i = 0; i <= n; ++i)
    if (map.check({pose.x, pose.y, pose.phi + turn * i / n}).collision) return false;
  return true;
}

double marginTime(const Twist& cmd, double margin, double sweep_radius) {
  const double av = std::abs(cmd.v), aw = std::abs(cmd.w);
  if (av > 0) return margin / av;
  return aw > 0 && sweep_radius > 0 ? margin / (aw * sweep_radius) : 0.0;
}

bool canBrake(const Twist& cmd, double time_to_collision, const RobotParams& robot, double margin,
              double sweep_radius) {
  const double av = std::abs(cmd.v), aw = std::abs(cmd.w);
  if (time_to_collision <= 0) return false;  // already in contact
  if (av == 0 && aw == 0) return true;
  // Braking both at the same relative rate keeps the arc; the robot stops
  // after stop_time seconds, having covered the arc of stop_time / 2 seconds
  // at the command (v^2 / 2a for the translation, Eq. 4.1).
  const double stop_time = std::max(av / robot.acc_v, aw / robot.acc_w);
  const double available = time_to_collision - marginTime(cmd, margin, sweep_radius);
  return stop_time / 2 <= available;
}

std::optional<RouteAhead> routeAhead(const PlannerInput& in) {
  if (!in.map || (in.path.empty() && !in.goal)) return std::nullopt;
  RouteAhead r;
  r.path = in.path;
  if (r.path.empty()) r.path.push_back({in.goal->x, in.goal->y});
  r.to_end = std::hypot(r.path.back().x - in.pose.x, r.path.back().y - in.pose.y);
  return r;
}

Window dynamicWindow(const Twist& cur, const RobotParams& r, const DwaParams& p) {
  Window w;
  const double dv = r.acc_v * p.window_time, dw = r.acc_w * p.window_time;
  w.v_lo = std::max(r.v_min, cur.v - dv);
  w.v_hi = std::min(r.v_max, cur.v + dv);
  if (w.v_lo > w.v_hi) w.v_lo = w.v_hi = std::clamp(cur.v, r.v_min, r.v_max);
  w.w_lo = std::max(-r.w_max, cur.w - dw);
  w.w_hi = std::min(r.w_max, cur.w + dw);
  if (w.w_lo > w.w_hi) w.w_lo = w.w_hi = std::clamp(cur.w, -r.w_max, r.w_max);
  return w;
}

namespace {

void linspace(double lo, double hi, int n, std::vector<double>& out) {
  if (n <= 1 || hi - lo < 1e-9) {
    out.push_back(hi);
    return;
  }
  for (int i = 0; i < n; ++i) out.push_back(lo + (hi - lo) * i / (n - 1));
}

}  // namespace

std::vector<Twist> sampleWindow(const Window& win, const DwaParams& p,
                                const std::vector<Twist>& extra) {
  std::vector<double> vs, ws;
  if (win.v_hi > 0) linspace(std::max(win.v_lo, 0.0), win.v_hi, p.v_samples, vs);
  if (win.v_lo < 0) linspace(win.v_lo, std::min(win.v_hi, 0.0), p.v_samples, vs);
  vs.push_back(win.v_lo);
  vs.push_back(win.v_hi);
  if (win.v_lo <= 0 && win.v_hi >= 0) vs.push_back(0);
  linspace(win.w_lo, win.w_hi, p.w_samples, ws);
  if (win.w_lo <= 0 && win.w_hi >= 0) ws.push_back(0);
  auto dedupe = [](std::vector<double>& a) {
    std::sort(a.begin(), a.end());
    a.erase(
        std::unique(a.begin(), a.end(), [](double x, double y) { return std::abs(x - y) < 1e-6; }),
        a.end());
  };
  dedupe(vs);
  dedupe(ws);
  std::vector<Twist> out;
  out.reserve(vs.size() * ws.size() + extra.size());
  for (double v : vs)
    for (double w : ws) out.push_back({v, w});
  for (const auto& e : extra)
    out.push_back({std::clamp(e.v, win.v_lo, win.v_hi), std::clamp(e.w, win.w_lo, win.w_hi)});
  return out;
}

PlannerRegistry::PlannerRegistry() {
  add("user-intent-dwa",
      "walker shared control ([Rosa17, Alg. 4, Eq. 4.10]): the user's (v, w) unless unsafe",
      makeUserIntentDwa);
  add("goal-dwa", "dynamic window towards the next waypoint of the global route", makeGoalDwa);
  add("mrpt-ptg", mrptPtgDescription(),
      [](const NavigationParams& p, const RobotParams& r) { return makeMrptPtg(p, r); });
}

PlannerRegistry& PlannerRegistry::instance() {
  static PlannerRegistry r;
  return r;
}

void PlannerRegistry::add(const std::string& name, const std::string& description,
                          PlannerFactory f) {
  entries_[name] = {description, std::move(f)};
}

std::unique_ptr<LocalPlanner> PlannerRegistry::create(const std::string& name,
                                                      const NavigationParams& p,
                                                      const RobotParams& robot) const {
  const auto it = entries_.find(name);
  if (it == entries_.end()) {
    std::string known;
    for (const auto& [n, e] : entries_) known += (known.empty() ? "" : ", ") + n;
    throw InputError("unknown local planner '" + name + "' (known: " + known + ")");
  }
  return it->second.second(p, robot);
}

std::vector<std::pair<std::string, std::string>> PlannerRegistry::list() const {
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& [n, e] : entries_) out.emplace_back(n, e.first);
  return out;
}

}  // namespace carenav::navigation
