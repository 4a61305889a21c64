// goal-dwa: dynamic window towards the next waypoint of the global route
// (Interbot and HOBBIT: [Conceicao16, Ch. 3]; [Puente14, App. Sec. IV-B]).
#include <carenav/navigation/local_planner.h>
#include <carenav/navigation/polyline.h>
#include <carenav/navigation/safety.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

namespace carenav::navigation {

namespace {

/** Distance from p to the polyline (or to its only point). */
double distanceToPath(const std::vector<TPoint2D>& path, double x, double y) {
  return path.empty() ? 0 : nearestOnPolyline(path, x, y).distance;
}

class GoalDwa final : public LocalPlanner {
 public:
  /** `goal_tolerance` (m) and `goal_tolerance_deg`: when the goal is reached
   *  ([navigation]). */
  GoalDwa(const DwaParams& d, const GoalDwaParams& g, const CommitmentParams& c,
          double goal_tolerance, double goal_tolerance_deg, const RobotParams& r)
      : d_(d),
        g_(g),
        c_(c),
        goal_tol_(goal_tolerance),
        goal_tol_deg_(goal_tolerance_deg),
        r_(r),
        corner_(g.corner_deg > 0 ? mrpt::DEG2RAD(g.corner_deg) : M_PI) {}
  std::string name() const override { return "goal-dwa"; }
  bool needsUserIntent() const override { return false; }
  bool usesMotionState() const override { return true; }

  /** The goal is aimed at within half the tolerance (the estimate is off by
   *  the localisation's error, and a robot that stopped as soon as its
   *  estimate entered the tolerance ended on its edge); within the tolerance
   *  where nothing goes on towards it, it is reached where the robot is. */
  PlannerOutput plan(const PlannerInput& in) override {
    const auto route = routeAhead(in);
    if (!route) {
      PlannerOutput out;
      out.mark(PlanStatus::NoRoute);
      return out;
    }
    const Window win = dynamicWindow(in.current, r_, d_);
    const double to_goal = route->to_end;
    PlannerOutput out;
    if (in.goal && to_goal < aim()) {
      out = atGoal(in, route->path, to_goal, win);
    } else {
      out = approach(in, route->path, to_goal, win);
      if (in.goal && to_goal < goal_tol_ && !(out.ok && std::abs(out.cmd.v) > 1e-6))
        out = atGoal(in, route->path, to_goal, win);
    }
    commit(out);
    return out;
  }

 private:
  static constexpr double kStopped = 0.01;  // m, braking distance of a robot that has stopped
  double aim() const { return goal_tol_ / 2; }
  /** At the goal: brake, turn to its heading, then report it reached once
   *  the robot has (all but) stopped: it brakes to rest within kStopped. */
  PlannerOutput atGoal(const PlannerInput& in, const std::vector<TPoint2D>& path, double to_goal,
                       const Window& win) const {
    const double target_heading = in.goal->phi;
    const bool facing =
        std::abs(angleDiff(target_heading, in.pose.phi)) < mrpt::DEG2RAD(goal_tol_deg_);
    const double stopping = in.current.v * in.current.v / (2 * std::max(r_.acc_v, 1e-6));
    if (facing && stopping <= kStopped) {
      PlannerOutput out;
      out.ok = true;
      out.mark(PlanStatus::GoalReached);
      return out;
    }
    return score(in, path, to_goal, win, target_heading, Mode::AtGoal);
  }
  /** On the way: towards the look-ahead point on the route. */
  PlannerOutput approach(const PlannerInput& in, const std::vector<TPoint2D>& path, double to_goal,
                         const Window& win) const {
    const TPoint2D t = lookaheadPoint(path, in.pose.x, in.pose.y, g_.lookahead, corner_);
    const double target_heading = std::atan2(t.y - in.pose.y, t.x - in.pose.x);
    const bool turn =
        std::abs(angleDiff(target_heading, in.pose.phi)) > mrpt::DEG2RAD(g_.turn_in_place_deg);
    return score(in, path, to_goal, win, target_heading, turn ? Mode::Turn : Mode::Drive);
  }
  enum class Mode { Drive, Turn, AtGoal };
  PlannerOutput score(const PlannerInput& in, const std::vector<TPoint2D>& path, double to_goal,
                      const Window& win, double target_heading, Mode mode) const {
    PlannerOutput out;
    const bool turn_only = mode != Mode::Drive;
    const bool at_goal = mode == Mode::AtGoal;
    std::vector<Twist> samples = candidates(in, win, to_goal, turn_only);
    if (turn_only) {
      // Slow down first when still moving: v from the window's low end.
      if (samples.empty())
        for (const Twist& s : sampleWindow(win, d_))
          if (std::abs(s.v - (win.v_lo > 0 ? win.v_lo : win.v_hi)) < 1e-9) samples.push_back(s);
      out.mark(PlanStatus::TurnInPlace);
    }
    const double cap = d_.clearance_influence;
    const double now_off = routeOffset(path, in.pose);
    auto evaluate = [&](const std::vector<Twist>& candidates) {
      double best = std::numeric_limits<double>::infinity();
      for (const Twist& s : candidates) {
        // With the robot's dynamics (in.motion): the motion it will make
        // when s is sent now, and the supervisor's own stop test of it.
        std::optional<CommandMotion> motion;
        if (in.motion) motion.emplace(in.pose, *in.motion, s, r_);
        Trajectory tr = motion ? rollout(*in.map, *motion, s, d_.sim_time, d_.sim_step, cap,
                                         d_.obstacle_distance_cap)
                               : rollout(*in.map, in.pose, s, d_.sim_time, d_.sim_step, cap,
                                         d_.obstacle_distance_cap);
        ++out.evaluated;
        // Admissible: brakes before the first contact, and the supervisor
        // (same footprint, braking model and safe distance) passes it unchanged.
        // (from the robot's state: no contact before a stop sent next cycle
        // could act, then the supervisor's own stop test)
        const bool brakes = motion ? tr.time_to_collision > in.motion->latency + in.motion->period
                                   : canBrake(s, tr.time_to_collision, r_, r_.safe_distance,
                                              in.map->footprint().circumscribed);
        const MotionState* ms = in.motion ? &*in.motion : nullptr;
        if (!tr.leaves_map && brakes &&
            brakingScale(*in.map, in.pose, s, r_, d_.sim_step, r_.safe_distance, ms) >= 1.0) {
          const double ts = std::min(g_.score_time, d_.sim_time);
          // the distance to the route where it has reached the goal, if it does within ts
          const double te = arrives(in, to_goal, s, ts) ? to_goal / std::abs(s.v) : ts;
          const TPose2D e = motion ? motion->pose(te) : integrateArc(in.pose, s.v, s.w, te);
          // ... and it does not end where the robot could neither go on nor turn
          if (std::abs(s.v) > 1e-6 && !turnableAt(in, path, e, now_off)) {
            out.trajectories.push_back(tr);
            continue;
          }
          ++out.admissible;
          const double heading_err = headingError(in, path, to_goal, target_heading, s,
                                                  motion ? &*motion : nullptr, ts, at_goal);
          const double path_dist = distanceToPath(path, e.x, e.y);
          const double speed = r_.v_max > 0 ? (r_.v_max - s.v) / r_.v_max : 0;
          tr.cost = g_.k_heading * heading_err + g_.k_path * path_dist + g_.k_speed * speed +
                    g_.k_goal_obs / std::max(std::min(tr.contact_time, d_.sim_time), 1e-3) +
                    c_.k_switch * switches(s);
          if (tr.cost < best - 1e-12) {
            best = tr.cost;
            out.cmd = s;
            out.ok = true;
          }
        }
        out.trajectories.push_back(tr);
      }
    };
    evaluate(samples);
    const bool forward = out.ok && std::abs(out.cmd.v) > 1e-6;
    if (!forward && !turnableAt(in, path, in.pose, 0.0)) out.wedged = true;
    if (!out.ok && !turn_only) {
      // Nothing moves forward safely: turn on the spot towards the route.
      std::vector<Twist> turns;
      for (const Twist& s : sampleWindow(win, d_))
        if (std::abs(s.v) < 1e-9 && std::abs(s.w) > 1e-6) turns.push_back(s);
      evaluate(turns);
      if (out.ok) out.mark(PlanStatus::TurnInPlace, "turn in place (blocked ahead)");
    }
    if (!out.ok) out.mark(PlanStatus::NoAdmissible);
    if (out.wedged) out.note += out.note.empty() ? "wedged" : " (wedged)";
    return out;
  }

  /** 1 when `s` backs up after a command forward, or turns on the spot
   *  against the last turn on the spot; else 0. Driving forward again after
   *  backing up is never held back (the rear is seen least). */
  double switches(const Twist& s) const {
    const int v = sign(s.v), w = sign(s.w);
    if (v != 0) return v < 0 && v_sign_ > 0 ? 1.0 : 0.0;
    return w != 0 && w == -turn_sign_ ? 1.0 : 0.0;
  }
  /** Remembers the directions of a plan's command: of travel when it moves,
   *  of its turn when it turns on the spot (kept until a command moves on). */
  void commit(const PlannerOutput& out) {
    if (!out.ok || out.status == PlanStatus::GoalReached) return;
    const int v = sign(out.cmd.v), w = sign(out.cmd.w);
    if (v != 0) {
      v_sign_ = v;
      turn_sign_ = 0;
    } else if (w != 0) {
      turn_sign_ = w;
    }
  }
  static int sign(double x) { return x > 1e-6 ? 1 : (x < -1e-6 ? -1 : 0); }

  /** The window's samples that are worth scoring. Standing still is not a
   *  way to the goal: when nothing else is admissible the planner says so
   *  and the supervisor stops. Arriving, no faster than stops within a
   *  quarter of the tolerance of the goal at the robot's deceleration, where
   *  the window allows. */
  std::vector<Twist> candidates(const PlannerInput& in, const Window& win, double to_goal,
                                bool turn_only) const {
    const double v_arrive =
        in.goal ? std::max(win.v_lo, std::sqrt(2 * r_.acc_v * std::max(0.0, to_goal - aim() / 2)))
                : std::numeric_limits<double>::infinity();
    // Backward only to slow down from backing up, unless `reverse`.
    const double v_lo = c_.reverse ? win.v_lo : std::min(0.0, win.v_hi);
    std::vector<Twist> out;
    for (const Twist& s : sampleWindow(win, d_))
      if ((!turn_only || std::abs(s.v) < 1e-9) && (std::abs(s.v) > 1e-6 || std::abs(s.w) > 1e-6) &&
          s.v <= v_arrive + 1e-9 && s.v >= v_lo - 1e-9)
        out.push_back(s);
    return out;
  }
  /** True when `s` covers the distance to the goal (not yet within half the
   *  tolerance) within `ts`. */
  bool arrives(const PlannerInput& in, double to_goal, const Twist& s, double ts) const {
    return in.goal && to_goal >= aim() && std::abs(s.v) * ts > to_goal;
  }
  /** The heading critic of `s` (rad). Taken after `ts` (along `motion`
   *  when given), unwrapped: the turn still needed (from the start heading,
   *  within +-pi) less the turn made, which may exceed pi at a fast robot's
   *  turn rate; wrapping it would make a spin past the target look as good
   *  as stopping on it. When `s` reaches the goal within `ts`, it is the
   *  angle by which the pose where it has covered the distance to the goal
   *  misses it (seen from the start): scored beyond the goal, every fast
   *  candidate would face back at it, and the robot crept to a stop short of it.
   *  `at_goal`: the heading needed is the goal's. */
  double headingError(const PlannerInput& in, const std::vector<TPoint2D>& path, double to_goal,
                      double target_heading, const Twist& s, const CommandMotion* motion, double ts,
                      bool at_goal) const {
    auto poseAt = [&](double t) {
      return motion ? motion->pose(t) : integrateArc(in.pose, s.v, s.w, t);
    };
    if (!at_goal && arrives(in, to_goal, s, ts)) {
      const TPose2D a = poseAt(to_goal / std::abs(s.v));
      return std::atan2(std::hypot(in.goal->x - a.x, in.goal->y - a.y), to_goal);
    }
    const TPose2D e = poseAt(ts);
    const double turned = motion ? motion->turned(ts) : s.w * ts;
    double needed;
    if (at_goal)
      needed = angleDiff(target_heading, in.pose.phi);
    else {
      const TPoint2D t = lookaheadPoint(path, e.x, e.y, g_.lookahead, corner_);
      needed = angleDiff(std::atan2(t.y - e.y, t.x - e.x), in.pose.phi);
    }
    return std::abs(committed(needed) - turned);
  }
  /** rad, how far the heading of `p` is off the way the route goes on from
   *  its position (towards the look-ahead point from there). */
  double routeOffset(const std::vector<TPoint2D>& path, const TPose2D& p) const {
    const TPoint2D t = lookaheadPoint(path, p.x, p.y, g_.lookahead, corner_);
    if (std::hypot(t.x - p.x, t.y - p.y) < 1e-6) return 0;
    return angleDiff(std::atan2(t.y - p.y, t.x - p.x), p.phi);
  }
  /** False when the pose `e`, where a candidate's critics are taken, faces
   *  the route's way on by more than `align_deg` and by more than the robot
   *  faces it now (`now_off`, rad), and the footprint cannot turn on the spot
   *  there to within `align_deg` of it: a place from which the robot could
   *  neither go on nor turn (a post beside the mouth of a gap it reached
   *  skewed). Reaching it is left to the candidates that keep it turnable. */
  bool turnableAt(const PlannerInput& in, const std::vector<TPoint2D>& path, const TPose2D& e,
                  double now_off) const {
    if (g_.align_deg >= 180 ||
        (in.goal && std::hypot(in.goal->x - e.x, in.goal->y - e.y) < goal_tol_))
      return true;
    const double tol = mrpt::DEG2RAD(g_.align_deg);
    const double off = routeOffset(path, e);
    if (std::abs(off) <= std::max(tol, std::abs(now_off) + 1e-9)) return true;
    return turnFree(*in.map, e, off - std::copysign(tol, off));  // to the tolerance's edge
  }

  /** The turn `needed` (rad, within +-pi) the way the last turn on the spot
   *  went, when that way is longer by less than k_switch / k_heading: with
   *  the target near behind, the shorter side flips with every small change
   *  and the robot turned back and forth on the spot. */
  double committed(double needed) const {
    if (turn_sign_ == 0 || sign(needed) != -turn_sign_ || g_.k_heading <= 0) return needed;
    const double other = needed + turn_sign_ * 2 * M_PI;
    return std::abs(other) - std::abs(needed) < c_.k_switch / g_.k_heading ? other : needed;
  }

  DwaParams d_;
  GoalDwaParams g_;
  CommitmentParams c_;
  double goal_tol_, goal_tol_deg_;
  RobotParams r_;
  double corner_;
  int v_sign_ = 0, turn_sign_ = 0;  // the commitment: directions of the last command
};

}  // namespace

/** The point `lookahead` metres along the path after the point nearest to
 *  (x, y); the last point when the path is shorter. */
TPoint2D lookaheadPoint(const std::vector<TPoint2D>& path, double x, double y, double lookahead,
                        double corner, double reached) {
  // No segment to walk along (GoalDwa's path for a goal with an empty route
  // is the goal alone).
  if (path.size() < 2) return path.empty() ? TPoint2D{x, y} : path.front();
  const PolylinePoint near = nearestOnPolyline(path, x, y);
  const size_t seg = near.segment;
  const double best_u = near.u;
  double left = lookahead;
  TPoint2D p{path[seg].x + best_u * (path[seg + 1].x - path[seg].x),
             path[seg].y + best_u * (path[seg + 1].y - path[seg].y)};
  for (size_t i = seg + 1; i < path.size(); ++i) {
    const double d = std::hypot(path[i].x - p.x, path[i].y - p.y);
    if (d >= left) {
      return {p.x + (path[i].x - p.x) * left / d, p.y + (path[i].y - p.y) * left / d};
    }
    left -= d;
    p = path[i];
    // A vertex is reached within `reached` of it, or once the robot is
    // abeam of it (less than `reached` before it along the path): a robot
    // passing it a little aside must not turn back to it.
    if (corner < M_PI && i + 1 < path.size() && lookahead - left > reached &&
        std::hypot(path[i].x - x, path[i].y - y) > reached) {
      const double a0 = std::atan2(path[i].y - path[i - 1].y, path[i].x - path[i - 1].x);
      const double a1 = std::atan2(path[i + 1].y - path[i].y, path[i + 1].x - path[i].x);
      if (std::abs(angleDiff(a1, a0)) > corner) return path[i];
    }
  }
  return path.back();
}

std::unique_ptr<LocalPlanner> makeGoalDwa(const NavigationParams& p, const RobotParams& r) {
  return std::make_unique<GoalDwa>(p, p, p, p.goal_tolerance, p.goal_tolerance_deg, r);
}

}  // namespace carenav::navigation
