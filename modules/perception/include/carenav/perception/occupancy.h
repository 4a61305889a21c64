// Log-odds fusion into a robot-centred local occupancy grid ([Garrote17, Eq. 3]), and the
// height-band and 2D-scan insertions of the baselines into it. The inverse sensor model that
// fills it from the 2.5D grid is in ism.h.
#pragma once

#include <carenav/perception/cloud.h>
#include <carenav/perception/perception_params.h>

#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/poses/CPose2D.h>

#include <cmath>
#include <cstddef>
#include <vector>

namespace carenav::perception {

struct CellCounts {
  size_t occupied = 0, free = 0, unknown = 0;
};

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
  /** Cell (i, j) holds a drop: a surface seen below the floor, or a drop's
   *  edge line. Kept (and scrolled) until the floor is seen in the cell
   *  (setDrop(i, j, false)); the camera's blind zone gives such a cell no
   *  free evidence (integrateIsm()). */
  void setDrop(int i, int j, bool drop) {
    if (inside(i, j)) drop_[static_cast<size_t>(i) * m_ + j] = drop;
  }
  bool drop(int i, int j) const { return inside(i, j) && drop_[static_cast<size_t>(i) * m_ + j]; }

 private:
  int m_;
  double r_, lmax_;
  long org_i_ = 0, org_j_ = 0;  // lattice index of cell (0, 0)
  mrpt::poses::CPose2D robot_;
  std::vector<float> logodds_, occ_, free_;
  std::vector<uint8_t> drop_;
};

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
