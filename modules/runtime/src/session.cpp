// The navigation session: goals, routes and the control cycle (session.h).
#include <carenav/common/errors.h>
#include <carenav/localization/localizer.h>
#include <carenav/navigation/mrpt_ptg.h>
#include <carenav/perception/pipeline.h>
#include <carenav/runtime/session.h>

#include <unistd.h>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

namespace carenav::navigation {

SessionSetup sessionSetup(const std::string& profile_path, const std::vector<std::string>& sets,
                          const std::string& plugin) {
  SessionSetup s;
  s.profile = Profile::load(profile_path);
  s.profile.applyOverrides(sets);
  s.profile.validate();
  configureMrptPtg(s.profile);  // [nav.mrpt_ptg] for the mrpt-ptg plugin
  s.robot = s.profile.section<RobotParams>("robot");
  s.sensors = loadSensors(s.profile);
  s.nav = NavigationParams::fromProfile(s.profile);  // [navigation] and [nav.*]
  if (!plugin.empty()) s.nav.plugin = plugin;
  return s;
}

namespace {

/** Unknown floor ahead from the profile: the reaction time is the command
 *  latency ([robot] command_latency: the time between a command and its
 *  effect, the same the planners' rollouts use), one control cycle and one frame of the
 *  camera; the margin the robot's safe_distance; "seen free" the perception
 *  grid's free threshold. */
std::unique_ptr<UnknownAhead> makeUnknownAhead(const SessionSetup& s,
                                               const perception::PerceptionParams& percp,
                                               const SensorParams& camera) {
  UnknownAheadParams p;
  p.command_latency = s.robot.command_latency;
  p.control_period = s.control_rate > 0 ? 1.0 / s.control_rate : 0.1;
  p.frame_period = camera.rate_hz > 0 ? 1.0 / camera.rate_hz : 0.1;
  p.margin = s.robot.safe_distance;
  p.seen_free_below = percp.free_threshold;
  return std::make_unique<UnknownAhead>(s.robot, p, percp.resolution);
}

}  // namespace

NavigationSession::NavigationSession(SessionSetup setup)
    : s_(std::move(setup)),
      nav_(s_.nav, s_.robot),
      fp_(s_.robot.footprint, s_.nav.resolution),
      replanner_(s_.control_rate) {
  const auto locp = s_.profile.section<localization::LocalizationParams>("localization");
  auto percp = s_.profile.section<perception::PerceptionParams>("perception");
  // A robot navigates with its calibrated mounting: a floor in view below
  // its own is a drop from the first frame on (it may start at a stair edge).
  percp.mounting_calibrated = true;
  const auto recp = s_.profile.section<RecoveryParams>("nav.recovery");
  nav_.setRecoveryParams(recp, s_.profile.section<ManeuverParams>("nav.maneuver"));
  replanner_ = RouteReplanner(s_.control_rate, recp.avoid_after, recp.avoid_radius);
  walker_ = nav_.planner().needsUserIntent();
  for (const auto& sp : s_.sensors)
    if (sp.type == "lidar2d" && loc_sensor_.empty()) loc_sensor_ = sp.label;
  for (const auto& sp : s_.sensors)
    if (sp.type == "depth-camera") {
      perceive_ = std::make_unique<perception::Pipeline>(percp, perception::Method::RrtGpd);
      perception_sensor_ = percp.sensor;
      unknown_ = makeUnknownAhead(s_, percp, sp);
      break;
    }
  if (s_.localise && s_.map && s_.start && !loc_sensor_.empty()) {
    loc_ = std::make_unique<localization::Localizer>(*s_.map, locp);
    loc_->initPose(mrpt::poses::CPose2D(s_.start->x, s_.start->y, s_.start->phi), 0.1, 0.1,
                   mrpt::DEG2RAD(3.0));
  }
  m_.scenario = s_.name;
  m_.plugin = s_.nav.plugin;
  m_.min_clearance_m = std::numeric_limits<double>::infinity();
  if (s_.start) path_.push_back({s_.start->x, s_.start->y});
  if (s_.start) user_path_.push_back({s_.start->x, s_.start->y});
  wall0_ = std::chrono::steady_clock::now();
  tty_ = s_.progress && isatty(fileno(stderr));
}

NavigationSession::~NavigationSession() = default;

bool NavigationSession::setGoals(std::vector<SessionGoal> goals, bool patrol, double leg_timeout,
                                 const TPoint2D& from) {
  if (goals.empty()) return false;
  goals_ = std::move(goals);
  patrol_ = patrol && goals_.size() > 1;
  leg_timeout_ = leg_timeout;
  goal_ = goals_.front().pose;
  m_.goal_name = goals_.front().label;
  replanner_.newGoal();
  if (!s_.map) return false;
  gp_ = std::make_unique<GlobalPlanner>(*s_.map, fp_.inscribed, s_.nav);
  // A robot that drives its route itself gets one its footprint can drive;
  // a walker's user steers (the route only guides the scripted user).
  if (!walker_) gp_->setFootprint(fp_.polygon);
  route_origin_ = from;
  planRoute(from);
  return route_.has_value();
}

std::vector<TPoint2D> NavigationSession::routePoints() const {
  std::vector<TPoint2D> out{route_start_};
  if (route_) out.insert(out.end(), route_->waypoints.begin(), route_->waypoints.end());
  return out;
}

// The route from `from` to the goal (with plan_clearance to spare, or
// through the widest passage there is: GlobalPlanner).
void NavigationSession::planRoute(const TPoint2D& from) {
  try {
    route_ = gp_->plan(from, {goal_->x, goal_->y});
  } catch (const InputError& e) {  // a start or goal off the map: the run's input
    throw InputError(s_.origin + ": " + e.what());
  }
  route_start_ = from;
  if (route_)
    nav_.setRoute(routePoints(), *goal_);
  else
    nav_.clearRoute();
}

// A patrol's leg ends (reported reached: checked against where the robot
// truly is, or its estimate without a truth) and the next goal is taken.
void NavigationSession::nextLeg(bool reported, const TPoint2D& where, double now) {
  if (reported) {
    const double err = std::hypot(where.x - goal_->x, where.y - goal_->y);
    if (err > s_.nav.goal_tolerance) {
      ++m_.legs_missed;  // the robot's localisation put it there; the truth did not
      m_.leg_miss_max_m = std::max(m_.leg_miss_max_m, err);
    } else {
      ++m_.legs_completed;
    }
  } else {
    ++m_.legs_failed;
  }
  leg_ = (leg_ + 1) % goals_.size();
  goal_ = goals_[leg_].pose;
  leg_t0_ = now;
  replanner_.newGoal();
  const TPose2D mp = nav_.mapPose();
  if (gp_) planRoute({mp.x, mp.y});  // none: the replanner keeps trying; the leg times out
}

bool NavigationSession::walkerArrived(const TPose2D& truth, double t) {
  const bool there = std::hypot(truth.x - goal_->x, truth.y - goal_->y) < s_.nav.goal_tolerance;
  if (patrol_ && (there || t - leg_t0_ > leg_timeout_)) {
    nextLeg(there, {truth.x, truth.y}, t);
    return false;
  }
  if (there) endRun(SessionEnd::GoalReached, t);
  return there;
}

void NavigationSession::endRun(SessionEnd why, double t) {
  end_ = why;
  end_t_ = t;
}

NavigationSession::Step NavigationSession::cycle(double t, const std::optional<Truth>& truth) {
  const auto c0 = std::chrono::steady_clock::now();
  Step st{nav_.cycle(t)};
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - c0).count();
  work_ms_ = threadCpuMs() - work0_;
  record(t, st.cycle, truth, ms);
  const size_t k = k_++;
  user_.reset();
  if (const auto end = goalCheck(t, st.cycle, truth)) {
    st.end = *end;
    return st;
  }
  const double replan0 = threadCpuMs();
  replan(k, st.cycle.replan, st.cycle.stuck_at);
  work_ms_ += threadCpuMs() - replan0;
  sampleHealth(k);
  return st;
}

// The cycle's ends: a goal reached (a patrol takes the next leg instead, as
// it does when the robot gave up or the leg timed out), the first
// collision, the recoveries given up.
std::optional<SessionEnd> NavigationSession::goalCheck(double t, const Navigator::Cycle& c,
                                                       const std::optional<Truth>& truth) {
  if (patrol_ && !walker_ && (c.goal_reached || c.gave_up || t - leg_t0_ > leg_timeout_)) {
    const TPose2D where = truth ? truth->pose : nav_.mapPose();
    nextLeg(c.goal_reached, {where.x, where.y}, t);
  } else if (goal_ && c.goal_reached) {
    endRun(SessionEnd::GoalReached, t);
    return end_;
  }
  if (truth && truth->collisions > 0 && !s_.continue_after_collision) {
    endRun(SessionEnd::Collision, t);
    return end_;
  }
  if (c.gave_up && !patrol_) {
    gave_up_note_ = c.plan.note;
    endRun(SessionEnd::GaveUp, t);
    return end_;
  }
  return std::nullopt;
}

// Replan from the localised pose with the obstacles the robot has seen
// marked on the map (boxes and people the map does not show; when that
// finds no route, the last one stays), and around the places where
// recoveries keep beginning. A walker's scripted user walks the
// new route too: a user sees boxes and people.
void NavigationSession::replan(size_t k, bool recovery_ended,
                               const std::optional<TPoint2D>& stuck_at) {
  if (!goal_ || !gp_) return;
  if (stuck_at && replanner_.recovered(*stuck_at)) ++m_.avoided_places;
  const bool people = !nav_.predicted().empty();
  if (!recovery_ended && !replanner_.due(k, people)) return;
  const TPose2D mp = nav_.mapPose();
  if (auto r2 =
          replanner_.step(people, *s_.map, nav_.obstaclesInMap(), {mp.x, mp.y},
                          {goal_->x, goal_->y}, route_, fp_.inscribed, fp_.circumscribed + 0.2,
                          s_.nav, walker_ ? std::vector<Point2>{} : fp_.polygon)) {
    route_ = r2;
    route_start_ = {mp.x, mp.y};
    nav_.setRoute(routePoints(), *goal_);
  }
}

}  // namespace carenav::navigation
