#include <carenav/localization/likelihood_field.h>

#include <mrpt/maps/CPointsMap.h>

#include <algorithm>
#include <cmath>

namespace carenav::localization {

using mrpt::maps::COccupancyGridMap2D;

namespace {

constexpr double kDtInf = 1e20;

/** One-dimensional squared Euclidean distance transform of f over n samples
 *  (lower envelope of the parabolas (q - p)^2 + f(p)): Felzenszwalb,
 *  Huttenlocher 2012, "Distance Transforms of Sampled Functions", Theory of
 *  Computing 8, sec. 2.1, algorithm DT(f). v (n) and z (n + 1) are scratch. */
void distanceTransform1d(const double* f, int n, double* d, int* v, double* z) {
  int k = 0;
  v[0] = 0;
  z[0] = -kDtInf;
  z[1] = kDtInf;
  for (int q = 1; q < n; ++q) {
    // z[0] = -inf stops the loop at k = 0 (f is at most kDtInf, so s > -kDtInf)
    auto cross = [&](int r) {
      return ((f[q] + double(q) * q) - (f[r] + double(r) * r)) / (2.0 * (q - r));
    };
    double s = cross(v[k]);
    while (s <= z[k]) s = cross(v[--k]);
    ++k;
    v[k] = q;
    z[k] = s;
    z[k + 1] = kDtInf;
  }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while (z[k + 1] < q) ++k;
    const double dq = q - v[k];
    d[q] = dq * dq + f[v[k]];
  }
}

/** Squared distance (in cells²) from every cell of the grid to the nearest
 *  occupied one (free probability below 0.5): rows, then columns. */
std::vector<double> squaredDistances(const COccupancyGridMap2D& map, int sx, int sy) {
  const size_t cells = size_t(sx) * size_t(sy);
  std::vector<double> g(cells);
  const auto occupied = COccupancyGridMap2D::p2l(0.5f);
  const auto& raw = map.getRawMap();
  for (size_t k = 0; k < cells; ++k) g[k] = raw[k] < occupied ? 0.0 : kDtInf;
  const int longest = std::max(sx, sy);
  std::vector<double> f(longest), d(longest), z(longest + 1);
  std::vector<int> v(longest);
  for (int cy = 0; cy < sy; ++cy) {  // along x
    double* row = g.data() + size_t(cy) * sx;
    std::copy(row, row + sx, f.begin());
    distanceTransform1d(f.data(), sx, row, v.data(), z.data());
  }
  for (int cx = 0; cx < sx; ++cx) {  // along y
    for (int cy = 0; cy < sy; ++cy) f[cy] = g[cx + size_t(cy) * sx];
    distanceTransform1d(f.data(), sy, d.data(), v.data(), z.data());
    for (int cy = 0; cy < sy; ++cy) g[cx + size_t(cy) * sx] = d[cy];
  }
  return g;
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
                                 std::vector<float>& xs, std::vector<float>& ys) const {
  xs.clear();
  ys.clear();
  mrpt::maps::CPointsMap::TInsertionOptions opts;
  opts.minDistBetweenLaserPoints = static_cast<float>(res_ * 0.5f);
  opts.isPlanarMap = true;
  opts.horizontalTolerance = horizontal_tolerance_;
  const auto* pm = scan.buildAuxPointsMap<mrpt::maps::CPointsMap>(&opts);
  if (!pm) return;
  const size_t n = pm->size();
  const size_t step = n < 10 ? 1 : static_cast<size_t>(std::max(1, decimation_));
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
