// Recovery behaviours (docs/navigate.md, "Recovery"): back out along the
// recent path, turn on the spot, wait; then replan. Nav2's recoveries
// (back up, spin, wait) are the model.
#include <carenav/navigation/polyline.h>
#include <carenav/navigation/recovery.h>
#include <carenav/navigation/safety.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace carenav::navigation {

namespace {

/** Distance from (x, y) to the polyline of the poses' positions. */
double distanceToPoses(const std::vector<TPose2D>& path, double x, double y) {
  return nearestOnPolyline(path, x, y).distance;  // +inf when empty
}

/** Spacing of the recorded path's points (m). */
constexpr double kPathSpacing = 0.03;
/** Pure-pursuit look-ahead when backing out along the recorded path (m). */
constexpr double kBackLookahead = 0.3;
/** Facing the route within this, a turn is done (rad: 15 deg). */
constexpr double kFacing = 15.0 * M_PI / 180.0;
/** A maneuver is planned again at most this many times (a step ended off
 *  its pose, or its command is no longer admissible). */
constexpr int kManeuverReplans = 3;
/** A back-out that has not yet reached a place where the robot can turn to
 *  face the route goes on up to this many times `backup_distance`. */
constexpr double kTurnableBackups = 3.0;

/** Where a maneuver may reverse: a grid of cells around the robot known
 *  free (under the footprint along the recorded path, or seen free by a
 *  sensor lately), and the footprint where the robot stands. */
class KnownFree {
 public:
  KnownFree(const TPose2D& at, double radius, double res, const Footprint& fp)
      : at_(at), res_(res), fp_(fp) {
    ix0_ = static_cast<int64_t>(std::floor((at.x - radius) / res));
    iy0_ = static_cast<int64_t>(std::floor((at.y - radius) / res));
    n_ = static_cast<int64_t>(std::ceil(2 * radius / res)) + 2;
    cells_.assign(static_cast<size_t>(n_ * n_), 0);
  }
  /** Cells whose centre the footprint at `p` covers. */
  void addFootprint(const TPose2D& p) {
    const double c = std::cos(p.phi), s = std::sin(p.phi), r = fp_.circumscribed;
    for (int64_t iy = cell(p.y - r, iy0_); iy <= cell(p.y + r, iy0_); ++iy)
      for (int64_t ix = cell(p.x - r, ix0_); ix <= cell(p.x + r, ix0_); ++ix) {
        if (!inside(ix, iy)) continue;
        const double dx = (ix0_ + ix + 0.5) * res_ - p.x, dy = (iy0_ + iy + 0.5) * res_ - p.y;
        if (fp_.contains(c * dx + s * dy, -s * dx + c * dy)) cells_[index(ix, iy)] = 1;
      }
  }
  /** Cells whose sighting `fresh` accepts. */
  template <class Fresh>
  void addSeen(const SeenFree& seen, const Fresh& fresh) {
    for (int64_t iy = 0; iy < n_; ++iy)
      for (int64_t ix = 0; ix < n_; ++ix) {
        const SeenFree::Sight* s = seen.at((ix0_ + ix + 0.5) * res_, (iy0_ + iy + 0.5) * res_);
        if (s && fresh(*s)) cells_[index(ix, iy)] = 1;
      }
  }
  /** Every sample of the footprint at `q` lies in the footprint where the
   *  robot stands or in a known-free cell. */
  bool covers(const TPose2D& q) const {
    const double cq = std::cos(q.phi), sq = std::sin(q.phi);
    const double ca = std::cos(at_.phi), sa = std::sin(at_.phi);
    auto known = [&](const TPoint2D& p) {
      const double x = q.x + cq * p.x - sq * p.y, y = q.y + sq * p.x + cq * p.y;
      const int64_t ix = cell(x, ix0_), iy = cell(y, iy0_);
      if (inside(ix, iy) && cells_[index(ix, iy)]) return true;
      const double dx = x - at_.x, dy = y - at_.y;
      return fp_.contains(ca * dx + sa * dy, -sa * dx + ca * dy);
    };
    return std::all_of(fp_.boundary.begin(), fp_.boundary.end(), known) &&
           std::all_of(fp_.interior.begin(), fp_.interior.end(), known);
  }

 private:
  int64_t cell(double v, int64_t origin) const {
    return static_cast<int64_t>(std::floor(v / res_)) - origin;
  }
  bool inside(int64_t ix, int64_t iy) const { return ix >= 0 && iy >= 0 && ix < n_ && iy < n_; }
  size_t index(int64_t ix, int64_t iy) const { return static_cast<size_t>(iy * n_ + ix); }
  TPose2D at_;
  double res_;
  const Footprint& fp_;
  int64_t ix0_ = 0, iy0_ = 0, n_ = 0;
  std::vector<uint8_t> cells_;
};

}  // namespace

const ParamTable<RecoveryParams>& RecoveryParams::table() {
  using P = RecoveryParams;
  static const auto t =
      ParamTable<P>()
          .flag("enabled", &P::enabled,
                "goal robots recover when boxed in or making no progress (back out, turn, wait, "
                "replan; give up after max_attempts); off: the planner alone")
          .real("stuck_time", &P::stuck_time, "s", 0.1, 60,
                "boxed in: no admissible trajectory, or stopped by the supervisor, this long")
          .real("progress_time", &P::progress_time, "s", 1, 600,
                "no progress: the route left has not shrunk by progress_distance for this long")
          .real("progress_distance", &P::progress_distance, "m", 0.01, 10,
                "shrinking of the route left that counts as progress")
          .real("still_time", &P::still_time, "s", 0, 600,
                "standing still: moved less than still_distance and turned less than "
                "still_deg for this long, while not blocked (a planner turning left and right "
                "on the spot); 0: off")
          .real("still_distance", &P::still_distance, "m", 0.001, 1,
                "standing still: moved less than this")
          .real("still_deg", &P::still_deg, "deg", 1, 180, "standing still: turned less than this")
          .real("backup_distance", &P::backup_distance, "m", 0.05, 5,
                "backed out along the recent path per attempt (times the attempt, at most 3)")
          .real("backup_speed", &P::backup_speed, "m/s", 0.01, 2,
                "reversing speed (at most the robot's -v_min; a robot with v_min = 0 does not "
                "reverse)")
          .real("backup_margin", &P::backup_margin, "m", 0, 1,
                "the supervisor's margin before a contact for recovery moves (a crawl out of a "
                "wedge), instead of the robot's safe_distance; a command is used only when the "
                "supervisor passes it unchanged")
          .real("path_corridor", &P::path_corridor, "m", 0.01, 1,
                "reversing stays this close to the recorded path (known free)")
          .real("spin_deg", &P::spin_deg, "deg", 1, 360,
                "most a turn on the spot turns per attempt (towards the route)")
          .real("wait_time", &P::wait_time, "s", 0, 60,
                "waiting when neither backing out nor turning is free")
          .integer("max_attempts", &P::max_attempts, "", 1, 1000,
                   "recoveries without progress before giving up")
          .real("path_memory", &P::path_memory, "m", 0.1, 50,
                "length of the robot's recent path kept for backing out")
          .integer("avoid_after", &P::avoid_after, "", 0, 1000,
                   "recoveries begun at one place (within 2 x avoid_radius) before the route "
                   "is planned around it until the next goal; 0: never")
          .real("avoid_radius", &P::avoid_radius, "m", 0.01, 5,
                "radius of the disk around such a place that the route keeps clear of (the "
                "robot's own radius and the route's clearance on top)")
          .real("odom_error_d", &P::odom_error_d, "m/m", 0, 1,
                "odometry error bound per metre travelled: a recorded pose is known free "
                "while the error since, at the footprint's corners, is at most backup_margin")
          .real("odom_error_w", &P::odom_error_w, "rad/rad", 0, 1,
                "odometry heading error bound per radian turned")
          .real("odom_error_wd", &P::odom_error_wd, "rad/m", 0, 1,
                "odometry heading error bound per metre travelled")
          .real("seen_keep", &P::seen_keep, "s", 0, 600,
                "a maneuver may also reverse where a sensor saw free space this recently (the "
                "lidar's blind rear was in view before; odometry error since within "
                "backup_margin); 0: over the recorded path only");
  return t;
}

Recovery::Recovery(const RecoveryParams& p, const RobotParams& robot, const NavigationParams& nav,
                   const ManeuverParams& mp)
    : p_(p), r_(robot), nav_(nav), planner_(mp, robot), seen_(nav.resolution, 0) {
  for (const auto& q : r_.footprint) lever_ = std::max(lever_, std::hypot(q.x, q.y));
  seen_ = SeenFree(nav.resolution, knownRadius());
}

double Recovery::knownRadius() const { return planner_.params().radius + lever_ + nav_.resolution; }

bool Recovery::fresh(const SeenFree::Sight& s, double now) const {
  return now - s.t <= p_.seen_keep && odomError(s.travel, s.turned) <= p_.backup_margin;
}

double Recovery::odomError(double travel, double turned) const {
  const double d = travel_ - travel, a = turned_ - turned;
  return p_.odom_error_d * d + (p_.odom_error_w * a + p_.odom_error_wd * d) * lever_;
}

void Recovery::addSeen(const WorldScan& scan, double t) {
  if (!(p_.seen_keep > 0)) return;
  seen_.prune(scan.robot.value_or(scan.origin),
              [&](const SeenFree::Sight& s) { return fresh(s, t); });
  seen_.addScan(scan, {t, travel_, turned_});
}

const char* Recovery::phaseName(Phase p) {
  switch (p) {
    case Phase::Idle:
      return "";
    case Phase::Maneuver:
      return "maneuver";
    case Phase::BackUp:
      return "back out";
    case Phase::Spin:
      return "turn";
    case Phase::Wait:
      return "wait";
    case Phase::GaveUp:
      return "gave up";
  }
  return "?";
}

void Recovery::trackOdometry(const TPose2D& pose) {
  if (odo_last_) {
    travel_ += std::hypot(pose.x - odo_last_->x, pose.y - odo_last_->y);
    turned_ += std::abs(angleDiff(pose.phi, odo_last_->phi));
  }
  odo_last_ = pose;
  // The error of a recorded pose grows with what the odometry measured
  // since: the oldest go first.
  size_t drop = 0;
  while (drop < path_odo_.size()) {
    if (odomError(path_odo_[drop].first, path_odo_[drop].second) <= p_.backup_margin) break;
    ++drop;
  }
  path_.erase(path_.begin(), path_.begin() + static_cast<std::ptrdiff_t>(drop));
  path_odo_.erase(path_odo_.begin(), path_odo_.begin() + static_cast<std::ptrdiff_t>(drop));
}

void Recovery::recordPose(const TPose2D& pose) {
  trackOdometry(pose);
  if (phase_ == Phase::BackUp) return;  // retracing: the path is cut when backing ends
  if (!path_.empty() && std::hypot(pose.x - path_.back().x, pose.y - path_.back().y) < kPathSpacing)
    return;
  path_.push_back(pose);
  path_odo_.push_back({travel_, turned_});
  // keep path_memory metres
  double len = 0;
  size_t keep = 0;
  for (size_t i = path_.size() - 1; i > 0; --i) {
    len += std::hypot(path_[i].x - path_[i - 1].x, path_[i].y - path_[i - 1].y);
    if (len > p_.path_memory) {
      keep = i - 1;
      break;
    }
  }
  if (keep > 0) {
    path_.erase(path_.begin(), path_.begin() + static_cast<std::ptrdiff_t>(keep));
    path_odo_.erase(path_odo_.begin(), path_odo_.begin() + static_cast<std::ptrdiff_t>(keep));
  }
}

size_t Recovery::nearestIndex(const TPose2D& pose) const {
  size_t best = 0;
  double bd = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < path_.size(); ++i) {
    const double d = std::hypot(path_[i].x - pose.x, path_[i].y - pose.y);
    if (d <= bd) bd = d, best = i;  // ties: the newest
  }
  return best;
}

bool Recovery::reverseAdmissible(const LocalCostmap& map, const TPose2D& pose,
                                 const Twist& cmd) const {
  if (cmd.v == 0 || cmd.v < r_.v_min - 1e-9 || cmd.v > r_.v_max + 1e-9 || path_.size() < 2)
    return false;
  // The supervisor's rule, unchanged: the command passes without slowing.
  if (brakingScale(map, pose, cmd, r_, nav_.sim_step, p_.backup_margin,
                   motion_ ? &*motion_ : nullptr) < 1.0)
    return false;
  // ... and the poses it sweeps until it could stop (one cycle, braking and
  // the safe distance) stay on the way the robot came.
  const double u = std::abs(cmd.v);
  const double dist = u * 2 * nav_.sim_step + u * u / (2 * r_.acc_v) + p_.backup_margin;
  const double horizon = dist / u;
  const double step = nav_.sim_step / 2;
  for (double t = step; t <= horizon + 1e-9; t += step) {
    const TPose2D q = integrateArc(pose, cmd.v, cmd.w, t);
    if (distanceToPoses(path_, q.x, q.y) > p_.path_corridor) return false;
  }
  return true;
}

std::optional<Twist> Recovery::backOutCommand(const LocalCostmap& map, const TPose2D& pose) const {
  if (path_.size() < 2) return std::nullopt;
  const size_t i = nearestIndex(pose);
  if (i == 0) return std::nullopt;  // at the oldest point: nothing left behind
  // the point kBackLookahead metres back along the recorded path
  double left = kBackLookahead;
  TPoint2D target{path_[0].x, path_[0].y};
  TPoint2D prev{pose.x, pose.y};
  for (size_t k = i + 1; k-- > 0;) {
    const double d = std::hypot(path_[k].x - prev.x, path_[k].y - prev.y);
    if (d >= left) {
      target = {prev.x + (path_[k].x - prev.x) * left / d,
                prev.y + (path_[k].y - prev.y) * left / d};
      break;
    }
    left -= d;
    prev = {path_[k].x, path_[k].y};
  }
  const double L = std::hypot(target.x - pose.x, target.y - pose.y);
  if (L < 0.02) return std::nullopt;
  const double bearing = std::atan2(target.y - pose.y, target.x - pose.x);
  // Pure pursuit along the way back: reversing when it lies behind (the
  // rear is the heading plus pi), forwards when the robot has turned to
  // face it.
  const double a_rear = angleDiff(bearing, pose.phi + M_PI);
  const bool reverse = std::abs(a_rear) <= M_PI / 2;
  const double u =
      reverse ? std::min(p_.backup_speed, -r_.v_min) : std::min(p_.backup_speed, r_.v_max);
  if (!(u > 0)) return std::nullopt;
  const double alpha = reverse ? a_rear : angleDiff(bearing, pose.phi);
  const double sgn = reverse ? -1.0 : 1.0;
  const double w = std::clamp(2 * u * std::sin(alpha) / L, -r_.w_max, r_.w_max);
  for (const Twist c : {Twist{sgn * u, w}, Twist{sgn * u, 0.0}, Twist{sgn * u / 2, w / 2}}) {
    if (reverseAdmissible(map, pose, c)) return c;
  }
  return std::nullopt;
}

double Recovery::routeError(const PlannerInput& in) const {
  if (!in.path.empty()) {
    const TPoint2D t = lookaheadPoint(in.path, in.pose.x, in.pose.y, nav_.lookahead);
    return angleDiff(std::atan2(t.y - in.pose.y, t.x - in.pose.x), in.pose.phi);
  }
  if (in.goal)
    return angleDiff(std::atan2(in.goal->y - in.pose.y, in.goal->x - in.pose.x), in.pose.phi);
  return 0;
}

bool Recovery::canFaceRoute(const PlannerInput& in) const {
  const double err = routeError(in);
  if (std::abs(err) <= kFacing) return true;
  return in.map && turnFree(*in.map, in.pose, err - std::copysign(kFacing, err));
}

std::optional<Twist> Recovery::spinCommand(const PlannerInput& in, bool toward_only) const {
  if (!in.map) return std::nullopt;
  const double err = routeError(in);
  const double w = 0.5 * r_.w_max;
  const double dir0 = spin_dir_ != 0 ? spin_dir_ : (err >= 0 ? 1.0 : -1.0);
  const double angle =
      std::min(mrpt::DEG2RAD(20.0), std::min(mrpt::DEG2RAD(p_.spin_deg), M_PI) - spun_);
  if (angle <= 0) return std::nullopt;
  for (const double dir : {dir0, -dir0}) {
    if ((spin_dir_ != 0 || toward_only) && dir != dir0) break;  // a turn keeps its direction
    const Twist cmd{0, dir * w};
    const Trajectory tr = rollout(*in.map, in.pose, cmd, angle / w, nav_.sim_step / 2, 0.0);
    if (tr.admissible() && brakingScale(*in.map, in.pose, cmd, r_, nav_.sim_step, p_.backup_margin,
                                        motion_ ? &*motion_ : nullptr) >= 1.0)
      return cmd;
  }
  return std::nullopt;
}

PlannerOutput Recovery::command(const Twist& cmd, const std::string& note) const {
  PlannerOutput o;
  o.ok = true;
  o.cmd = cmd;
  o.note = note;
  o.margin = p_.backup_margin;
  return o;
}

void Recovery::routeChanged(double) {
  // Progress is measured on the new route from the next cycle, but the time
  // since the last progress keeps running: a route replanned every few
  // seconds around a robot that goes nowhere must not hide that it does.
  rebase_ = true;
}

void Recovery::newGoal(double now) {
  have_best_ = false;
  rebase_ = false;
  best_t_ = now;
  phase_ = Phase::Idle;
  reason_.clear();
  attempts_ = 0;
  replan_ = false;
  blocked_since_.reset();
  still_.reset();
}

void Recovery::start(double now, const PlannerInput& in, const std::string& why) {
  ++recoveries_;
  ++attempts_;
  reason_ = why;
  phase_t0_ = now;
  last_pose_ = start_pose_ = in.pose;
  backed_ = spun_ = spin_dir_ = 0;
  facing_ = false;
  blocked_since_.reset();
  man_ = planManeuver(in);
  if (man_) {
    phase_ = Phase::Maneuver;
    man_step_ = 0;
    man_done_ = 0;
    man_replans_ = 0;
    man_limit_ = now + maneuverDuration(*man_) * 3 + 2.0;
    return;
  }
  startFallback(now, in);
}

void Recovery::startFallback(double now, const PlannerInput& in) {
  phase_t0_ = now;
  if (in.map && backOutCommand(*in.map, in.pose)) {
    phase_ = Phase::BackUp;
  } else if (auto s = spinCommand(in)) {
    phase_ = Phase::Spin;
    spin_dir_ = s->w > 0 ? 1.0 : -1.0;
  } else {
    phase_ = Phase::Wait;
  }
}

double Recovery::maneuverSpeed(int dir) const {
  return std::min(p_.backup_speed, dir < 0 ? -r_.v_min : r_.v_max);
}

double Recovery::maneuverTurnRate() const {
  // the footprint's corner no faster than twice the straights' speed
  return std::min(0.5 * r_.w_max, 2 * maneuverSpeed(1) / std::max(lever_, 0.05));
}

double Recovery::maneuverDuration(const Maneuver& m) const {
  double t = 0;
  for (const auto& s : m.steps)
    t += s.dir == 0 ? std::abs(s.turn) / maneuverTurnRate() : s.length / maneuverSpeed(s.dir);
  return t;
}

std::optional<TPose2D> Recovery::maneuverGoal(const PlannerInput& in) const {
  if (in.path.size() < 2 || !in.map) return std::nullopt;
  const ManeuverParams& mp = planner_.params();
  const double x = in.pose.x, y = in.pose.y;
  for (double along = mp.reach; along <= mp.reach + 1.0 + 1e-9; along += 0.25) {
    const TPoint2D a = lookaheadPoint(in.path, x, y, along);
    TPoint2D b = lookaheadPoint(in.path, x, y, along + 0.2);
    TPoint2D o = a;
    if (std::hypot(b.x - a.x, b.y - a.y) < 0.05) {  // the route's end: its last way
      o = lookaheadPoint(in.path, x, y, std::max(0.0, along - 0.2));
      b = a;
    }
    if (std::hypot(b.x - o.x, b.y - o.y) < 0.05) return std::nullopt;
    const TPose2D g{a.x, a.y, std::atan2(b.y - o.y, b.x - o.x)};
    const FootprintCheck k = in.map->check(g, mp.margin);
    if (!k.collision && !k.outside && k.clearance >= mp.margin) return g;
    if (b.x == a.x && b.y == a.y) return std::nullopt;  // nothing further to try
  }
  return std::nullopt;
}

std::optional<Maneuver> Recovery::planManeuver(const PlannerInput& in) const {
  if (!planner_.params().enabled || !in.map) return std::nullopt;
  const auto goal = maneuverGoal(in);
  if (!goal) return std::nullopt;
  // Reversing only over the way the robot came (its footprint swept it)
  // or over space a sensor saw free lately (the lidar's blind rear).
  const Footprint& fp = in.map->footprint();
  KnownFree known(in.pose, knownRadius(), nav_.resolution, fp);
  for (const auto& q : path_) known.addFootprint(q);
  if (p_.seen_keep > 0)
    known.addSeen(seen_, [&](const SeenFree::Sight& s) { return fresh(s, in.t); });
  const auto swept = [&](const TPose2D& q) { return known.covers(q); };
  auto m = planner_.plan(*in.map, in.pose, *goal, swept);
  if (m && m->steps.empty()) return std::nullopt;  // already there: nothing to maneuver
  return m;
}

std::optional<Twist> Recovery::stepCommand(const PlannerInput& in, const ManeuverStep& s,
                                           double remaining) const {
  const double step_dt = motion_ ? motion_->period : nav_.sim_step;
  Twist cmd;
  if (s.dir == 0) {
    cmd.w = std::copysign(std::min(maneuverTurnRate(), remaining / step_dt), s.turn);
  } else {
    const double u = std::min(maneuverSpeed(s.dir), remaining / step_dt);
    cmd.v = s.dir * u;
    // The curvature that ends the step at its planned heading: the arc's
    // own when the robot is on it, and a correction when it is not.
    const double w_max = maneuverTurnRate();
    cmd.w = std::clamp(u * angleDiff(s.end.phi, in.pose.phi) / std::max(remaining, 0.05), -w_max,
                       w_max);
  }
  // The supervisor's rule looks a cycle further at speed than the
  // maneuver's margin: slower, it looks no further than the margin.
  for (const double scale : {1.0, 0.5, 0.25}) {
    const Twist c{cmd.v * scale, cmd.w * scale};
    if (brakingScale(*in.map, in.pose, c, r_, nav_.sim_step, p_.backup_margin,
                     motion_ ? &*motion_ : nullptr) >= 1.0)
      return c;
  }
  return std::nullopt;
}

bool Recovery::replanManeuver(const PlannerInput& in) {
  if (++man_replans_ > kManeuverReplans) return false;
  man_ = planManeuver(in);
  man_step_ = 0;
  man_done_ = 0;
  return man_.has_value();
}

std::optional<Twist> Recovery::maneuverCommand(const PlannerInput& in) {
  while (man_ && man_step_ < man_->steps.size()) {
    const ManeuverStep& s = man_->steps[man_step_];
    // A turn ends at its planned heading, not after its angle (one that
    // overshot leaves the next step no error to carry); by the angle turned
    // while more than a right angle is left (a heading is ambiguous beyond).
    double remaining = (s.dir == 0 ? std::abs(s.turn) : s.length) - man_done_;
    if (s.dir == 0 && remaining <= M_PI / 2)
      remaining = std::copysign(1.0, s.turn) * angleDiff(s.end.phi, in.pose.phi);
    if (remaining > (s.dir == 0 ? 0.02 : 0.01)) {
      if (auto c = stepCommand(in, s, remaining)) return c;
      // Not admissible from where the robot is, with what it sees now:
      // planned again from here.
      if (!replanManeuver(in)) return std::nullopt;
      continue;
    }
    // The step is done: on to the next, planned again when the robot
    // ended it off its pose.
    const bool off = std::hypot(in.pose.x - s.end.x, in.pose.y - s.end.y) > 0.1 ||
                     std::abs(angleDiff(in.pose.phi, s.end.phi)) > mrpt::DEG2RAD(10.0);
    ++man_step_;
    man_done_ = 0;
    if (off && man_step_ < man_->steps.size() && !replanManeuver(in)) return std::nullopt;
  }
  return std::nullopt;  // done (maneuverDone)
}

void Recovery::cutRetraced() {
  const size_t i = nearestIndex(last_pose_);
  path_.resize(std::min(path_.size(), i + 1));
  path_odo_.resize(path_.size());
}

void Recovery::finish(double now) {
  if (phase_ == Phase::BackUp) cutRetraced();
  phase_ = Phase::Idle;
  replan_ = true;
  best_t_ = now;  // the planner gets a fresh window
  blocked_since_.reset();
  still_.reset();
}

bool Recovery::standingStill(double now, const TPose2D& pose, bool at_goal) {
  const bool moved =
      still_ &&
      (std::hypot(pose.x - still_->first.x, pose.y - still_->first.y) > p_.still_distance ||
       std::abs(angleDiff(pose.phi, still_->first.phi)) > mrpt::DEG2RAD(p_.still_deg));
  if (!still_ || moved || at_goal) still_ = std::make_pair(pose, now);
  return p_.still_time > 0 && now - still_->second >= p_.still_time;
}

std::optional<PlannerOutput> Recovery::step(double now, const PlannerInput& in,
                                            const PlannerOutput& plan, bool blocked,
                                            double route_left) {
  if (!p_.enabled) return std::nullopt;
  motion_ = in.motion;
  if (phase_ == Phase::GaveUp) {
    PlannerOutput o;
    o.note = "gave up: " + reason_;
    return o;
  }
  // Progress along the route (near the goal: turning to its heading is progress).
  if (rebase_ && have_best_) {
    // the new route's length, less what was gained since the best on the old one
    best_left_ = route_left + std::max(0.0, best_left_ - last_left_);
  }
  rebase_ = false;
  last_left_ = route_left;
  if (!have_best_ || route_left < best_left_ - p_.progress_distance ||
      route_left < nav_.goal_tolerance) {
    if (have_best_ && route_left < best_left_ - p_.progress_distance) attempts_ = 0;
    best_left_ = route_left;
    best_t_ = now;
    have_best_ = true;
  }
  if (phase_ == Phase::Idle) {
    const bool still = standingStill(now, in.pose, route_left < nav_.goal_tolerance);
    if (plan.ok && plan.status == PlanStatus::GoalReached) return std::nullopt;
    if (blocked) {
      if (!blocked_since_) blocked_since_ = now;
    } else {
      blocked_since_.reset();
    }
    std::string why;
    if (blocked_since_ && now - *blocked_since_ >= p_.stuck_time)
      why = "boxed in";
    else if (now - best_t_ >= p_.progress_time)
      why = "no progress";
    else if (still)
      why = "standing still";
    if (why.empty()) return std::nullopt;
    if (attempts_ >= p_.max_attempts) {
      phase_ = Phase::GaveUp;
      reason_ = why + " after " + std::to_string(attempts_) + " recoveries";
      PlannerOutput o;
      o.note = "gave up: " + reason_;
      return o;
    }
    start(now, in, why);
  }
  // The recovery under way.
  if (phase_ == Phase::Maneuver && !man_) startFallback(now, in);
  if (phase_ == Phase::Maneuver) {
    const auto& st = man_->steps[std::min(man_step_, man_->steps.size() - 1)];
    man_done_ += st.dir == 0 ? std::abs(angleDiff(in.pose.phi, last_pose_.phi))
                             : std::hypot(in.pose.x - last_pose_.x, in.pose.y - last_pose_.y);
    last_pose_ = in.pose;
    std::optional<Twist> c;
    if (now <= man_limit_) c = maneuverCommand(in);
    if (c) return command(*c, "recovery (" + reason_ + "): maneuver");
    if (man_ && man_step_ >= man_->steps.size()) {  // every step driven
      finish(now);
      return command({0, 0}, "recovery (" + reason_ + "): maneuvered, replanning");
    }
    startFallback(now, in);  // not admissible any more, or too long: back out, turn or wait
  }
  if (phase_ == Phase::BackUp) {
    backed_ += std::hypot(in.pose.x - last_pose_.x, in.pose.y - last_pose_.y);
    last_pose_ = in.pose;
    // At least backup_distance times the attempt, and on to where the
    // robot can turn to face the route (a robot backed out of a gap's mouth
    // by less came straight back into it skewed).
    const double target = p_.backup_distance * std::min(attempts_, 3);
    const bool further =
        backed_ < target || (backed_ < kTurnableBackups * p_.backup_distance && !canFaceRoute(in));
    std::optional<Twist> c;
    if (further && in.map) c = backOutCommand(*in.map, in.pose);
    if (c) return command(*c, "recovery (" + reason_ + "): back out");
    if (backed_ < 0.05) {
      // could not back out after all: turn or wait instead
      if (auto s = spinCommand(in)) {
        phase_ = Phase::Spin;
        spin_dir_ = s->w > 0 ? 1.0 : -1.0;
      } else {
        phase_ = Phase::Wait;
        phase_t0_ = now;
      }
    } else if (std::abs(routeError(in)) > kFacing && spinCommand(in, true)) {
      // face the route before the planner resumes: it enters straight
      cutRetraced();
      phase_ = Phase::Spin;
      spun_ = spin_dir_ = 0;
      facing_ = true;
    } else {
      finish(now);
      return command({0, 0}, "recovery (" + reason_ + "): backed out, replanning");
    }
  }
  if (phase_ == Phase::Spin) {
    spun_ += std::abs(angleDiff(in.pose.phi, last_pose_.phi));
    last_pose_ = in.pose;
    std::optional<Twist> c;
    if (std::abs(routeError(in)) > kFacing || spun_ < 0.05) c = spinCommand(in, facing_);
    if (c) return command(*c, "recovery (" + reason_ + "): turn");
    if (spun_ < 0.05 && !facing_) {
      phase_ = Phase::Wait;
      phase_t0_ = now;
    } else {
      finish(now);
      return command({0, 0}, "recovery (" + reason_ + "): turned, replanning");
    }
  }
  if (phase_ == Phase::Wait) {
    if (now - phase_t0_ >= p_.wait_time) {
      finish(now);
      return command({0, 0}, "recovery (" + reason_ + "): waited, replanning");
    }
    return command({0, 0}, "recovery (" + reason_ + "): wait");
  }
  return std::nullopt;
}

}  // namespace carenav::navigation
