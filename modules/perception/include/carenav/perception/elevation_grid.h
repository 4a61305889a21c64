// 2.5D elevation grid ([Garrote17, Sec. III-A]; docs/design.md, 'Perception').
#pragma once

#include <carenav/perception/cloud.h>

#include <cmath>
#include <cstdint>
#include <optional>
#include <vector>

namespace carenav::perception {

/** One elevation voxel: z-, z+, N_z and the running mean/variance of z. */
struct ElevationCell {
  float z_lo = 0, z_hi = 0;  ///< z-, z+
  uint32_t n = 0;            ///< N_z (0: no information)
  double mean = 0, m2 = 0;   ///< Welford running mean and sum of squared deviations
  double variance() const { return n > 1 ? m2 / (n - 1) : 0.0; }
  void add(float z);
};

/** m x m cells of size d_r centred on the robot (robot frame: x forward,
 *  y left, z up). Cell (i, j): i along x, j along y; the robot is at the
 *  centre of the grid. */
class ElevationGrid {
 public:
  ElevationGrid(int cells, double resolution);
  int cells() const { return m_; }
  double resolution() const { return r_; }
  /** Adds the valid points of `robot_frame` (z within [z_min, z_max]), then,
   *  when outlier_sigma > 0, removes per cell the elevations farther than
   *  outlier_sigma standard deviations from the cell mean and recomputes z-,
   *  z+, N_z, mean and variance ([Garrote17, Fig. 4]). Returns the points used. */
  size_t build(const Cloud& robot_frame, double z_min, double z_max, double outlier_sigma);
  void clear();

  const ElevationCell& at(int i, int j) const { return cells_[idx(i, j)]; }
  bool inside(int i, int j) const { return i >= 0 && j >= 0 && i < m_ && j < m_; }
  bool valid(int i, int j) const { return inside(i, j) && cells_[idx(i, j)].n > 0; }
  /** Cell of a robot-frame position (may be outside). */
  int cellOf(double v) const { return static_cast<int>(std::floor(v / r_ + m_ * 0.5)); }
  double centre(int i) const { return (i + 0.5 - m_ * 0.5) * r_; }
  size_t validCells() const { return valid_; }
  /** Valid (finite, non-zero) points of the last build's cloud. */
  size_t validPoints() const { return last_valid_; }
  size_t outliersRemoved() const { return outliers_; }

  /** Inverse-distance weighted elevation (cell means) at robot-frame (x, y)
   *  over the s x s window of cells around it; nullopt when the window holds
   *  no valid cell ([Garrote17, Sec. IV]: IDW). */
  std::optional<double> idw(double x, double y, int s) const;

 private:
  size_t idx(int i, int j) const { return static_cast<size_t>(i) * m_ + j; }
  int m_;
  double r_;
  std::vector<ElevationCell> cells_;
  // scratch, reused from frame to frame (no allocation once warm)
  struct PointCell {
    int32_t cell;
    float z;
  };
  std::vector<PointCell> point_cell_;  // the points used: cell and elevation
  std::vector<int32_t> touched_;       // cells with data, in first-touch order
  struct Acc {                         // 32 bytes: two per cache line
    uint32_t n = 0;
    float lo = 0, hi = 0;
    float ref = 0;
    double s = 0, ss = 0;  // sums of (z - ref) and (z - ref)^2 (ref: the first z, stability)
    void add(float z, bool first);
  };
  std::vector<Acc> acc_;
  struct Band {
    float lo, hi;
  };
  std::vector<Band> band_;  // 3-sigma band of each cell (pass 1)
  size_t valid_ = 0, outliers_ = 0, last_valid_ = 0;
};

}  // namespace carenav::perception
