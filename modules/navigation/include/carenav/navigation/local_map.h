// What the local planners see: recently sensed obstacles (with memory) and a
// robot-centred grid with the distance to the nearest obstacle, queried with
// the robot's footprint.
#pragma once

#include <carenav/common/params.h>
#include <carenav/navigation/navigation_params.h>

#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/math/TPoint2D.h>
#include <mrpt/math/TPose2D.h>

#include <cstdint>
#include <functional>
#include <optional>
#include <unordered_map>
#include <vector>

namespace carenav::navigation {

using mrpt::math::TPoint2D;
using mrpt::math::TPose2D;

/** One range scan in the world (odometry or map) frame: the sensor's
 *  position and the end point of every ray; `hit[i]` is false for a ray that
 *  saw nothing up to its maximum range (it only clears). */
struct WorldScan {
  TPoint2D origin;
  std::vector<TPoint2D> ends;
  std::vector<uint8_t> hit;
  double range_min = 0;  ///< m, the sensor is blind closer than this (nothing is cleared there)
  /** Where the robot was when the scan was taken (the obstacle memory keeps
   *  hits within its radius of it); none: the sensor's origin. */
  std::optional<TPoint2D> robot;
};

/** A segment of the world (its end points; equal for a point). */
struct Segment {
  TPoint2D a, b;
};

/** The segment standing for one scan's hits [begin, end) of `pts` in a
 *  cell, seen from the sensor at `o`: a range sensor's bearings are precise
 *  and its ranges noisy, so the range is fitted as linear in the bearing
 *  (a plane face) by least squares, and the ends are at the hits' extreme
 *  bearings. A face seen in a cell gives its part of the face, its corner
 *  kept and the range noise averaged; one hit is itself, two the segment
 *  between them. */
Segment fitAlongBearings(const TPoint2D& o, const std::vector<TPoint2D>& pts, size_t begin,
                         size_t end);

/** Cells already visited by the rays of the current scan, on a small dense
 *  grid around the sensor: near the sensor, a lidar's thousand rays pass the
 *  same cells again and again; each cell is updated once per scan. */
class ScanCells {
 public:
  /** A new scan from the cell (ox, oy), rays at most `reach_cells` long. */
  void begin(int64_t ox, int64_t oy, int64_t reach_cells);
  /** True the first time the cell is met in this scan (always true for a
   *  cell beyond the reach, or when the reach is too large to cover). */
  bool first(int64_t cx, int64_t cy);

 private:
  static constexpr int64_t kMaxHalf = 512;  // 1025 x 1025 cells at most (4 MiB)
  std::vector<uint32_t> stamp_;
  uint32_t now_ = 0;
  int64_t ox_ = 0, oy_ = 0, half_ = -1;
};

/** Obstacles seen recently, in the world frame, on a hash grid of cells.
 *  A hit marks its cell with the scan time; a later ray that passes through
 *  a marked cell clears it (a person who walked away); cells not seen for
 *  `persistence` seconds, or farther than `radius` from the robot, are
 *  dropped. This keeps obstacles that left a depth camera's blind zone
 *  (HOBBIT, [Puente14, App. Sec. IV-C, Table I]: obstacles remembered 5 s). */
class ObstacleMemory {
 public:
  ObstacleMemory(double resolution, double persistence, double radius);
  void add(const WorldScan& scan, double t);
  /** Adds bare obstacle points (no clearing), e.g. from a perception grid. */
  void addPoints(const std::vector<TPoint2D>& points, double t);
  /** Drops cells outside the radius, and cells older than persistence that
   *  lie where the sensors look (the bearings of the rays of the scans added
   *  between the last two prunes, from the last one's origin; everywhere
   *  when no scan was ever added): what no sensor can see now, behind a 270
   *  deg lidar, is kept until the robot turns to see it or leaves it
   *  behind. */
  void prune(double now, const TPoint2D& robot);
  /** Where in each cell the obstacle was seen: the two ends of the segment
   *  of the hits of the scan that saw it last (fitAlongBearings), one point
   *  when they coincide. LocalCostmap::build takes two points of a cell as
   *  the segment between them. */
  std::vector<TPoint2D> points() const;
  size_t size() const { return cells_.size(); }
  void clear() { cells_.clear(); }

 private:
  uint64_t key(double x, double y) const;
  double res_, persistence_, radius_;
  /** A remembered cell: when it was last seen, and the segment of that
   *  scan's hits in it. One arbitrary hit of a post's face may lie 4 cm from
   *  the face's corner that the robot will pass; the segment keeps it. */
  struct Cell {
    double t = 0;
    float ax = 0, ay = 0, bx = 0, by = 0;
  };
  /** The bearings the scans between two prunes covered, in 1 deg bins
   *  about the last scan's origin. */
  struct View {
    static constexpr int kBins = 360;
    bool any = false;   ///< a scan was ever added
    bool next = false;  ///< pruned since: the next scan starts a new view
    TPoint2D origin;
    std::vector<uint8_t> bins;
    void add(const WorldScan& s);
    int bin(double x, double y) const;
    bool covers(double x, double y) const;
  };
  std::unordered_map<uint64_t, Cell> cells_;
  ScanCells visited_;
  View view_;
};

/** Where free space was seen recently (ray clearing of scans, free cells of
 *  a perception grid), per cell: the start and end of its latest stretch
 *  of being seen free. An obstacle in a cell whose free stretch ended
 *  recently, after lasting a while, has moved in: a person, not a wall
 *  (walls are never seen free; noise flickers too briefly). */
class FreeSpaceHistory {
 public:
  FreeSpaceHistory(double resolution, double radius) : res_(resolution), radius_(radius) {}
  void markFree(double x, double y, double t);
  /** An obstacle seen in the cell: a later sighting of free space starts a
   *  new stretch (cells at the edge of a wall flicker; they never build a
   *  stretch long enough to count). */
  void markHit(double x, double y, double t);
  /** The rays of a scan, up to one cell before each hit, within `radius`
   *  of the sensor. */
  void addScan(const WorldScan& scan, double t);
  /** The cell was seen free for at least `min_free` seconds, ending at most
   *  `window` seconds before `now`, and was not hit during the
   *  `static_memory` seconds before that stretch began. */
  bool recentlyFree(double x, double y, double now, double window, double min_free,
                    double static_memory = 0) const;
  /** Something moved into open space: the cell and at least 7 of its 8
   *  neighbours were recently free (as above), and none of them is a
   *  static obstacle (staticHit). (The edge cell of a static obstacle can
   *  look free to grazing rays while its neighbours are the obstacle's own
   *  cells, never seen free; a thin post's cells are all grazed from some
   *  side, but they were hit before. The cell diagonal to a post's corner
   *  has one such neighbour only: range noise puts hits of the corner in
   *  it; at the face of a wall seen at a grazing angle, likewise. A person
   *  beside a wall is seen moving one cell from it.) */
  bool movedIn(double x, double y, double now, double window, double min_free,
               double static_memory = 0) const;
  /** The cell was hit within `window` seconds of `now`, not seen free
   *  since, and its hits began no later than `since` (the start of a
   *  neighbour's free stretch): an obstacle that was there while the
   *  neighbour was seen free, not one that moved in (a walking person's
   *  cells were hit only after the cells ahead of it were seen free). */
  bool staticHit(double x, double y, double now, double window, double since) const;
  /** Drops cells neither seen free for `keep` seconds nor hit for
   *  `keep_hits` seconds. */
  void prune(double now, double keep, double keep_hits = 0);
  size_t size() const { return cells_.size(); }

 private:
  uint64_t key(double x, double y) const;
  double res_, radius_;
  ScanCells visited_;
  struct Stretch {
    double first = -1e300, last = -1e300;  ///< the latest stretch of being seen free
    double hit = -1e300;                   ///< last hit
    double hit_before = -1e300;            ///< last hit before the stretch began
    double hit_since = -1e300;             ///< first hit since the cell was last seen free
  };
  std::unordered_map<uint64_t, Stretch> cells_;
};

/** Where a sensor saw free space: per cell, its latest sighting (a ray
 *  passed through it, up to a cell short of the ray's hit) with the stamp
 *  the caller gives (time, and the odometry travelled and turned then, for
 *  the error of where the cell lies now), within `radius` of the sensor. A
 *  270 deg lidar never sees behind the robot; it saw that space as the
 *  robot came (Recovery: a maneuver may reverse over it). */
class SeenFree {
 public:
  struct Sight {
    double t = 0, travel = 0, turned = 0;
  };
  SeenFree(double resolution, double radius) : res_(resolution), radius_(radius) {}
  void addScan(const WorldScan& scan, const Sight& stamp);
  /** Drops the cells farther than `radius` from `robot` and those whose
   *  sighting `keep` refuses. */
  void prune(const TPoint2D& robot, const std::function<bool(const Sight&)>& keep);
  /** The cell's latest sighting; null when none is kept. */
  const Sight* at(double x, double y) const;
  size_t size() const { return cells_.size(); }

 private:
  double res_, radius_;
  ScanCells visited_;
  std::unordered_map<uint64_t, Sight> cells_;
};

/** The robot's footprint with what the queries need. */
struct Footprint {
  std::vector<Point2> polygon;     ///< robot frame, m
  double inscribed = 0;            ///< m, largest circle about the origin inside the polygon
  double circumscribed = 0;        ///< m, smallest circle about the origin holding it
  std::vector<TPoint2D> boundary;  ///< samples along the outline (robot frame)
  std::vector<TPoint2D> interior;  ///< samples inside (robot frame)
  /** Runs of neighbouring samples (of `boundary`, then of `interior`, which
   *  are stored tile by tile) with the circle holding them: a run whose
   *  centre is far enough from every obstacle needs no look at its samples. */
  struct Group {
    TPoint2D centre;
    double radius = 0;
    size_t begin = 0, end = 0;
  };
  std::vector<Group> boundary_groups, interior_groups;
  Footprint() = default;
  /** Samples the outline and the inside every `spacing` metres. Throws
   *  InputError for fewer than 3 vertices or no area. */
  Footprint(const std::vector<Point2>& polygon, double spacing);
  bool contains(double x, double y) const;  ///< robot frame
};

/** Result of placing the footprint at a pose. */
struct FootprintCheck {
  bool collision =
      false;             ///< an obstacle touches (within the padding) or lies inside the footprint
  bool outside = false;  ///< part of the footprint leaves the local grid
  double clearance = 0;  ///< m, footprint outline to the nearest obstacle (0 on collision)
};

/** A square grid of side `local_size` around a centre, with the Euclidean
 *  distance from every cell to the nearest obstacle cell (exact distance
 *  transform, Felzenszwalb and Huttenlocher 2012), a 0..100 cell cost
 *  falling with that distance ([Rosa17, Sec. 4.1.2]: 0 free .. 100
 *  occupied), and footprint queries. */
class LocalCostmap {
 public:
  LocalCostmap(const LocalMapParams& p, const Footprint& footprint);
  /** Rebuilds around `centre` from obstacle points (world frame; contact is
   *  measured to what the points of a cell stand for: one a point, two the
   *  segment between them, more their box) and,
   *  optionally, the occupied cells of a static map in the same frame
   *  (cells with occupancy probability above `static_occupied`). */
  void build(const TPoint2D& centre, const std::vector<TPoint2D>& obstacles,
             const mrpt::maps::COccupancyGridMap2D* static_map = nullptr,
             double static_occupied = 0.65);
  /** The same, with `cell_points` each standing alone for its cell (a
   *  perception grid's obstacle cells, not sensor hits), replacing what was
   *  put there before. */
  void build(const TPoint2D& centre, const std::vector<TPoint2D>& obstacles,
             const std::vector<TPoint2D>& cell_points,
             const mrpt::maps::COccupancyGridMap2D* static_map = nullptr,
             double static_occupied = 0.65);
  /** Grows moving obstacles (world frame) by `inflation` metres on the map
   *  built last: the distance of a cell becomes the smaller of its distance
   *  to the static ones and its distance to a moving one less `inflation`. */
  void addMoving(const std::vector<TPoint2D>& moving, double inflation);
  size_t movingCells() const { return moving_cells_; }

  bool inside(double x, double y) const;
  /** m, from (x, y) to the nearest obstacle cell centre; `farValue()` when
   *  there is no obstacle; 0 on an obstacle cell; -1 outside the grid. */
  double distance(double x, double y) const;
  double farValue() const { return far_; }
  /** 0 (clear by cost_decay or more) .. 100 (obstacle cell); 100 outside. */
  int cellCost(double x, double y) const;
  FootprintCheck check(const TPose2D& pose) const;
  /** Footprint clearance at the pose, capped at `cap` metres (cheaper when
   *  the robot is far from everything). */
  FootprintCheck check(const TPose2D& pose, double cap) const;
  /** The same with the heading's cosine and sine given (rollouts have them). */
  FootprintCheck check(const TPose2D& pose, double cap, double cos_phi, double sin_phi) const;

  const Footprint& footprint() const { return fp_; }
  double resolution() const { return res_; }
  size_t obstacleCells() const { return obstacle_cells_; }
  TPoint2D origin() const { return {x0_, y0_}; }
  int size() const { return n_; }

  /** m, from the footprint's outline at the pose to the nearest obstacle
   *  (as check's clearance, uncapped), negative when an obstacle point lies
   *  inside the footprint; 0 on a static map's or a moving obstacle's cell
   *  under the outline. Continuous in the pose near point obstacles: the
   *  supervisor tells a move away from a post from one towards it. */
  double outlineClearance(const TPose2D& pose) const;
  /** What one sample (world point wx, wy) of the outline of the footprint
   *  at `pose` (its heading's cosine and sine c, s) says: true for contact
   *  (the nearest obstacle within the padding of the outline, or inside
   *  it), else `clearance` lowered to what it sees. check() asks this of
   *  every sample near enough to an obstacle to matter. */
  bool sampleContact(double wx, double wy, const TPose2D& pose, double c, double s,
                     double& clearance) const;
  /** The same for a sample inside the footprint: an obstacle in its cell
   *  lies inside the footprint (or touches its outline). */
  bool interiorContact(double wx, double wy, const TPose2D& pose, double c, double s) const;

 private:
  int cellX(double x) const;
  int cellY(double y) const;
  /** m, from the outline of the footprint at (x, y, cos, sin) to the
   *  obstacle nearest to the world point (wx, wy) (a sample of the
   *  outline): the exact point for sensed obstacles, the cell's square for
   *  a static map's; negative inside the footprint; infinity when none is
   *  within `reach` cells. */
  double outlineDistanceNear(double wx, double wy, const TPose2D& pose, double c, double s,
                             int reach) const;
  /** The outline distance of one world point (robot frame via c, s). */
  double outlineDistanceOf(double wx, double wy, const TPose2D& pose, double c, double s) const;
  /** The outline distance of what the sensed points of cell `i` stand for
   *  (a point, a segment or a box): of its nearest end or corner, or of the
   *  outline's nearest vertex to it; negative with an end or corner inside,
   *  0 when it crosses the outline. */
  double shapeDistanceOf(size_t i, const TPose2D& pose, double c, double s) const;
  double segmentDistanceOf(size_t i, const TPose2D& pose, double c, double s) const;
  double boxDistanceOf(size_t i, const TPose2D& pose, double c, double s) const;
  /** One more sensed point in cell `i`; setPoint: `o` alone in it. */
  void addToCell(size_t i, const TPoint2D& o);
  void setPoint(size_t i, const TPoint2D& o);
  double res_, far_, decay_, contact_, padding_;
  int n_ = 0;
  double x0_ = 0, y0_ = 0;    // world coordinates of cell (0, 0)'s lower-left corner
  std::vector<float> dist_;   // metres, to any obstacle (moving ones grown)
  std::vector<float> mdist_;  // metres, to the grown moving obstacles only
  std::vector<uint8_t> occ_;  // 1: a sensed point in the cell, 2: a static map's cell
  // The sensed points of a cell (occ_ 1): one (p = q), a segment p-q (two)
  // or their box, lower corner p, upper q (three or more, count_ 3).
  std::vector<float> px_, py_, qx_, qy_;
  std::vector<uint8_t> count_;
  size_t obstacle_cells_ = 0, moving_cells_ = 0;
  Footprint fp_;
};

}  // namespace carenav::navigation
