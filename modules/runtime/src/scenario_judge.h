// What a scenario run is judged by: the simulator's truth about the robot
// (clearance of its footprint, forbidden regions, the map's edge) and the
// run's outcome ([Conceicao16, Sec. 6.1]). Internal to the simulator adapter.
#pragma once

#include <carenav/navigation/local_map.h>
#include <carenav/runtime/scenario.h>
#include <carenav/runtime/session.h>
#include <carenav/sim/simulator.h>

#include <string>
#include <vector>

namespace carenav::navigation {

/** Footprint clearance against the true world: walls, floor height changes
 *  (steps up or down, holes, stairs), table tops lower than the robot and
 *  people. */
class TruthClearance {
 public:
  TruthClearance(const sim::World& w, const RobotParams& robot, double step);
  double at(const sim::Pose2& p, const std::vector<sim::PersonNow>& people) const;
  /** Whether any part of the footprint at `p` lies in the polygon: a
   *  sample of its outline inside it, or a corner of it inside the
   *  footprint (a walker whose front wheels are over a stair edge has
   *  entered the stairs, wherever its centre is). */
  bool enters(const sim::Pose2& p, const std::vector<TPoint2D>& poly) const;

 private:
  const sim::World& w_;
  Footprint fp_;
  std::vector<TPoint2D> outline_;  // fp_.polygon as the polygon tests take it
  std::vector<float> dist_;
};

/** The truth of the simulator at time t, for the session. */
Truth simulatorTruth(const sim::Simulator& sim, const sim::World& world,
                     const TruthClearance& clearance, const Scenario& sc, double t);

/** How a scenario run ended, beside its metrics. */
struct ScenarioEnd {
  bool goal_mode = false, patrol = false;
  bool goal_reached = false;  ///< the robot reported it (or a guided walker arrived)
  bool has_route = false;     ///< a route to the goal existed at the end
  bool reached = false;       ///< the centre entered the scenario's `reach` region
  bool live_user = false;     ///< a live intent source drove the walker
  std::string gave_up;        ///< the planner's note when the recoveries gave up
  double duration = 0;        ///< s, the run's limit
  double goal_tolerance = 0;
};

/** Outcome and success of the run into `m` (collisions, forbidden regions,
 *  the map's edge, legs and final_goal_error_m already in it). */
void judgeScenario(const Scenario& sc, const ScenarioEnd& e, RunMetrics& m);

/** The closed loop of a scenario run: the simulator steps, its sensor data
 *  and the scenario's user go to the session, its commands to the robot;
 *  ends at `duration` s or when the session, the user or `o.stop` ends it. */
RunMetrics runSimulated(const Scenario& sc, const RunOptions& o, const sim::World& world,
                        sim::Simulator& sim, NavigationSession& session, double duration);

}  // namespace carenav::navigation
