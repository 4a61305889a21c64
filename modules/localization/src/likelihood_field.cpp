#include <carenav/common/distance_transform.h>
#include <carenav/localization/likelihood_field.h>

#include <mrpt/maps/CPointsMap.h>

#include <algorithm>
#include <cmath>

namespace carenav::localization {

using mrpt::maps::COccupancyGridMap2D;

namespace {

/** Squared distance (in cells²) from every cell of the grid to the nearest
 *  occupied one (free probability below 0.5). */
std::vector<double> squaredDistances(const COccupancyGridMap2D& map, int sx, int sy) {
  const size_t cells = size_t(sx) * size_t(sy);
  std::vector<uint8_t> source(cells);
  const auto occupied = COccupancyGridMap2D::p2l(0.5f);
  const auto& raw = map.getRawMap();
  for (size_t k = 0; k < cells; ++k) source[k] = raw[k] < occupied ? 0 : 1;
  return squaredDistanceTransform(source, sx, sy);
}

}  // namespace

// The likelihood field of Thrun, Burgard, Fox, "Probabilistic Robotics"
// (2005), sec. 6.4, table 6.3, in the form MRPT's COccupancyGridMap2D uses for
// lmLikelihoodField_Thrun: a point that falls in a cell at distance d from the
// nearest occupied cell (free probability below 0.5; d capped at
// lf_max_corr_dist) has likelihood z_random / max_range + z_hit exp(-d^2 / (2
// sigma^2)), a scan the sum of the logs over every lf_decimation-th point.
// MRPT searches a window around every cell the first time a point falls there;
// here the logs for the whole grid come from one exact distance transform
// (rows, then columns) when the field is built, and a particle costs one
// sin/cos and a table look-up per point.
LikelihoodField::LikelihoodField(const COccupancyGridMap2D& map, const LocalizationParams& p)
    : sx_(static_cast<int>(map.getSizeX())),
      sy_(static_cast<int>(map.getSizeY())),
      xmin_(map.getXMin()),
      ymin_(map.getYMin()),
      res_(map.getResolution()),
      horizontal_tolerance_(map.insertionOptions.horizontalTolerance),
      decimation_(p.lf_decimation) {
  // The same constants, in the same precision, as MRPT's
  // COccupancyGridMap2D::computeLikelihoodField_Thrun, so that the table
  // holds the very logs MRPT sums.
  const float std_hit = static_cast<float>(p.lf_sigma);
  const float z_hit = static_cast<float>(p.lf_z_hit);
  const float z_random_term =
      static_cast<float>(p.lf_z_random) / static_cast<float>(p.lf_max_range);
  const float q = -0.5f / (std_hit * std_hit);
  const float max_corr = static_cast<float>(p.lf_max_corr_dist);
  const double max_corr_sq = max_corr * max_corr;
  far_ = std::log(z_random_term + z_hit * std::exp(q * max_corr_sq));
  // Squared distances in MRPT's integer units: 100 per squared cell.
  const double units = 100 / (res_ * res_);
  const double cap = std::round(max_corr_sq * units);
  const std::vector<double> g = squaredDistances(map, sx_, sy_);
  log_.assign(g.size(), far_);
  for (int cy = 0; cy + 1 < sy_; ++cy)  // the last row and column count as off the map (as in MRPT)
    for (int cx = 0; cx + 1 < sx_; ++cx) {
      const size_t k = cx + size_t(cy) * sx_;
      const auto dist_units = static_cast<unsigned>(std::min(cap, 100 * g[k]));
      const float dist_sq = static_cast<float>(dist_units / units);
      const double lik = z_random_term + z_hit * std::exp(q * dist_sq);
      log_[k] = std::log(lik);
    }
}

void LikelihoodField::scanPoints(const mrpt::obs::CObservation2DRangeScan& scan,
                                 std::vector<float>& xs, std::vector<float>& ys, int every) const {
  xs.clear();
  ys.clear();
  mrpt::maps::CPointsMap::TInsertionOptions opts;
  opts.minDistBetweenLaserPoints = static_cast<float>(res_ * 0.5f);
  opts.isPlanarMap = true;
  opts.horizontalTolerance = horizontal_tolerance_;
  const auto* pm = scan.buildAuxPointsMap<mrpt::maps::CPointsMap>(&opts);
  if (!pm) return;
  const size_t n = pm->size();
  const size_t step = every > 0 ? static_cast<size_t>(every)
                      : n < 10  ? 1
                                : static_cast<size_t>(std::max(1, decimation_));
  const auto& px = pm->getPointsBufferRef_x();
  const auto& py = pm->getPointsBufferRef_y();
  for (size_t j = 0; j < n; j += step) {
    xs.push_back(px[j]);
    ys.push_back(py[j]);
  }
}

double LikelihoodField::logLikelihood(const std::vector<float>& xs, const std::vector<float>& ys,
                                      double x, double y, double phi) const {
  if (xs.empty()) return -100;  // as MRPT: no point, no information
  const double c = std::cos(phi), s = std::sin(phi);
  const unsigned sx1 = static_cast<unsigned>(sx_ - 1), sy1 = static_cast<unsigned>(sy_ - 1);
  const double* table = log_.data();
  double sum = 0;
  for (size_t j = 0; j < xs.size(); ++j) {
    const double gx = x + xs[j] * c - ys[j] * s;
    const double gy = y + xs[j] * s + ys[j] * c;
    const int cx = static_cast<int>((gx - xmin_) / res_);
    const int cy = static_cast<int>((gy - ymin_) / res_);
    sum += (static_cast<unsigned>(cx) >= sx1 || static_cast<unsigned>(cy) >= sy1)
               ? far_
               : table[cx + static_cast<size_t>(cy) * sx_];
  }
  return sum;
}

}  // namespace carenav::localization
