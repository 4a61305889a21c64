// A simulated world: an occupancy grid plus a height layer (steps, stairs,
// holes, gutters, ramps, tables) and people walking scripted paths. Read
// from a small YAML world file (docs/simulate.md).
#pragma once

#include <carenav/common/errors.h>

#include <mrpt/maps/COccupancyGridMap2D.h>

#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace carenav::sim {

/** Limits of a world file, checked while reading it (docs/simulate.md):
 *  coordinates within +-kMaxCoordinate m, at most kMaxPoints points in a
 *  polygon or path, kMaxFeatures features and kMaxPeople people. */
inline constexpr double kMaxCoordinate = 1e5;
inline constexpr size_t kMaxPoints = 1000;
inline constexpr size_t kMaxFeatures = 1000;
inline constexpr size_t kMaxPeople = 100;

struct Vec2 {
  double x = 0, y = 0;
};

/** A raised or lowered region of the floor. */
struct Feature {
  enum class Kind { Step, Hole, Gutter, Stairs, Ramp, Table };
  Kind kind = Kind::Step;
  std::vector<Vec2> polygon;  ///< outline in the map frame (rect becomes 4 vertices)
  double height = 0;          ///< step: floor height; hole/gutter: -depth; table: top height
  // stairs / ramp: heights change along `axis` (unit vector in the map frame)
  Vec2 axis{1, 0};
  int steps = 1;            ///< stairs: number of steps
  double rise = 0;          ///< stairs: height change per step; ramp: total change (negative: down)
  double thickness = 0.04;  ///< table: top thickness
  double leg = 0.05;        ///< table: square leg side at each corner (0: no legs)
  static const char* kindName(Kind k);
};

/** A person: a vertical cylinder walking a polyline at constant speed. */
struct Person {
  double radius = 0.25, height = 1.7, speed = 0.8;  ///< m, m, m/s
  bool loop = true;  ///< after the last waypoint walk back to the first; else stop there
  std::vector<Vec2> path;
  /** Position at time t (s since the start). */
  Vec2 at(double t) const;
};

/** One cell of the height layer. */
struct Cell {
  float floor = 0;                                          ///< floor height (m); +inf for walls
  float slab_lo = std::numeric_limits<float>::infinity();   ///< overhang (table top) bottom
  float slab_hi = -std::numeric_limits<float>::infinity();  ///< overhang top
  bool plain() const { return floor == 0 && !(slab_lo <= slab_hi); }
  bool wall() const { return floor == std::numeric_limits<float>::infinity(); }
  bool hasSlab() const { return slab_lo <= slab_hi; }
};

/** The static world and its people. Cells are those of the occupancy grid. */
class World {
 public:
  /** Builds the height layer from the grid (occupied cells become walls of
   *  `wall_height`) and the features. */
  World(mrpt::maps::COccupancyGridMap2D grid, std::vector<Feature> features,
        std::vector<Person> people, double wall_height = 2.5);

  const mrpt::maps::COccupancyGridMap2D& grid() const { return grid_; }
  const std::vector<Feature>& features() const { return features_; }
  const std::vector<Person>& people() const { return people_; }
  double wallHeight() const { return wall_height_; }

  int sizeX() const { return nx_; }
  int sizeY() const { return ny_; }
  double resolution() const { return res_; }
  double xMin() const { return x0_; }
  double yMin() const { return y0_; }
  bool inside(int cx, int cy) const { return cx >= 0 && cy >= 0 && cx < nx_ && cy < ny_; }
  int cellX(double x) const;
  int cellY(double y) const;
  const Cell& cell(int cx, int cy) const { return cells_[static_cast<size_t>(cy) * nx_ + cx]; }
  /** Floor height at a point (0 outside the grid; +inf on a wall). */
  double floorAt(double x, double y) const;
  /** Chebyshev distance (cells) from a cell to the nearest non-plain cell,
   *  capped at 255; used to skip empty space when casting rays. */
  uint8_t clearance(int cx, int cy) const { return clear_[static_cast<size_t>(cy) * nx_ + cx]; }

  /** Where the file came from (for messages). */
  std::string source;

 private:
  void rasterise();
  void computeClearance();

  mrpt::maps::COccupancyGridMap2D grid_;
  std::vector<Feature> features_;
  std::vector<Person> people_;
  double wall_height_;
  int nx_ = 0, ny_ = 0;
  double res_ = 0.05, x0_ = 0, y0_ = 0;
  std::vector<Cell> cells_;
  std::vector<uint8_t> clear_;
};

/** Reads a world YAML (docs/simulate.md) and the map it names (relative to
 *  the YAML's folder). Throws InputError naming the file, the line and what
 *  is wrong: empty or truncated file, unknown keys, bad numbers, missing map.
 *  Walls are `wall_height` tall when the file says, else default_wall_height. */
World loadWorld(const std::string& yaml_path, double default_wall_height = 2.5);
/** The same from text; `origin` names the file in messages and `base_dir`
 *  resolves the map path. */
World worldFromText(const std::string& text, const std::string& origin, const std::string& base_dir,
                    double default_wall_height = 2.5);

/** True when the point is inside the polygon (even-odd rule). */
bool pointInPolygon(const std::vector<Vec2>& poly, double x, double y);

}  // namespace carenav::sim
