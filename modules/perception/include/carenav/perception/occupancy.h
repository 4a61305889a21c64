// 2.5D -> 2D: inverse sensor model ([Garrote17, Eqs. 3-6]; docs/design.md, 'Inverse sensor model')
// and log-odds fusion into a robot-centred local occupancy grid; the height-band and 2D-scan
// insertions of the baselines use the same grid.
#pragma once

#include <carenav/perception/elevation_grid.h>
#include <carenav/perception/ground_plane.h>
#include <carenav/perception/perception_params.h>

#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/poses/CPose2D.h>

#include <cstdint>
#include <vector>

namespace carenav::perception {

struct CellCounts {
  size_t occupied = 0, free = 0, unknown = 0;
};

/** What the ISM made of one elevation voxel (for tests and rendering). */
enum class VoxelClass : uint8_t { None = 0, Ground, Obstacle };

/** m x m log-odds grid, axis-aligned with the odometry frame and kept centred
 *  on the robot: moveTo() scrolls it by whole cells (cells leaving the window
 *  are forgotten, new ones are unknown). One frame is a single measurement
 *  z_t: during a frame each cell collects its strongest occupied evidence and
 *  its strongest free evidence; at endFrame() the cell's p(c|z_t) is the
 *  occupied evidence when there is any (safety first: a voxel's obstacle is
 *  never erased by the floor seen beside it in the same frame), else the free
 *  one, and it is fused in log odds ([Garrote17, Eq. 3], prior 0.5). */
class LocalOccupancy {
 public:
  LocalOccupancy(int cells, double resolution, double logodds_max);
  int cells() const { return m_; }
  double resolution() const { return r_; }
  void reset();
  /** Robot pose in the odometry frame; scrolls the grid to stay centred. */
  void moveTo(const mrpt::poses::CPose2D& robot);
  const mrpt::poses::CPose2D& robot() const { return robot_; }

  void beginFrame();
  /** Evidence in odometry-frame cell (i, j) (grid indices). */
  void addEvidence(int i, int j, float p);
  void endFrame();

  /** Grid cell of an odometry-frame position (may be outside). */
  int cellX(double x) const;
  int cellY(double y) const;
  double centreX(int i) const;
  double centreY(int j) const;
  bool inside(int i, int j) const { return i >= 0 && j >= 0 && i < m_ && j < m_; }
  /** Occupancy probability of cell (i, j) (0.5 unknown). */
  double prob(int i, int j) const;
  /** Occupancy probability at an odometry-frame position (0.5 outside). */
  double probAt(double x, double y) const;
  CellCounts counts(double free_below, double occupied_above) const;
  /** As an MRPT grid (cells hold the free probability, 1 - p). */
  mrpt::maps::COccupancyGridMap2D toMrpt() const;

  /** Casts the ray robot -> (x, y) (odometry frame) and calls f(i, j, dist of
   *  the cell centre from the robot, along-ray index) until `max_dist`. */
  template <class F>
  void walkRay(double x, double y, double max_dist, F&& f) const;
  /** Walks the ray robot -> (x, y) from distance s0 to s1 (either direction,
   *  half-cell steps, each cell once), calling f(i, j, dist of the cell
   *  centre from the robot); f returns false to stop. */
  template <class F>
  void walkSegment(double x, double y, double s0, double s1, F&& f) const;
  /** This frame's strongest free evidence in cell (i, j) (0.5: none). */
  float frameFree(int i, int j) const { return free_[static_cast<size_t>(i) * m_ + j]; }

 private:
  int m_;
  double r_, lmax_;
  long org_i_ = 0, org_j_ = 0;  // lattice index of cell (0, 0)
  mrpt::poses::CPose2D robot_;
  std::vector<float> logodds_, occ_, free_;
};

/** Noise-aware voxel classification (docs/perceive.md "Noise-aware voxel
 *  rules"), one class per elevation cell (None: no data):
 *  1. distance rule ([Garrote17]): d = max distance of z+ and z- to the plane; the
 *     threshold is max(d_pth, noise_k sigma_v), sigma_v the vertical depth
 *     noise at the voxel (depth_noise_std r^2 along the ray from
 *     `sensor_origin`, times the ray's vertical share |dz| / r);
 *  2. mean rule: |mean - plane| > mean_step + noise_k sigma_v / sqrt(N_z)
 *     (small boxes >= 20 mm, [Puente14, App. Sec. VI]);
 *  3. traversable surfaces: an off-plane voxel flat within the rule-1
 *     threshold around its own mean and connected (4-neighbours, breadth
 *     first from the plane's ground voxels) through mean steps of at most
 *     tan(max_slope_deg) d_r + noise_k sigma_diff is ground (ramps).
 *  `sensor_origin` null: no noise model (sigma_v = 0). */
struct IsmStats {
  size_t voxels = 0, obstacle_voxels = 0, ground_voxels = 0;
  size_t rescued_voxels = 0;  ///< off-plane voxels kept as ground by rule 3
};
IsmStats classifyVoxels(const ElevationGrid& g, const Plane& plane, const PerceptionParams& p,
                        const Point3f* sensor_origin, std::vector<VoxelClass>& classes);

/** Vertical noise sigma of a voxel at robot-frame (x, y, z) seen from `o`
 *  (0 without a noise model). */
double verticalNoise(const PerceptionParams& p, const Point3f* o, double x, double y, double z);

/** ISM integration of one elevation grid (robot frame) given the ground
 *  plane (robot frame), into `grid` at its current robot pose. `classes`
 *  (optional, one per elevation cell) receives each voxel's class. */
IsmStats integrateIsm(const ElevationGrid& g, const Plane& plane, const PerceptionParams& p,
                      LocalOccupancy& grid, std::vector<VoxelClass>* classes = nullptr,
                      const Point3f* sensor_origin = nullptr);

/** Voxel density, [Garrote17, Eq. 4], h floored at 1 mm (docs/design.md, 'Floored height'). */
double voxelDensity(const ElevationCell& c, double cell_area, const PerceptionParams& p);
/** Distance of a voxel to the plane: max over (x, y, z+) and (x, y, z-). */
double voxelPlaneDistance(const ElevationCell& c, double x, double y, const Plane& pl);

/** Height-band baseline ([Rosa17, Sec. 5.3], ROS pointcloud_to_laserscan +
 *  local_map): points with band_z_min < z < band_z_max are obstacles; per
 *  bearing bin the cells up to the nearest obstacle (or, without one, up to
 *  the farthest point seen) are free. Returns the number of band points. */
size_t integrateHeightBand(const Cloud& robot_frame, const PerceptionParams& p,
                           LocalOccupancy& grid);

/** Inserts a 2D scan (sensor pose taken into account): cells before each
 *  valid return free, the return's cell occupied. */
void integrateScan(const mrpt::obs::CObservation2DRangeScan& scan, LocalOccupancy& grid,
                   float p_free = 0.35f, float p_occ = 0.8f);

// ---------------------------------------------------------------- inline

template <class F>
void LocalOccupancy::walkRay(double x, double y, double max_dist, F&& f) const {
  const double rx = robot_.x(), ry = robot_.y();
  const double dx = x - rx, dy = y - ry;
  const double len = std::sqrt(dx * dx + dy * dy);
  if (len < 1e-9) {
    f(cellX(rx), cellY(ry), 0.0, 0);
    return;
  }
  const double ux = dx / len, uy = dy / len;
  const double step = 0.5 * r_;
  int last_i = -(1 << 30), last_j = -(1 << 30), k = 0;
  for (double s = 0; s <= max_dist; s += step) {
    const int i = cellX(rx + ux * s), j = cellY(ry + uy * s);
    if (i == last_i && j == last_j) continue;
    if (!inside(i, j)) break;
    last_i = i;
    last_j = j;
    const double cx = centreX(i) - rx, cy = centreY(j) - ry;
    f(i, j, std::sqrt(cx * cx + cy * cy), k++);
  }
}

template <class F>
void LocalOccupancy::walkSegment(double x, double y, double s0, double s1, F&& f) const {
  const double rx = robot_.x(), ry = robot_.y();
  const double dx = x - rx, dy = y - ry;
  const double len = std::sqrt(dx * dx + dy * dy);
  if (len < 1e-9) {
    f(cellX(rx), cellY(ry), 0.0);
    return;
  }
  const double ux = dx / len, uy = dy / len;
  const double inv = 1.0 / r_;
  const double step = s1 >= s0 ? 0.5 * r_ : -0.5 * r_;
  const int n = static_cast<int>(std::floor((s1 - s0) / step + 1e-9));
  int last_i = -(1 << 30), last_j = -(1 << 30);
  for (int k = 0; k <= n + 1; ++k) {
    const double s = k <= n ? s0 + k * step : s1;  // the last sample is s1 itself
    const int i = static_cast<int>(static_cast<long>(std::floor((rx + ux * s) * inv)) - org_i_);
    const int j = static_cast<int>(static_cast<long>(std::floor((ry + uy * s) * inv)) - org_j_);
    if (i == last_i && j == last_j) continue;
    if (!inside(i, j)) {
      if (step > 0) break;
      continue;
    }
    last_i = i;
    last_j = j;
    const double cx = (org_i_ + i + 0.5) * r_ - rx, cy = (org_j_ + j + 0.5) * r_ - ry;
    if (!f(i, j, std::sqrt(cx * cx + cy * cy))) return;
  }
}

}  // namespace carenav::perception
