// 2.5D -> 2D: the inverse sensor model ([Garrote17, Eqs. 3-6]; docs/design.md, 'Inverse sensor
// model'): elevation voxels classified against the ground plane and turned into occupancy
// evidence along the rays of a robot-centred local grid.
#pragma once

#include <carenav/perception/elevation_grid.h>
#include <carenav/perception/ground_plane.h>
#include <carenav/perception/occupancy.h>
#include <carenav/perception/perception_params.h>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace carenav::perception {

/** What the ISM made of one elevation voxel (for tests and rendering). */
enum class VoxelClass : uint8_t { None = 0, Ground, Obstacle };

/** What the slope rules said of one elevation voxel (classifyVoxels()), for
 *  the integration of the frame (integrateIsm()). */
enum class SlopeVerdict : uint8_t {
  None = 0,
  SteepWindow,  ///< ground after rules 1-3, 5 and 6, an obstacle by rule 4's window
  Gentle,       ///< ground, its slope judged at most max_slope_deg (rule 4's window or a
                ///< gentle region of rule 6)
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
 *     tan(max_slope_deg) d_r + noise_k sigma_diff is ground (ramps);
 *  then rule 5 (rescueGentleGround), rule 6 (ramps by region: smooth regions
 *  judged by their own plane fit, src/slope_regions.cpp) and rule 4
 *  (markSteepGround) on the voxels rule 6 left to it.
 *  `sensor_origin` null: no noise model (sigma_v = 0). `verdicts` (when
 *  given) receives one SlopeVerdict per elevation cell. */
struct IsmStats {
  size_t voxels = 0, obstacle_voxels = 0, ground_voxels = 0;
  size_t rescued_voxels = 0;  ///< off-plane voxels kept as ground by rule 3
  size_t steep_voxels = 0;    ///< ground voxels on slopes steeper than max_slope_deg (rule 4)
  size_t step_voxels = 0;     ///< ground voxels on the line of a step between levels (rule 6)
  /// Rule 6: the slope (deg, up ahead / up to the left) of the floor's region,
  /// the floor under the robot as seen (a mounting's pitch and roll error
  /// show here); NaN when no region was the floor.
  double floor_slope_x_deg = std::numeric_limits<double>::quiet_NaN();
  double floor_slope_y_deg = std::numeric_limits<double>::quiet_NaN();
};
IsmStats classifyVoxels(const ElevationGrid& g, const Plane& plane, const PerceptionParams& p,
                        const Point3f* sensor_origin, std::vector<VoxelClass>& classes,
                        std::vector<SlopeVerdict>* verdicts = nullptr);

/** Vertical noise sigma of a voxel at robot-frame (x, y, z) seen from `o`
 *  (0 without a noise model). */
double verticalNoise(const PerceptionParams& p, const Point3f* o, double x, double y, double z);

/** Measured depth noise against the model: the median, over the voxels with
 *  at least 8 samples, of their vertical standard deviation divided by
 *  verticalNoise() at the voxel. Most voxels of a downward-looking camera
 *  are floor, whose spread inside a 5 cm cell is the noise. 0 when there is
 *  no noise model or fewer than 20 such voxels. */
double measuredNoiseRatio(const ElevationGrid& g, const PerceptionParams& p,
                          const Point3f* sensor_origin);

/** ISM integration of one elevation grid (robot frame) given the ground
 *  plane (robot frame), into `grid` at its current robot pose. `classes`
 *  (optional, one per elevation cell) receives each voxel's class. An
 *  obstacle that only rule 4's window made gives no spread along its ray to
 *  ground voxels whose own slope was judged traversable. */
IsmStats integrateIsm(const ElevationGrid& g, const Plane& plane, const PerceptionParams& p,
                      LocalOccupancy& grid, std::vector<VoxelClass>* classes = nullptr,
                      const Point3f* sensor_origin = nullptr);

/** Drop edges from an organised cloud (robot frame, one point per pixel, NaN
 *  where no return), column by column from the bottom row up: after a floor
 *  point (within the rule-1 threshold of `plane`), kGap (4) invalid rows where
 *  the floor would still return within depth_max, or two returns in a row
 *  below the floor by more than the rule-1 threshold, mean the floor ends
 *  there: occupied evidence on the 0.1 m past that floor point (the edge
 *  line). An obstacle point (above the floor) ends the floor run: the shadow
 *  behind a box is no drop. Returns the edges marked (0 for an unorganised
 *  cloud). Call between grid.beginFrame() and grid.endFrame(). */
size_t markImageDropEdges(const Cloud& c, const Plane& plane, const PerceptionParams& p,
                          const Point3f& sensor_origin, LocalOccupancy& grid);

/** Rule 4, steep ground (docs/perceive.md): for every ground voxel the
 *  least-squares slope of the ground voxel means over the 7 x 7 cells around
 *  it (at least half of them judged: N_z >= d_min), measured against the
 *  floor the robot stands on (the plane of the ground voxels within 0.75 m
 *  of the nearest one when it passes under the robot at z = 0 within
 *  prior_height_tolerance, else `plane`, whichever is tilted less than sqrt(2)
 *  prior_tilt_deg from the robot frame's level; else that level); steeper
 *  than max_slope_deg, and by more than noise_k standard errors of that
 *  slope, makes it an obstacle, whatever rules 1-3 and 5 said. Windows with
 *  residuals beyond the noise (a step inside) and voxels within noise_k depth
 *  sigmas of depth_max are not judged. `decided` (optional, one per cell,
 *  rule 6): 2 (a steep region) is not judged, 1 (a gentle region) only
 *  when steeper than max_slope_deg by noise_k standard errors (an edge the
 *  region's plane smooths over). Returns the voxels changed. */
size_t markSteepGround(const ElevationGrid& g, const Plane& plane, const PerceptionParams& p,
                       const Point3f* sensor_origin, std::vector<VoxelClass>& classes,
                       const std::vector<uint8_t>* decided = nullptr);

/** Rule 5, gentle ground: breadth first from the ground voxels, an obstacle
 *  voxel (N_z >= d_min) becomes ground when the least-squares plane over
 *  every judged voxel of the 7 x 7 cells around it (at least half of them)
 *  leaves residuals of the noise's size (no step, no edge inside) and is no
 *  steeper than max_slope_deg against the reference of rule 4. Runs after
 *  rule 3, before rule 4. Returns the voxels changed. */
size_t rescueGentleGround(const ElevationGrid& g, const Plane& plane, const PerceptionParams& p,
                          const Point3f* sensor_origin, std::vector<VoxelClass>& classes);

/** Voxel density, [Garrote17, Eq. 4], h floored at 1 mm (docs/design.md, 'Floored height'). */
double voxelDensity(const ElevationCell& c, double cell_area, const PerceptionParams& p);
/** Distance of a voxel to the plane: max over (x, y, z+) and (x, y, z-). */
double voxelPlaneDistance(const ElevationCell& c, double x, double y, const Plane& pl);

}  // namespace carenav::perception
