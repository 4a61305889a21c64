#include <carenav/navigation/navigator.h>
#include <carenav/navigation/polyline.h>

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservationRange.h>
#include <mrpt/poses/CPoint2D.h>
#include <mrpt/poses/CPose2D.h>

#include <algorithm>
#include <cmath>

namespace carenav::navigation {

using mrpt::poses::CPose2D;

Navigator::Navigator(const NavigationParams& p, const RobotParams& robot)
    : p_(p),
      robot_(robot),
      planner_(PlannerRegistry::instance().create(p.plugin, p, robot)),
      supervisor_(p, robot),
      footprint_(robot.footprint, p.resolution),
      map_(p, footprint_),
      memory_(p.resolution, p.obstacle_persistence, p.memory_radius),
      free_history_(p.resolution, p.track_radius),
      tracker_([&] {
        MovingTrackerParams t;
        t.gate = p.track_gate;
        t.min_cells = p.track_min_cells;
        t.cell = p.resolution;
        return t;
      }()),
      recovery_(RecoveryParams{}, robot, p) {}

void Navigator::setRecoveryParams(const RecoveryParams& rp, const ManeuverParams& mp) {
  recovery_ = Recovery(rp, robot_, p_, mp);
}

void Navigator::setOdometry(const TPose2D& pose, const Twist& measured, double t) {
  odom_ = pose;
  measured_ = measured;
  odom_t_ = t;
}

void Navigator::setMapPose(const TPose2D& m) {
  // odom = T (+) map for points: T = odom (+) inverse(map pose).
  const CPose2D t = CPose2D(odom_) + (CPose2D() - CPose2D(m));
  map_to_odom_ = {t.x(), t.y(), t.phi()};
}

TPose2D Navigator::mapPose() const {
  const CPose2D m = (CPose2D() - CPose2D(map_to_odom_)) + CPose2D(odom_);
  return {m.x(), m.y(), m.phi()};
}

std::vector<TPoint2D> Navigator::obstaclesInMap() const {
  const CPose2D inv = CPose2D() - CPose2D(map_to_odom_);
  std::vector<TPoint2D> out;
  std::vector<TPoint2D> all = memory_.points();
  all.insert(all.end(), perceived_.begin(), perceived_.end());
  // Moving obstacles, grown as on the local cost map, and the lanes the
  // tracked ones walk in over route_predict_horizon (a route along a
  // person's lane is blocked and goes aside early).
  const double grow = p_.predict_speed * p_.predict_time;
  const int n = static_cast<int>(std::ceil(grow / p_.resolution));
  for (const auto& m : moving_)
    for (int dy = -n; dy <= n; ++dy)
      for (int dx = -n; dx <= n; ++dx)
        if (std::hypot(dx, dy) * p_.resolution <= grow)
          all.push_back({m.x + dx * p_.resolution, m.y + dy * p_.resolution});
  if (p_.predict_horizon > 0 && p_.route_predict_horizon > 0) {
    const auto lanes = tracker_.predictedPath(p_.route_predict_horizon, p_.resolution, grow);
    all.insert(all.end(), lanes.begin(), lanes.end());
  }
  for (const auto& p : all) {
    const auto q = inv + mrpt::poses::CPoint2D(p.x, p.y);
    out.push_back({q.x(), q.y()});
  }
  return out;
}

TPoint2D Navigator::mapToOdom(const TPoint2D& p) const {
  const double c = std::cos(map_to_odom_.phi), s = std::sin(map_to_odom_.phi);
  return {map_to_odom_.x + c * p.x - s * p.y, map_to_odom_.y + s * p.x + c * p.y};
}

TPose2D Navigator::mapToOdom(const TPose2D& p) const {
  const TPoint2D q = mapToOdom(TPoint2D{p.x, p.y});
  return {q.x, q.y,
          std::atan2(std::sin(p.phi + map_to_odom_.phi), std::cos(p.phi + map_to_odom_.phi))};
}

void Navigator::setUserIntent(const Twist& u, double t) {
  user_ = u;
  intent_t_ = t;
}

bool Navigator::addObservation(const mrpt::obs::CObservation& obs, const TPose2D& at, double t) {
  const CPose2D robot(at);
  if (const auto* scan = dynamic_cast<const mrpt::obs::CObservation2DRangeScan*>(&obs)) {
    const CPose2D sensor = robot + CPose2D(scan->sensorPose);
    WorldScan ws;
    ws.origin = {sensor.x(), sensor.y()};
    ws.robot = TPoint2D{at.x, at.y};
    const size_t n = scan->getScanSize();
    const double max_range = scan->maxRange;
    for (size_t i = 0; i < n; ++i) {
      if (!scan->getScanRangeValidity(i)) continue;  // no return: neither hit nor clear
      const double r = scan->getScanRange(i);
      const double a = scan->getScanAngle(i);
      const CPose2D end = sensor + CPose2D(r * std::cos(a), r * std::sin(a), 0);
      ws.ends.push_back({end.x(), end.y()});
      ws.hit.push_back(r < max_range - 1e-3 ? 1 : 0);
    }
    memory_.add(ws, t);
    recovery_.addSeen(ws, t);
    if (p_.predict_speed * p_.predict_time > 0) {
      free_history_.addScan(ws, t);
      for (size_t i = 0; i < ws.ends.size(); ++i)
        if (ws.hit[i]) fresh_hits_.push_back(ws.ends[i]);
    }
    scan_t_ = t;
    return true;
  }
  if (const auto* ra = dynamic_cast<const mrpt::obs::CObservationRange*>(&obs)) {
    // A range array (Leddar): each segment is a cone; its return may come
    // from anywhere across the cone, so the hit is spread over the arc.
    for (const auto& m : ra->sensedData) {
      const CPose2D sensor = robot + CPose2D(mrpt::poses::CPose3D(m.sensorPose));
      WorldScan ws;
      ws.origin = {sensor.x(), sensor.y()};
      ws.robot = TPoint2D{at.x, at.y};
      const double r = m.sensedDistance;
      if (!(r > 0) || !std::isfinite(r)) continue;
      const bool hit = r < ra->maxSensorDistance - 1e-3;
      const double ap = ra->sensorConeApperture;
      const int n = std::max(1, static_cast<int>(std::ceil(r * ap / p_.resolution)));
      for (int k = 0; k <= n; ++k) {
        const double a = -ap / 2 + ap * k / n;
        const CPose2D end = sensor + CPose2D(r * std::cos(a), r * std::sin(a), 0);
        ws.ends.push_back({end.x(), end.y()});
        ws.hit.push_back(hit ? 1 : 0);
      }
      // A range array's cone does not say where across it the return is:
      // its hits never count as moving (no free-space history from them).
      memory_.add(ws, t);
    }
    scan_t_ = t;
    return true;
  }
  return false;
}

void Navigator::addObstaclePoints(const std::vector<TPoint2D>& points, double t) {
  memory_.addPoints(points, t);
  scan_t_ = t;
}

void Navigator::setPerceivedObstacles(std::vector<TPoint2D> points, double t) {
  perceived_ = std::move(points);
  scan_t_ = t;
}

void Navigator::addPerceivedFrame(const std::vector<TPoint2D>& free_cells,
                                  const std::vector<TPoint2D>& hit_cells, double t) {
  if (!(p_.predict_speed * p_.predict_time > 0)) return;
  for (const auto& c : free_cells) free_history_.markFree(c.x, c.y, t);
  for (const auto& c : hit_cells) free_history_.markHit(c.x, c.y, t);
  for (const auto& c : hit_cells)
    if (std::hypot(c.x - odom_.x, c.y - odom_.y) <= p_.track_depth_range)
      fresh_depth_hits_.push_back(c);
}

void Navigator::setRoute(const std::vector<TPoint2D>& waypoints, const TPose2D& goal) {
  const bool same_heading =
      goal_ && (goal_->phi == goal.phi || (std::isnan(goal_->phi) && std::isnan(goal.phi)));
  const bool new_goal = !goal_ || goal_->x != goal.x || goal_->y != goal.y || !same_heading;
  route_ = waypoints;
  goal_ = goal;
  if (new_goal)
    recovery_.newGoal(odom_t_.value_or(0.0));
  else
    recovery_.routeChanged(odom_t_.value_or(0.0));
}

namespace {

/** Length of the route still to go from (x, y): to its nearest point, then along it. */
double routeLeft(const std::vector<TPoint2D>& path, double x, double y) {
  if (path.empty()) return 0;
  if (path.size() == 1) return std::hypot(path[0].x - x, path[0].y - y);
  const PolylinePoint near = nearestOnPolyline(path, x, y);
  const size_t seg = near.segment;
  double left = near.distance + (1 - near.u) * std::hypot(path[seg + 1].x - path[seg].x,
                                                          path[seg + 1].y - path[seg].y);
  for (size_t i = seg + 1; i + 1 < path.size(); ++i)
    left += std::hypot(path[i + 1].x - path[i].x, path[i + 1].y - path[i].y);
  return left;
}

}  // namespace

void Navigator::clearRoute() {
  route_.clear();
  goal_.reset();
}

PlannerOutput Navigator::turnInPlace(const PlannerInput& in) const {
  // Both turning directions at half the turn rate; the one whose swept
  // footprint stays clear for a quarter turn (the wider clearance when both
  // do) wins. Still turning: keep the direction (no dithering).
  PlannerOutput out;
  const double w = 0.5 * robot_.w_max;
  const double quarter = (M_PI / 2) / w;
  double best = -1;
  for (const double sgn : {1.0, -1.0}) {
    const Twist cmd{0, sgn * w};
    const Trajectory tr =
        rollout(*in.map, in.pose, cmd, quarter, p_.sim_step, p_.clearance_influence);
    ++out.evaluated;
    if (!tr.admissible()) continue;
    ++out.admissible;
    const bool same = in.current.w * sgn > 0.05;
    const double score = tr.clearance + (same ? 1.0 : 0.0);
    if (score > best) {
      best = score;
      out.cmd = cmd;
      out.ok = true;
    }
  }
  out.note = out.ok ? "turn in place to relocalise" : "cannot turn in place to relocalise";
  return out;
}

std::optional<double> Navigator::intentDeviation(const Twist& user, const Twist& cmd) const {
  const Twist uc{std::clamp(user.v, robot_.v_min, robot_.v_max),
                 std::clamp(user.w, -robot_.w_max, robot_.w_max)};
  if (std::abs(uc.v) < p_.intent_deadband) return std::nullopt;
  const Trajectory ut =
      rollout(map_, cycle_pose_, uc, p_.sim_time, p_.sim_step, p_.clearance_influence);
  if (!ut.admissible()) return std::nullopt;
  return std::hypot(cmd.v - uc.v, cmd.w - uc.w);
}

TPose2D Navigator::poseAt(double now) const {
  if (!odom_t_) return odom_;
  const double age = std::clamp(now - *odom_t_, 0.0, p_.odom_timeout);
  return integrateArc(odom_, measured_.v, measured_.w, age);
}

MotionState Navigator::motionState() const {
  MotionState m;
  m.current = measured_;
  m.commanded = last_cmd_;
  m.latency = robot_.command_latency;
  // The control period as measured between cycles (the rollout step until
  // two cycles have run).
  m.period = period_ > 0 ? period_ : p_.sim_step;
  return m;
}

Navigator::Cycle Navigator::cycle(double now) {
  Cycle c;
  if (last_cycle_ && now > *last_cycle_ && now - *last_cycle_ < 1.0) period_ = now - *last_cycle_;
  last_cycle_ = now;
  // Every command is judged from the robot's dynamics, whatever its planner
  // assumes: the pose at the cycle's time, the velocity it still has.
  const TPose2D pose = poseAt(now);
  cycle_pose_ = pose;
  memory_.prune(now, {pose.x, pose.y});
  // The perception grid's cells stand alone in theirs: joined to the
  // lidar's segment of the cell they became a box, grown by the noise.
  map_.build({pose.x, pose.y}, memory_.points(), perceived_);
  // Moving obstacles (people): obstacle cells that were free just before,
  // grown by how far a person walks in predict_time.
  moving_.clear();
  const double grow = p_.predict_speed * p_.predict_time;
  if (grow > 0) {
    // Hit cells are kept for dynamic_window: movedIn() asks whether a
    // neighbour was hit that recently (a post's cell that no ray passed is
    // never seen free and was dropped at once).
    free_history_.prune(now, p_.dynamic_window + 1.0,
                        std::max(p_.static_memory, p_.dynamic_window));
    // Only what locates its obstacles precisely and is current: the lidar
    // hits and the depth frames' obstacle cells since the last cycle (not
    // the perception grid's fused cells, whose edges grow as a static box
    // is approached).
    for (const auto& o : fresh_hits_)
      if (free_history_.movedIn(o.x, o.y, now, p_.dynamic_window, p_.dynamic_min_free,
                                p_.static_memory))
        moving_.push_back(o);
    fresh_hits_.clear();
    // A depth camera's cells are noisier: only bodies of cells moving in together.
    std::vector<TPoint2D> depth_moving;
    for (const auto& o : fresh_depth_hits_)
      if (free_history_.movedIn(o.x, o.y, now, p_.dynamic_window, p_.dynamic_min_free,
                                p_.static_memory))
        depth_moving.push_back(o);
    fresh_depth_hits_.clear();
    for (const auto& c : clusterPoints(depth_moving, 1.5 * p_.resolution))
      if (c.size() >= static_cast<size_t>(p_.track_depth_min_cells))
        for (size_t i : c) moving_.push_back(depth_moving[i]);
    // Only bodies are moving obstacles (MovingTrackerParams::min_cells);
    // tracked, they also block where they are going.
    tracker_.update(moving_, now);
    moving_ = tracker_.bodies();
    predicted_.clear();
    if (p_.predict_horizon > 0)
      predicted_ = tracker_.predictedPath(p_.predict_horizon, p_.resolution);
    std::vector<TPoint2D> all = moving_;
    all.insert(all.end(), predicted_.begin(), predicted_.end());
    // People who walked out of sight nearby may step back in.
    if (p_.predict_horizon > 0) {
      const auto hidden = tracker_.hiddenRegions(now, p_.resolution);
      all.insert(all.end(), hidden.begin(), hidden.end());
    }
    map_.addMoving(all, grow);
  }
  c.obstacles = memory_.size();
  c.clearance = map_.check(pose, 2.0).clearance;

  PlannerInput in;
  in.t = now;
  in.pose = pose;
  in.current = measured_;
  if (planner_->usesMotionState()) in.motion = motionState();
  in.map = &map_;
  if (planner_->needsUserIntent()) in.user = user_;
  if (goal_) {
    for (const auto& w : route_) in.path.push_back(mapToOdom(w));
    in.goal = mapToOdom(*goal_);
    if (std::isnan(goal_->phi)) in.goal->phi = pose.phi;  // kAnyHeading: as it stands
  }
  if (rotate_request_ && !planner_->needsUserIntent()) {
    c.plan = turnInPlace(in);
  } else {
    c.plan = planner_->plan(in);
    c.goal_reached = goal_ && c.plan.ok && c.plan.status == PlanStatus::GoalReached;
    // Recovery behaviours (goal robots): boxed in or no progress.
    if (goal_ && !planner_->needsUserIntent()) {
      recovery_.recordPose(pose);
      const bool blocked = !c.plan.ok || c.plan.wedged || blocked_;
      if (auto r = recovery_.step(now, in, c.plan, blocked, routeLeft(in.path, pose.x, pose.y))) {
        c.plan = *r;
        c.recovery = Recovery::phaseName(recovery_.phase());
        c.gave_up = recovery_.gaveUp();
      }
      c.replan = recovery_.takeReplanRequest();
      if (c.replan) {
        const TPose2D& a = recovery_.startedAt();
        const auto q = (CPose2D() - CPose2D(map_to_odom_)) + mrpt::poses::CPoint2D(a.x, a.y);
        c.stuck_at = TPoint2D{q.x(), q.y()};
      }
    }
  }

  SafetyInput s;
  s.now = now;
  s.last_scan_time = scan_t_;
  s.last_odom_time = odom_t_;
  s.needs_intent = planner_->needsUserIntent();
  s.last_intent_time = intent_t_;
  s.user = user_;
  s.plan = c.plan;
  s.pose = pose;
  s.map = &map_;
  // The supervisor judges every command from the robot's state even when
  // its planner does not: mrpt-ptg and the walker's user-intent-dwa plan
  // commands as taken at once, and at 2 m/s both turned into posts they
  // could no longer avoid.
  s.motion = motionState();
  c.decision = supervisor_.apply(s);
  last_cmd_ = c.decision.cmd;
  // Held: stopped, or slowed to a crawl (the planner and the supervisor
  // share the braking rule, so this is rare: a recovery's business).
  blocked_ = c.decision.action == SafetyAction::Stop ||
             (std::abs(c.decision.cmd.v) < 0.01 && std::abs(c.decision.cmd.w) < 0.01);
  return c;
}

}  // namespace carenav::navigation
