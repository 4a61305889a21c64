// Virtual 2D scans from depth (docs/design.md, 'Virtual scans'): FSPF+ plane filtering
// ([InterbotDepth, Alg. 3]), Kinect Obstacle Scan ([InterbotDepth, Alg. 7]), HOBBIT's max-rule
// localisation scan ([Puente14, App. Sec. IV-A]) and MRPT's convertTo2DScan baseline.
#pragma once

#include <carenav/perception/cloud.h>
#include <carenav/perception/perception_params.h>

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>

#include <cstdint>
#include <vector>

namespace carenav::perception {

enum class PlaneClass : uint8_t { None = 0, Ground, Ceiling, LeftWall, RightWall, Front, Other };
const char* planeClassName(PlaneClass c);

struct FspfResult {
  std::vector<PlaneClass> pixel_class;  ///< per pixel of the organised cloud
  Cloud filtered;                       ///< plane points kept (ground and ceiling dropped)
  int planes = 0, planes_dropped = 0, iterations = 0;
  size_t eligible = 0;
};

/** FSPF+ on an organised robot-frame cloud whose sensor sits at
 *  `sensor_origin` (robot frame; depth is the distance to it). carenav's
 *  decision (docs/design.md, 'Virtual scans'): pointsLeft starts at the number of eligible pixels,
 * which are kept in a list (no rejection sampling). Plane classes from the normal and centroid in
 * the robot frame: horizontal planes within 0.1 m of the floor are ground, above the sensor
 * ceiling, other horizontal planes "other" (kept: table tops); vertical planes front / left / right
 * wall. An unorganised cloud gives an empty result. Deterministic for params.seed. Working
 * buffers are kept per thread between calls (no allocation per frame but the result's);
 * src/fspf_plus.cpp. */
FspfResult fspfPlus(const Cloud& robot_frame, const Point3f& sensor_origin,
                    const PerceptionParams& p);

/** Scan of `n` bins over 360 degrees in the robot frame (sensor pose z =
 *  height); ranges <= 0 are invalid. */
mrpt::obs::CObservation2DRangeScan makeScan(const std::vector<float>& ranges, double height,
                                            double max_range, const std::string& label);

/** Kinect Obstacle Scan: points within +-kos_band of each kos_heights level,
 *  minimum range per bearing bin; levels merged by the minimum. Computed in one vectorised pass
 *  over the points for all levels, with the bins and ranges of the per-level definition. */
mrpt::obs::CObservation2DRangeScan kinectObstacleScan(const Cloud& robot_frame,
                                                      const PerceptionParams& p);

/** HOBBIT's localisation scan: points in a maxrule_slab slab around
 *  maxrule_height, **maximum** range per bearing bin (walls bound the room). */
mrpt::obs::CObservation2DRangeScan maxRuleScan(const Cloud& robot_frame, const PerceptionParams& p);

/** MRPT's CObservation3DRangeScan::convertTo2DScan with the points projected
 *  from the robot origin and kept in band_z_min..band_z_max. */
mrpt::obs::CObservation2DRangeScan mrptConvertTo2DScan(mrpt::obs::CObservation3DRangeScan& obs,
                                                       const PerceptionParams& p);

}  // namespace carenav::perception
