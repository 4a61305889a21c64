// The likelihood field of an occupancy grid (Thrun, Burgard, Fox 2005, sec.
// 6.4), tabled once for the whole map: log p of a scan point per cell.
#pragma once

#include <carenav/localization/localization_params.h>

#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/obs/CObservation2DRangeScan.h>

#include <vector>

namespace carenav::localization {

/** MRPT's lmLikelihoodField_Thrun model with the lf_* parameters (see
 *  COccupancyGridMap2D::computeObservationLikelihood), the same values from a
 *  table built by one exact distance transform of the grid. */
class LikelihoodField {
 public:
  LikelihoodField() = default;
  LikelihoodField(const mrpt::maps::COccupancyGridMap2D& map, const LocalizationParams& params);

  /** The scan's points in the robot frame, as MRPT's likelihood field takes
   *  them (its points map of the scan: points closer than half a cell to the
   *  previous one dropped), every lf_decimation-th (every one under 10 points;
   *  every `every`-th when `every` > 0). */
  void scanPoints(const mrpt::obs::CObservation2DRangeScan& scan, std::vector<float>& xs,
                  std::vector<float>& ys, int every = 0) const;
  /** Sum of the logs of the points (robot frame) seen from pose (x, y, phi);
   *  -100 without points, as MRPT. */
  double logLikelihood(const std::vector<float>& xs, const std::vector<float>& ys, double x,
                       double y, double phi) const;

 private:
  std::vector<double> log_;  // log p of a point per cell (x + y * sx_)
  double far_ = 0;           // log p of a point off the map or beyond lf_max_corr_dist
  int sx_ = 0, sy_ = 0;
  double xmin_ = 0, ymin_ = 0, res_ = 1;
  float horizontal_tolerance_ = 0;  // of the map's insertion options
  int decimation_ = 1;
};

}  // namespace carenav::localization
