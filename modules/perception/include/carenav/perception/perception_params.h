// [perception]: 3D point cloud -> 2.5D elevation grid -> ground plane -> 2D
// local occupancy grid, and virtual 2D scans from depth (docs/design.md, 'Perception' and 'Virtual
// scans').
#pragma once

#include <carenav/common/params.h>

#include <string>
#include <vector>

namespace carenav::perception {

/** Parameters of the perception module. Defaults are [Garrote17, Table I] for the
 *  2.5D grid, RRT-GPD and the inverse sensor model; [InterbotDepth, Table 3.1] for
 *  FSPF+ and KOS; [Puente14, App. Sec. IV-A] for the max-rule scan. */
struct PerceptionParams {
  std::string sensor;  ///< sensorLabel of the 3D observations (empty: every 3D observation)
  // 2.5D elevation grid ([Garrote17, Sec. III-A])
  int grid_cells = 200;      ///< m_x = m_y
  double resolution = 0.05;  ///< d_r, m
  double outlier_sigma = 3;  ///< per-cell outlier rejection (0 disables)
  double z_min = -1.0;       ///< m, points below are ignored (robot frame)
  double z_max = 2.0;        ///< m, points above are ignored (robot frame)
  // RRT-GPD ([Garrote17, Alg. 1])
  int rrt_iterations = 600;              ///< K
  double normal_threshold = 0.2;         ///< N_th on 1 - |n.n|
  double elevation_threshold = 0.05;     ///< E_th, m
  int window = 3;                        ///< s_x = s_y, cells
  double expansion_distance = 0.4;       ///< d_n, m
  bool seed_upright = true;              ///< seed plane must pass the normal test against +z
  int seed_attempts = 5;                 ///< seeds tried when a tree stays small
  int min_tree_nodes = 10;               ///< smaller trees are refused (never the ground plane)
  double prior_height_tolerance = 0.02;  ///< m, plane height at the robot consistent with z = 0
  double prior_tilt_deg = 3;             ///< deg, mounting tilt uncertainty (slope reference)
  bool mounting_calibrated = false;      ///< the sensor pose is known right (Pipeline::lowerFloor)
  double seed_max_elevation = 0.3;  ///< m, seed elevation within this of the robot's floor (z = 0)
  int ransac_iterations = 200;      ///< final RANSAC (and the RANSAC-only baseline)
  double ransac_threshold = 0.02;   ///< m, inlier distance of the RANSAC planes
  int seed = 1;                     ///< random seed (deterministic output)
  // Inverse sensor model ([Garrote17, Eqs. 4-6])
  double d_pth = 0.03;  ///< m, distance to the ground plane above which a voxel is an obstacle
  // Noise-aware classification (docs/perceive.md "Noise-aware voxel rules")
  double depth_noise_std = 0;  ///< m, depth std at 1 m range, sigma(r) = this * r^2 (0: off)
  double noise_k = 4;          ///< voxel extremes beyond noise_k vertical sigmas are real
  double mean_step = 0.012;    ///< m, a voxel mean this far (+ noise_k std errors) is an obstacle
  double max_slope_deg = 8;    ///< deg, steepest surface connected to the ground kept traversable
  double mean_k = 2;           ///< ramp rule: standard errors allowed on differences of voxel means
  // Ramps by region (docs/perceive.md "Noise-aware voxel rules", rule 6)
  int region_min_cells = 50;        ///< a smooth region this large is judged as a whole (cells)
  double region_tolerance = 0.003;  ///< m, model error of a cell mean against its region's plane
  double region_trim_k =
      2;                 ///< region slope fit: border margin (depth sigmas), inliers (std errors)
  double k_g = 0.3;      ///< ground amplitude gain
  double sigma2 = 0.02;  ///< m^2, Gaussian variance
  double k_n = 0.0005;   ///< sample normalisation factor
  double d_min = 3;      ///< minimum number of points
  double k_m = 0.8;      ///< amplitude gain of the voxel density
  // Measured noise (docs/perceive.md "Noise measured per frame")
  /// each frame's measured depth noise raises depth_noise_std by at most this factor (1: off)
  double noise_adapt_max = 4;
  double occupied_threshold = 0.55;  ///< cells above count as occupied
  double free_threshold = 0.45;      ///< cells below count as free
  double logodds_max = 4.6;          ///< |log-odds| clamp of the fused grid (p 0.99)
  // Baselines
  double band_z_min = 0.2;  ///< m, height-band projection ([Rosa17, Sec. 5.3])
  double band_z_max = 1.5;  ///< m
  // Depth and virtual scans ([InterbotDepth]; [Puente14, App. Sec. IV-A])
  double depth_min = 0.5;                       ///< m
  double depth_max = 4.5;                       ///< m
  int fspf_n_min = 40;                          ///< nMin
  int fspf_omega = 60;                          ///< Omega, px
  double fspf_window = 0.5;                     ///< A, m
  double fspf_epsilon = 0.02;                   ///< epsilon, m
  double fspf_stop_fraction = 0.1;              ///< stop when this share of eligible pixels remains
  std::string kos_heights = "0.1 0.3 0.6 0.9";  ///< m, scan heights of the multi-level KOS
  double kos_band = 0.1;                        ///< m, half-height of each KOS slab
  double scan_resolution = 0.5;                 ///< deg, virtual scan bin width
  double maxrule_height = 0.35;                 ///< m, HOBBIT localisation scan plane
  double maxrule_slab = 0.05;                   ///< m, slab thickness of the max-rule scan

  static const ParamTable<PerceptionParams>& table();
  std::vector<double> kosHeights() const;
};

/** Registers [perception] with the profile schemas (main.cpp). */
void registerProfileSections();

}  // namespace carenav::perception
