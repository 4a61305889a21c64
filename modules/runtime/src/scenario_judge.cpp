// Judging a scenario run from the simulator's truth (scenario_judge.h).
#include "scenario_judge.h"

#include <carenav/common/distance_transform.h>
#include <carenav/common/text.h>
#include <carenav/places/places.h>
#include <carenav/sim/raycast.h>

#include <cmath>
#include <limits>

namespace carenav::navigation {

TruthClearance::TruthClearance(const sim::World& w, const RobotParams& robot, double step)
    : w_(w), fp_(robot.footprint, w.resolution()) {
  for (const auto& q : fp_.polygon) outline_.push_back({q.x, q.y});
  const int nx = w.sizeX(), ny = w.sizeY();
  std::vector<uint8_t> free(static_cast<size_t>(nx) * ny, 1);
  for (int y = 0; y < ny; ++y)
    for (int x = 0; x < nx; ++x) {
      const sim::Cell& c = w.cell(x, y);
      const bool blocked =
          c.wall() || std::abs(c.floor) > step || (c.hasSlab() && c.slab_lo < robot.height);
      if (blocked) free[static_cast<size_t>(y) * nx + x] = 0;
    }
  const auto d2 = squaredDistanceTransform<float>(free, nx, ny);
  dist_.resize(d2.size());
  for (size_t i = 0; i < d2.size(); ++i)
    dist_[i] = std::isinf(d2[i]) ? 1e3f : static_cast<float>(std::sqrt(d2[i]) * w.resolution());
}

double TruthClearance::at(const sim::Pose2& p, const std::vector<sim::PersonNow>& people) const {
  const double c = std::cos(p.yaw), s = std::sin(p.yaw);
  double best = std::numeric_limits<double>::infinity();
  for (const auto& b : fp_.boundary) {
    const double x = p.x + c * b.x - s * b.y, y = p.y + s * b.x + c * b.y;
    const int cx = w_.cellX(x), cy = w_.cellY(y);
    double d = 0;
    if (w_.inside(cx, cy)) d = dist_[static_cast<size_t>(cy) * w_.sizeX() + cx];
    for (const auto& q : people) d = std::min(d, std::hypot(x - q.x, y - q.y) - q.r);
    best = std::min(best, d);
  }
  return std::max(0.0, best - w_.resolution() / 2);
}

bool TruthClearance::enters(const sim::Pose2& p, const std::vector<TPoint2D>& poly) const {
  const double c = std::cos(p.yaw), s = std::sin(p.yaw);
  if (places::pointInPolygon(poly, p.x, p.y)) return true;
  for (const auto& b : fp_.boundary)
    if (places::pointInPolygon(poly, p.x + c * b.x - s * b.y, p.y + s * b.x + c * b.y)) return true;
  for (const auto& q : poly) {
    const double dx = q.x - p.x, dy = q.y - p.y;
    if (places::pointInPolygon(outline_, c * dx + s * dy, -s * dx + c * dy)) return true;
  }
  return false;
}

Truth simulatorTruth(const sim::Simulator& sim, const sim::World& world,
                     const TruthClearance& clearance, const Scenario& sc, double t) {
  const sim::Pose2 p = sim.groundTruth();
  Truth tr;
  tr.pose = {p.x, p.y, p.yaw};
  tr.clearance = clearance.at(p, sim::peopleAt(world, t));
  tr.collided = sim.collided();
  tr.collisions = sim.collisions();
  for (const auto& poly : sc.forbidden)
    if (clearance.enters(p, poly)) tr.forbidden = true;
  tr.off_map = !world.inside(world.cellX(p.x), world.cellY(p.y));
  return tr;
}

namespace {

std::string patrolOutcome(const RunMetrics& m) {
  const size_t legs = m.legs_completed + m.legs_missed + m.legs_failed;
  if (m.legs_failed == 0 && m.legs_missed == 0 && m.legs_completed > 0)
    return "patrolled " + std::to_string(m.legs_completed) + " legs";
  std::string s =
      std::to_string(m.legs_failed) + " of " + std::to_string(legs) + " patrol legs failed";
  if (m.legs_missed > 0)
    s += ", " + std::to_string(m.legs_missed) + " reported reached up to " +
         formatFixed(m.leg_miss_max_m, 2) + " m from the goal";
  return s;
}

}  // namespace

void judgeScenario(const Scenario& sc, const ScenarioEnd& e, RunMetrics& m) {
  // At the goal means at the goal in truth, at the end: the robot's own
  // "goal reached" (from its localisation) is not enough.
  const bool at_goal = e.goal_mode && e.goal_reached && m.final_goal_error_m <= e.goal_tolerance;
  if (m.collisions > 0)
    m.outcome = std::to_string(m.collisions) + " collision(s)";
  else if (m.entered_forbidden)
    m.outcome = "entered a forbidden region";
  else if (m.left_map)
    m.outcome = "left the map";
  else if (!e.gave_up.empty())
    m.outcome = e.gave_up;
  else if (e.patrol)
    m.outcome = patrolOutcome(m);
  else if (e.goal_mode && !e.has_route)
    m.outcome = sc.path_exists ? "no route to the goal" : "no route (as expected)";
  else if (e.goal_mode && !e.goal_reached)
    m.outcome = "goal not reached in " + formatFixed(e.duration, 0) + " s";
  else if (e.goal_mode && !at_goal)
    m.outcome = "reported the goal reached " + formatFixed(m.final_goal_error_m, 2) + " m from it";
  else if (sc.reach && !e.live_user && !e.reached)
    m.outcome = "did not reach the target region";
  else
    m.outcome = e.goal_mode ? "goal reached" : "ok";
  const bool goal_ok = e.patrol ? m.legs_failed == 0 && m.legs_missed == 0 && m.legs_completed > 0
                                : at_goal || (!e.has_route && !sc.path_exists);
  m.success = m.collisions == 0 && !m.entered_forbidden && !m.left_map && e.gave_up.empty() &&
              (e.goal_mode ? goal_ok : true) &&
              (!sc.reach || e.live_user || e.reached);  // a live user goes where they like
}

}  // namespace carenav::navigation
