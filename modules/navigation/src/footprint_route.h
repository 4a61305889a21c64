// Routes a rectangular robot can drive (GlobalPlanner's second stage). The
// A* route is planned for the footprint's inscribed circle: in a gap
// narrower than the robot's diagonal it may cross at a slant or turn where
// the rectangle cannot, and a robot that follows it wedges at the gap's
// mouth. Here the route is checked with the footprint itself, driven
// forward at each segment's heading and turned on the spot at each vertex;
// where it cannot be, a search over poses finds one that can, as the
// hybrid A* of [Dolgov10] and Nav2's Smac planner do.
#pragma once

#include <carenav/navigation/local_map.h>

#include <mrpt/math/TPoint2D.h>

#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

namespace carenav::navigation {

/** The planner's grid as the footprint checks read it. */
struct RouteGrid {
  int nx = 0, ny = 0;
  double res = 0;
  double x_min = 0, y_min = 0;       ///< m, the outer corner of cell (0, 0)
  const std::vector<uint8_t>* free;  ///< 1: free space
  const std::vector<float>* dist;    ///< m, cell centre to the nearest non-free cell's centre
  double influence = 0, weight = 0;  ///< the route's cost near obstacles (as the A* search)
};

class FootprintRoute {
 public:
  using Cell = std::pair<int, int>;
  /** `margin` (m): every pose keeps the outline this far from anything not
   *  free. `max_expansions` bounds the search. */
  FootprintRoute(const RouteGrid& g, const std::vector<Point2>& polygon, double margin,
                 int max_expansions);
  /** m, nearer than this to anything the robot may not turn freely on the
   *  spot: the footprint's circumscribed radius plus the margin. */
  double turnRadius() const { return fp_.circumscribed + margin_; }
  /** m, from (x, y) to the nearest non-free cell's edge (the distance field
   *  interpolated between cell centres); negative inside one. */
  double clearance(double x, double y) const;
  /** The footprint at (x, y, th) keeps `margin` from everything not free. */
  bool fits(double x, double y, double th) const;
  /** Whether the robot can drive `pts` (its start first) forward, each
   *  segment at its heading, turning on the spot at each vertex; nothing is
   *  checked within `skip` m of the first and the last point (a robot
   *  parked against a wall, a goal beside one). */
  bool drivable(const std::vector<TPoint2D>& pts, double skip) const;
  /** A way the footprint can drive from `start` to `goal` (cells): a
   *  hybrid A* ([Dolgov10]: continuous poses, one kept per cell and
   *  heading) whose steps are a straight of two cells along one of 48
   *  headings or a turn on the spot to the next heading where every heading
   *  between fits, guided by the distance to go through cells the
   *  inscribed circle passes; poses within `skip` m of start or goal are
   *  not checked. The polyline of its vertices (the start excluded, the
   *  goal cell's centre last) and the poses it passes, or nullopt when none
   *  is found within max_expansions. */
  struct Way {
    std::vector<TPoint2D> vertices, cells;
  };
  std::optional<Way> search(Cell start, Cell goal, double skip) const;

 private:
  double cx(int ix) const { return g_.x_min + (ix + 0.5) * g_.res; }
  double cy(int iy) const { return g_.y_min + (iy + 0.5) * g_.res; }
  bool inside(int ix, int iy) const { return ix >= 0 && iy >= 0 && ix < g_.nx && iy < g_.ny; }
  size_t idx(int ix, int iy) const { return static_cast<size_t>(iy) * g_.nx + ix; }
  /** Turning on the spot at (x, y) from heading a to b (shorter way). */
  bool turnFits(double x, double y, double a, double b) const;
  /** m still to go from each cell to `goal` through cells the inscribed
   *  circle fits in (the search's heuristic); infinity: none. */
  std::vector<float> distancesTo(Cell goal, Cell start, double skip) const;
  /** A pose the search reached: heading index h, cost g, the node before. */
  struct Node {
    double x, y;
    int h;
    float g;
    int parent;
  };
  /** The way from the start to node `found` (Way). */
  Way wayTo(const std::vector<Node>& nodes, int found, const TPoint2D& start,
            const TPoint2D& goal) const;
  /** The vertices of a search's path where the robot turns, merged where
   *  the robot could turn freely at any heading along the shortcut. */
  std::vector<TPoint2D> simplify(const std::vector<TPoint2D>& turns) const;
  RouteGrid g_;
  Footprint fp_;
  double margin_;
  int max_expansions_;
};

}  // namespace carenav::navigation
