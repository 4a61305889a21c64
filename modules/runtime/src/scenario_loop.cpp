// The closed loop of a scenario run (scenario_judge.h): the simulator, the
// scenario's user and the navigation session.
#include "scenario_judge.h"

#include <carenav/common/text.h>
#include <carenav/navigation/local_planner.h>

#include <chrono>
#include <cmath>
#include <thread>

namespace carenav::navigation {

namespace {

/** The walker's user in a scenario: a live intent source, the scenario's
 *  timed script, or (a walker with a goal) a user who knows the way and
 *  walks the route. */
class ScenarioUser {
 public:
  ScenarioUser(const Scenario& sc, const RunOptions& o, NavigationSession& s,
               const RobotParams& robot)
      : sc_(sc), o_(o), s_(s), robot_(robot), pose_(sc.start) {}

  /** The user's command at t (truth: where the walker is); false ends the
   *  run (a guided walker arrived; a live source ended and the walker stands). */
  bool step(double t, double dt, const sim::Pose2& truth, const sim::Simulator& sim) {
    if (!s_.walker()) return true;
    if (s_.goalMode()) return walkRoute(t, truth);
    if (o_.intent) return live(t, dt, sim);
    if (const auto u = sc_.userAt(t, truth.yaw)) {
      s_.userIntent({u->first, u->second}, t, t);
      // The user's intended path: their commands on a free floor.
      const auto ui = sc_.userAt(t, pose_.phi);
      pose_ =
          integrateArc(pose_, ui->first, std::clamp(ui->second, -robot_.w_max, robot_.w_max), dt);
      s_.userPathPoint({pose_.x, pose_.y});
    }
    return true;
  }
  bool sourceOver() const { return over_; }

 private:
  // Steering at heading_gain towards the point `lookahead` ahead on the
  // route, at user_speed; a person turns on the spot before walking off in
  // a new direction.
  bool walkRoute(double t, const sim::Pose2& truth) {
    if (s_.walkerArrived({truth.x, truth.y, truth.yaw}, t)) return false;
    if (!s_.hasRoute()) return true;
    const TPoint2D la =
        lookaheadPoint(s_.routePoints(), truth.x, truth.y, s_.setup().nav.lookahead);
    const double err =
        std::remainder(std::atan2(la.y - truth.y, la.x - truth.x) - truth.yaw, 2 * M_PI);
    const double v = std::abs(err) > M_PI / 3 ? 0.0 : sc_.user_speed;
    s_.userIntent({v, std::clamp(sc_.heading_gain * err, -robot_.w_max, robot_.w_max)}, t, t);
    s_.userPathPoint({truth.x, truth.y});
    return true;
  }
  bool live(double t, double dt, const sim::Simulator& sim) {
    if (const auto smp = o_.intent->poll(t)) {
      s_.userIntent(smp->cmd, smp->t, t);
      if (t - smp->t <= s_.setup().nav.intent_timeout) {
        pose_ = integrateArc(pose_, smp->cmd.v, std::clamp(smp->cmd.w, -robot_.w_max, robot_.w_max),
                             dt);
        s_.userPathPoint({pose_.x, pose_.y});
      }
    }
    // The source has ended (script over, q pressed): stop once the walker stands.
    if (!o_.intent->finished(t)) return true;
    if (over_ && std::abs(sim.v()) < 1e-3 && std::abs(sim.w()) < 1e-3) return false;
    over_ = true;
    return true;
  }

  const Scenario& sc_;
  const RunOptions& o_;
  NavigationSession& s_;
  const RobotParams& robot_;
  TPose2D pose_;  // where the user's commands alone would take a free walker
  bool over_ = false;
};

/** Live pace: simulated time runs `speed` times the wall clock. */
void pace(double sim_t, double speed, std::chrono::steady_clock::time_point wall0) {
  if (speed <= 0) return;
  std::this_thread::sleep_until(wall0 +
                                std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                    std::chrono::duration<double>(sim_t / speed)));
}

}  // namespace

RunMetrics runSimulated(const Scenario& sc, const RunOptions& o, const sim::World& world,
                        sim::Simulator& sim, NavigationSession& session, double duration) {
  const TruthClearance truth_clear(
      world, session.setup().robot,
      session.setup().profile.section<sim::SimParams>("sim").bumper_step);
  ScenarioUser user(sc, o, session, session.setup().robot);
  const double dt = 1.0 / o.control_rate;
  const size_t steps = std::isfinite(duration)
                           ? static_cast<size_t>(std::ceil(duration / dt - 1e-9))
                           : std::numeric_limits<size_t>::max();
  std::optional<InputError> input_error;  // a live source's bad message: outputs first
  std::optional<double> user_end;
  bool reached = false;
  const auto wall0 = std::chrono::steady_clock::now();
  for (size_t k = 0; k < steps; ++k) {
    if (o.stop && o.stop->load()) break;
    pace(sim.time(), o.speed, wall0);
    const auto frames = sim.step(dt);  // sensors and odometry of the last period
    session.beginWork();
    for (const auto& f : frames) {
      const TPose2D odo{f.odometry.x, f.odometry.y, f.odometry.yaw};
      session.odometry(odo, {sim.v(), sim.w()}, f.t);
      for (const auto& obs : f.observations) session.observation(obs, odo, f.t);
    }
    const double t = sim.time();
    try {
      if (!user.step(t, dt, sim.groundTruth(), sim)) {
        user_end = t;
        break;
      }
    } catch (const InputError& e) {
      input_error = e;
      sim.setCommand(0, 0);
      break;
    }
    const auto st = session.cycle(t, simulatorTruth(sim, world, truth_clear, sc, t));
    sim.setCommand(st.cycle.decision.cmd.v, st.cycle.decision.cmd.w);
    const sim::Pose2 p = sim.groundTruth();
    if (sc.reach &&
        std::hypot(p.x - sc.reach->first.x, p.y - sc.reach->first.y) <= sc.reach->second)
      reached = true;
    if (st.end != SessionEnd::None) break;
  }
  session.finishMetrics();
  RunMetrics& m = session.metrics();
  const bool patrol = !sc.patrol.empty() && session.goalMode();
  m.collisions = sim.collisions();
  const bool ended = session.ended() != SessionEnd::None || user_end;
  m.duration_s = !patrol && ended ? (user_end ? *user_end : session.endTime()) : sim.time();
  m.path_length_m = sim.distance();
  m.mean_speed_mps = m.duration_s > 0 ? m.path_length_m / m.duration_s : 0;
  const sim::Pose2 end = sim.groundTruth();
  if (session.goalMode())
    m.final_goal_error_m = std::hypot(end.x - session.goal()->x, end.y - session.goal()->y);
  ScenarioEnd e;
  e.goal_mode = session.goalMode();
  e.patrol = patrol;
  e.goal_reached = session.ended() == SessionEnd::GoalReached;
  e.has_route = session.hasRoute();
  e.reached = reached;
  e.live_user = o.intent != nullptr;
  e.gave_up = session.gaveUpNote();
  e.duration = duration;
  e.goal_tolerance = session.setup().nav.goal_tolerance;
  judgeScenario(sc, e, m);
  std::vector<io::Overlay> forbidden;
  for (const auto& poly : sc.forbidden) {
    io::Overlay f;
    f.points = poly;
    f.points.push_back(poly.front());
    f.colour = {200, 0, 200};
    forbidden.push_back(f);
  }
  session.writeOutputs("carenav navigate " + sc.name, std::move(forbidden));
  if (input_error) m.failWith(*input_error);
  return m;
}

}  // namespace carenav::navigation
