// Global route: A* on the static map inflated by the robot, never through
// unknown or occupied cells ([Puente14, Sec. 3, Fig. 2]: HOBBIT once planned through unknown
// space), with intermediate goals at the corners of the route ([Conceicao16]).
#pragma once

#include <carenav/common/params.h>
#include <carenav/navigation/navigation_params.h>

#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/math/TPoint2D.h>

#include <optional>
#include <vector>

namespace carenav::navigation {

using mrpt::math::TPoint2D;

class FootprintRoute;  // footprint_route.h (the module's own)

struct Route {
  /** Centres of the cells of the A* path, start to goal (a route planned
   *  for the footprint: the poses of its search). */
  std::vector<TPoint2D> cells;
  /** Corners (line-of-sight simplification) and, at each narrow passage,
   *  a point before it, its centre and a point after it on the axis across
   *  it; ending at the goal. */
  std::vector<TPoint2D> waypoints;
  double length = 0;  ///< m, along the waypoints
  /** m, the clearance from its centre line to anything not free that the
   *  route keeps: the robot's radius plus plan_clearance, or less where the
   *  map allows no more (GlobalPlanner::plan). */
  double radius = 0;
  /** Planned for the footprint (GlobalPlanner::setFootprint): a route the
   *  inscribed circle's check would pass is not one the rectangle can
   *  drive, so it is checked with the footprint. */
  bool footprint = false;
};

/** A* over the cells of a static occupancy grid. A cell is passable when it
 *  is free (p_free above free_threshold) and farther than `robot_radius` +
 *  plan_clearance from every cell that is not free (occupied or unknown).
 *  Steps cost their length, more near obstacles (plan_cost_weight). When no
 *  route keeps that much, the route keeps the most that some way from start
 *  to goal allows (the bottleneck of the widest way: a maximin path), if that
 *  is more than `robot_radius` + footprint_padding: a robot that must pass a
 *  narrow gap takes the widest one there is, not the narrowest one on the
 *  shortest way. */
class GlobalPlanner {
 public:
  GlobalPlanner(const mrpt::maps::COccupancyGridMap2D& map, double robot_radius,
                const NavigationParams& p, double free_threshold = 0.65);
  /** The robot's outline (robot frame): from now on a route must be one the
   *  footprint can drive (route_footprint): where the inscribed circle's
   *  route turns or crosses a gap at a slant the rectangle cannot, a search
   *  over cells and headings finds one it can (footprint_route.h); when none
   *  is found within route_footprint_nodes, the circle's route stays. */
  void setFootprint(const std::vector<Point2>& polygon);
  /** nullopt when no route exists. Throws InputError when start or goal lie
   *  outside the map or on a cell that is not free. */
  std::optional<Route> plan(const TPoint2D& start, const TPoint2D& goal) const;
  /** The cell at (x, y) is free space (not necessarily passable). */
  bool isFree(double x, double y) const;
  /** Free and farther than `radius` (default: robot radius + plan_clearance)
   *  from anything not free. */
  bool isPassable(double x, double y, double radius = -1) const;
  /** True when every segment of the polyline crosses passable cells only
   *  (the first `skip` metres from its start excepted: the robot may stand
   *  closer to an obstacle than the route may pass); `radius` as isPassable. */
  bool polylineClear(const std::vector<TPoint2D>& pts, double skip = 0, double radius = -1) const;
  /** polylineClear, but where `before` (this planner's map before new
   *  obstacles were marked on it) already left less than `radius`, or
   *  nothing, the clearance `before` left is enough: the polyline is
   *  blocked only by what `before` did not hold. */
  bool polylineClearOf(const GlobalPlanner& before, const std::vector<TPoint2D>& pts, double skip,
                       double radius) const;
  /** True when the footprint can drive `pts` forward (each segment at its
   *  heading, turning on the spot at its vertices) keeping half of
   *  route_footprint_margin, the first and last `skip` metres excepted;
   *  without a footprint, polylineClear at the least radius. */
  bool footprintClear(const std::vector<TPoint2D>& pts, double skip) const;
  /** m, from (x, y) to the nearest cell that is not free. */
  double clearance(double x, double y) const;

 private:
  bool cellPassable(int ix, int iy, double radius) const;
  bool lineOfSight(int x0, int y0, int x1, int y1, double radius) const;
  /** The route between two cells keeping `radius` (cells near them excepted). */
  std::optional<Route> planWith(int sx, int sy, int gx, int gy, const TPoint2D& start,
                                const TPoint2D& goal, double radius) const;
  /** m, the largest clearance some 8-connected way between the cells keeps
   *  (over cells passable at `floor`, those near start and goal counted as
   *  clear); 0 when there is none. */
  double widestWay(int sx, int sy, int gx, int gy, double floor) const;
  FootprintRoute footprintRoute(double margin) const;
  /** `r` when the footprint can drive it, else a route it can (setFootprint). */
  Route drivableRoute(Route r, const TPoint2D& start, const TPoint2D& goal, int sx, int sy, int gx,
                      int gy) const;
  const mrpt::maps::COccupancyGridMap2D& map_;
  int nx_ = 0, ny_ = 0;
  double res_ = 0, radius_ = 0, floor_ = 0, influence_ = 0, weight_ = 0;
  double passage_margin_ = 0, passage_approach_ = 0;
  std::vector<Point2> polygon_;  // empty: routes for the inscribed circle only
  bool footprint_on_ = true;
  double footprint_margin_ = 0;
  int footprint_nodes_ = 0;
  std::vector<uint8_t> free_;
  std::vector<float> dist_;  // m to the nearest non-free cell
};

/** Replanning with what the robot has seen: marks `seen` obstacles and the
 *  `keep_out` points (map frame) on a copy of `map` (the robot's outline
 *  `footprint`, if given: GlobalPlanner::setFootprint) and, when the route
 *  is no longer clear of them (beyond `skip` metres from `from`), plans a
 *  new one from `from` to `goal`. With replan_new_only (or route_footprint
 *  and a footprint), seen points on or beside the map's own obstacles are
 *  not marked and only the route ahead of the robot's nearest point on it
 *  is checked; with replan_new_only, where the map itself leaves a
 *  circle's route less than its clearance, that clearance is enough.
 *  nullopt: keep the current route (still clear, or no new one found: a
 *  route that flips between two equal detours makes the robot dither). */
std::optional<Route> replanAroundSeen(const mrpt::maps::COccupancyGridMap2D& map,
                                      const std::vector<TPoint2D>& seen, const TPoint2D& from,
                                      const TPoint2D& goal, const std::optional<Route>& route,
                                      double robot_radius, double skip, const NavigationParams& p,
                                      const std::vector<TPoint2D>& keep_out = {},
                                      const std::vector<Point2>& footprint = {});

/** When to replan (the simulator runs and the bridge share it): every 2 s
 *  when the route ahead is blocked by what the robot has seen; every 0.5 s
 *  while a tracked person's lane is on the local map (it may cross the
 *  route); and, after a detour around a person, once the person is gone, a
 *  fresh route (the detour is undone). Places where recoveries keep
 *  beginning (a gap the robot reaches and cannot get through, a corner it
 *  cannot turn at) are avoided: once `avoid_after` recoveries began within
 *  2 x `avoid_radius` of one, a fresh route keeps clear of a disk of
 *  `avoid_radius` there until the next goal (RecoveryParams; 0: never). */
class RouteReplanner {
 public:
  explicit RouteReplanner(double control_rate, int avoid_after = 0, double avoid_radius = 0.2)
      : rate_(control_rate), avoid_after_(avoid_after), avoid_radius_(avoid_radius) {}
  /** Whether cycle k replans; `people`: tracked lanes exist now. */
  bool due(size_t k, bool people) const;
  /** A recovery that began at `at` (map frame) has ended. True when its
   *  place has just become one to avoid. */
  bool recovered(const TPoint2D& at);
  /** A new goal: the places to avoid are forgotten. */
  void newGoal();
  /** The places the route keeps clear of (map frame). */
  std::vector<TPoint2D> avoided() const;
  /** Replans (call when due, and when a recovery ended): a new route, or
   *  nullopt to keep the current one (also when no route keeps clear of
   *  the places to avoid). */
  std::optional<Route> step(bool people, const mrpt::maps::COccupancyGridMap2D& map,
                            const std::vector<TPoint2D>& seen, const TPoint2D& from,
                            const TPoint2D& goal, const std::optional<Route>& route,
                            double robot_radius, double skip, const NavigationParams& p,
                            const std::vector<Point2>& footprint = {});

 private:
  /** Points filling the disks of the places to avoid (but one that holds
   *  `from` or `goal`: the route could neither leave nor reach it). */
  std::vector<TPoint2D> keepOut(const TPoint2D& from, const TPoint2D& goal,
                                double resolution) const;
  struct Place {
    TPoint2D at;
    int recoveries = 0;
  };
  double rate_;
  int avoid_after_;
  double avoid_radius_;
  bool detour_ = false;
  bool fresh_ = false;  ///< a place has just become one to avoid: plan anew
  std::vector<Place> places_;
};

}  // namespace carenav::navigation
