// Internal to the steep-ground rules (slope_rule.cpp, slope_regions.cpp):
// the floor slopes are measured against, and rule 6, ramps by region.
#pragma once

#include <carenav/perception/ism.h>

#include <cstdint>
#include <vector>

namespace carenav::perception {

/** Gradient of the floor the robot stands on (rise per cell along i and j)
 *  and its variance (sum over i and j; 0 when it is the plane or the level,
 *  not a fit): see markSteepGround(). */
struct SlopeReference {
  double gi = 0, gj = 0, var = 0;
};
SlopeReference slopeReference(const ElevationGrid& g, const Plane& plane, const PerceptionParams& p,
                              const std::vector<VoxelClass>& classes, uint32_t min_n);

/** Rule 6, ramps by region (docs/perceive.md): the judged voxels (N_z >=
 *  d_min, flat within the noise, not near depth_max) are grown, nearest the
 *  robot first, into connected regions whose voxel means share one plane
 *  within noise_k sqrt(se^2 + region_tolerance^2); border cells then move to
 *  the neighbouring region whose plane fits them better. A region whose
 *  slope fit (weighted, its cells away from its border, trimmed at
 *  region_trim_k standard errors) holds at least region_min_cells cells is
 *  judged (its border: other regions and voxels not judged, not the voxels
 *  near depth_max):
 *  steep when its angle to the floor's plane (the first judged region,
 *  nearest the robot, if level within the mounting's tilt uncertainty and
 *  its plane at z = 0 under the sensor, else `ref`) plus noise_k standard
 *  errors exceeds max_slope_deg (its ground voxels become obstacles),
 *  gentle otherwise. A region the trimmed fit cannot judge (a ramp seen
 *  over a few rows at the end of the view) is judged by the plain fit over
 *  all its cells when that is one plane within the noise and can tell level
 *  from max_slope_deg: steep by the same test, never gentle.
 *  Gentle regions reached from the floor's region through borders without
 *  a step (and the floor's region itself) get their
 *  obstacle voxels that pass rules 1-2 against the region's own plane, with
 *  the noise about that plane, back as ground, and so do the voxels no
 *  judged region holds (near depth_max, not flat within the level-floor
 *  model, in regions too small to judge) connected to such a region (not
 *  the floor's) through voxels near depth_max or ground voxels, against its
 *  plane or a level-off of it (a landing). `decided` (one per cell) is set to 2
 *  on the voxels of steep regions and to 1 on those of gentle regions
 *  farther from the region's border than a max_slope_deg kink stays in the
 *  growth band (nearer ones keep rule 4's window: the first cells of a
 *  steep ramp may have joined the floor's region). `thr` and
 *  `se`: per cell the rule-1 threshold and the standard error of the mean. */
struct RegionCounts {
  size_t steep = 0, rescued = 0, steps = 0;
  bool floor = false;        ///< the floor's plane is a judged region's (else `ref`)
  SlopeReference floor_ref;  ///< that region's gradient (per cell) and its variance
};
RegionCounts judgeSlopeRegions(const ElevationGrid& g, const PerceptionParams& p, const Point3f& o,
                               const SlopeReference& ref, const std::vector<float>& thr,
                               const std::vector<float>& se, std::vector<VoxelClass>& classes,
                               std::vector<uint8_t>& decided);

/** Rule 4 (markSteepGround()); `gentle` (one per cell, when given) is set
 *  to 1 on the ground voxels that kept a slope verdict of at most
 *  max_slope_deg: inside a gentle region (decided 1), or whose window's fit
 *  reads no steeper than that. */
size_t markSteepWindows(const ElevationGrid& g, const Plane& plane, const PerceptionParams& p,
                        const Point3f* o, std::vector<VoxelClass>& classes,
                        const std::vector<uint8_t>* decided, std::vector<uint8_t>* gentle,
                        const SlopeReference* ref = nullptr);

/** Calls f(i, j, q) for each of the 4 neighbours (i, j) of cell k of g that lie inside it,
 *  q = i * m + j its index: the step of the grid's flood fills. */
template <class F>
void forEachNeighbour4(const ElevationGrid& g, int32_t k, F&& f) {
  const int m = g.cells(), i = k / m, j = k % m;
  const int nbs[4][2] = {{i - 1, j}, {i + 1, j}, {i, j - 1}, {i, j + 1}};
  for (const auto& b : nbs)
    if (g.inside(b[0], b[1])) f(b[0], b[1], static_cast<int32_t>(b[0] * m + b[1]));
}

}  // namespace carenav::perception
