// A footprint maneuver out of a tight place: the shortest sequence of short
// motion primitives (forward and reverse straights and arcs, turns on the
// spot) that takes the robot's footprint, touching nothing seen, from where
// it stands to a pose on its route further on, facing the route's way. A
// search over (x, y, heading) with continuous poses kept per cell, as in
// Hybrid A* [Dolgov10]; Nav2's Smac planner does the same for car-like
// robots. The recoveries use it when the robot is boxed in or makes no
// progress: a wedge at a gap's mouth needs a turn, a step back and a turn
// that no single arc of a dynamic window holds.
#pragma once

#include <carenav/common/params.h>
#include <carenav/common/robot.h>
#include <carenav/navigation/local_map.h>
#include <carenav/navigation/local_planner.h>

#include <functional>
#include <optional>
#include <vector>

namespace carenav::navigation {

/** [nav.maneuver]: the footprint maneuvers of the recoveries. */
struct ManeuverParams {
  bool enabled = true;        ///< off: the recoveries back out, turn and wait only
  double reach = 1.0;         ///< m, a maneuver ends this far along the route past the robot
  double goal_radius = 0.15;  ///< m, ... within this of that point
  double goal_deg = 30;       ///< deg, ... facing the route's way within this
  double step = 0.1;          ///< m, length of a straight or arc primitive
  double turn_deg = 15;       ///< deg, heading change of an arc and of a turn on the spot
  double margin = 0.03;       ///< m, kept by every primitive and its continuation this far
  /** m, tried first (with a quarter of max_nodes): a maneuver keeping this
   *  much leaves room for the error of driving it (a turn that overshoots,
   *  a pose known to a few cm); when none is found, `margin`. */
  double comfort_margin = 0.06;
  double reverse_cost = 2.0;    ///< a metre reversed costs this many driven forward
  double switch_cost = 0.3;     ///< m, extra cost of changing between forward and reverse
  double clearance_cost = 1.0;  ///< m per m, extra cost of a primitive passing at no clearance
  double clearance_influence = 0.15;  ///< m, clearance beyond this costs nothing
  double radius = 2.5;                ///< m, the search stays within this of the start
  double greed = 2.0;                 ///< weight of the distance to go (weighted A*)
  int max_nodes = 20000;              ///< primitives expanded at most per search
  static const ParamTable<ManeuverParams>& table();
};

/** One step of a maneuver: a straight or arc (`length` m, forward when
 *  `dir` is 1, reverse when -1, turning `turn` rad over it) or a turn on
 *  the spot (`dir` 0, `turn` rad), ending at `end`. */
struct ManeuverStep {
  int dir = 1;
  double length = 0;
  double turn = 0;
  TPose2D end;
};

struct Maneuver {
  std::vector<ManeuverStep> steps;  ///< consecutive equal primitives merged
  double cost = 0;
  size_t expanded = 0;  ///< primitives expanded by the search
};

class DistanceToGoal;  // the search's heuristic (maneuver.cpp)

/** The search. Poses are in the map's frame. */
class ManeuverPlanner {
 public:
  /** Whether a reversing primitive may pass the pose (the rear is seen or
   *  was swept: the recoveries ask whether it lies on the way the robot
   *  came); unset: everywhere. */
  using ReverseGate = std::function<bool(const TPose2D&)>;

  ManeuverPlanner(const ManeuverParams& p, const RobotParams& robot);
  /** The cheapest maneuver from `start` to within goal_radius of `goal`
   *  facing goal.phi within goal_deg, every primitive's footprint (and its
   *  continuation by `margin`) `margin` from everything on `map` (a start
   *  nearer than that: as near as the start), comfort_margin when a first
   *  search of max_nodes / 4 expansions finds a maneuver keeping that much;
   *  none when the search finds none within max_nodes expansions. A robot
   *  with v_min = 0 never reverses. */
  std::optional<Maneuver> plan(const LocalCostmap& map, const TPose2D& start, const TPose2D& goal,
                               const ReverseGate& reverse_ok = {}) const;
  const ManeuverParams& params() const { return p_; }

 private:
  struct Primitive {
    int dir;
    double length, turn;
  };
  /** m, the smallest clearance along primitive `m` from `from` (whose
   *  clearance is `from_clearance`) and at its end, capped at
   *  clearance_influence; `least` negative when it or its continuation by
   *  `margin` comes nearer than `floor` to anything or leaves the map. */
  struct Sweep {
    double least, end;
  };
  Sweep sweep(const LocalCostmap& map, const TPose2D& from, double from_clearance,
              const Primitive& m, double floor, double margin) const;
  /** plan() keeping `margin`, expanding at most `max_nodes` primitives,
   *  guided by `togo` (computed once for both searches). */
  std::optional<Maneuver> search(const LocalCostmap& map, const TPose2D& start, const TPose2D& goal,
                                 const DistanceToGoal& togo, const ReverseGate& reverse_ok,
                                 double margin, int max_nodes) const;
  ManeuverParams p_;
  RobotParams r_;
  std::vector<Primitive> prims_;
  double lever_ = 0;  ///< m, the footprint's farthest corner from the centre
};

/** The pose reached by moving `length` m along an arc turning `turn` rad
 *  (dir 1 forward, -1 reverse), or turning `turn` rad on the spot (dir 0). */
TPose2D applyPrimitive(const TPose2D& p, int dir, double length, double turn);

}  // namespace carenav::navigation
