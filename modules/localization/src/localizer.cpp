#include <carenav/common/errors.h>
#include <carenav/localization/localizer.h>

#include <mrpt/bayes/CParticleFilter.h>
#include <mrpt/core/bits_math.h>
#include <mrpt/maps/CPointsMap.h>
#include <mrpt/math/distributions.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/poses/CPosePDFGaussian.h>
#include <mrpt/random/RandomGenerators.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace carenav::localization {

using mrpt::maps::COccupancyGridMap2D;
using mrpt::poses::CPose2D;

namespace {

double logSumExp(double a, double b) {
  const double m = std::max(a, b);
  if (m == -std::numeric_limits<double>::infinity()) return m;
  return m + std::log(std::exp(a - m) + std::exp(b - m));
}

/** log sum_i exp(a_i + b_i) (b empty: log sum_i exp(a_i)), one exp per term. */
double logSumExp(const std::vector<double>& a, const std::vector<double>& b = {}) {
  const auto term = [&](size_t i) { return b.empty() ? a[i] : a[i] + b[i]; };
  double m = -std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < a.size(); ++i) m = std::max(m, term(i));
  if (m == -std::numeric_limits<double>::infinity()) return m;
  double s = 0;
  for (size_t i = 0; i < a.size(); ++i) s += std::exp(term(i) - m);
  return m + std::log(s);
}

/** ESS ratio (Kong 1992: ESS = (sum w)^2 / sum w^2, over n) of the weights
 *  exp(a_i + beta l_i). */
double essRatio(const std::vector<double>& a, const std::vector<double>& l, double beta) {
  double m = -std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < a.size(); ++i) m = std::max(m, a[i] + beta * l[i]);
  double s = 0, s2 = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const double w = std::exp(a[i] + beta * l[i] - m);
    s += w;
    s2 += w * w;
  }
  return s2 > 0 ? s * s / s2 / static_cast<double>(a.size()) : 0;
}

/** Tempered (power) likelihood p(z|x)^beta: the largest beta in
 *  [beta_min, 1] whose updated weights keep an ESS ratio of at least
 *  share * ESS(prior), as adaptive tempering in sequential Monte Carlo does
 *  (Jasra, Stephens, Doucet, Tsagaris 2011, "Inference for Levy-driven
 *  stochastic volatility models via adaptive sequential Monte Carlo", sec.
 *  3.2: the next temperature solves ESS(beta) = target; found here by
 *  bisection on log beta). share 0: no tempering (beta 1). */
double temperingExponent(const std::vector<double>& a, const std::vector<double>& l, double share,
                         double beta_min) {
  if (share <= 0 || a.empty()) return 1;
  const double target = share * essRatio(a, l, 0);
  if (essRatio(a, l, 1) >= target) return 1;
  if (essRatio(a, l, beta_min) < target) return beta_min;
  double lo = std::log(beta_min), hi = 0;  // ESS(exp(lo)) >= target > ESS(exp(hi))
  for (int it = 0; it < 14; ++it) {
    const double mid = 0.5 * (lo + hi);
    (essRatio(a, l, std::exp(mid)) >= target ? lo : hi) = mid;
  }
  return std::exp(lo);
}

mrpt::bayes::CParticleFilter::TParticleFilterOptions filterOptions(const LocalizationParams& p) {
  mrpt::bayes::CParticleFilter::TParticleFilterOptions o;
  o.PF_algorithm = mrpt::bayes::CParticleFilter::pfStandardProposal;
  // MRPT's KLD sampling only draws with the multinomial method.
  o.resamplingMethod = mrpt::bayes::CParticleFilter::prMultinomial;
  o.adaptiveSampleSize = true;
  o.BETA = p.resample_ess;
  return o;
}

}  // namespace

Localizer::Localizer(const COccupancyGridMap2D& map, const LocalizationParams& params)
    : p_(params), map_(std::make_shared<COccupancyGridMap2D>(map)) {
  // The likelihood field of the grid is what weighs the particles.
  auto& lo = map_->likelihoodOptions;
  lo.likelihoodMethod = COccupancyGridMap2D::lmLikelihoodField_Thrun;
  lo.LF_stdHit = static_cast<float>(p_.lf_sigma);
  lo.LF_zHit = static_cast<float>(p_.lf_z_hit);
  lo.LF_zRandom = static_cast<float>(p_.lf_z_random);
  lo.LF_maxRange = static_cast<float>(p_.lf_max_range);
  lo.LF_maxCorrsDistance = static_cast<float>(p_.lf_max_corr_dist);
  lo.LF_decimation = static_cast<uint32_t>(p_.lf_decimation);
  lo.enableLikelihoodCache = true;

  const size_t nx = map_->getSizeX(), ny = map_->getSizeY();
  for (size_t cy = 0; cy < ny; ++cy)
    for (size_t cx = 0; cx < nx; ++cx)
      if (map_->getCell(static_cast<int>(cx), static_cast<int>(cy)) > p_.free_threshold)
        free_cells_.push_back(cx + cy * nx);
  if (free_cells_.empty())
    throw InputError("the map has no free cell (free probability above " +
                     std::to_string(p_.free_threshold) + "): nothing to localise in");

  mcl_.options.metricMap = map_;
  buildLikelihoodField();
  mrpt::random::getRandomGenerator().randomize(static_cast<uint32_t>(p_.seed));
}

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

}  // namespace

// The likelihood field of Thrun, Burgard, Fox, "Probabilistic Robotics"
// (2005), sec. 6.4, table 6.3, in the form MRPT's COccupancyGridMap2D uses for
// lmLikelihoodField_Thrun: a point that falls in a cell at distance d from the
// nearest occupied cell (free probability below 0.5; d capped at
// lf_max_corr_dist) has likelihood z_random / max_range + z_hit exp(-d^2 / (2
// sigma^2)), a scan the sum of the logs over every lf_decimation-th point.
// MRPT searches a window around every cell the first time a point falls there;
// here the logs for the whole grid come from one exact distance transform
// (rows, then columns) when the Localizer is built, and a particle costs one
// sin/cos and a table look-up per point.
void Localizer::buildLikelihoodField() {
  const int sx = static_cast<int>(map_->getSizeX()), sy = static_cast<int>(map_->getSizeY());
  lf_sx_ = sx;
  lf_sy_ = sy;
  lf_xmin_ = map_->getXMin();
  lf_ymin_ = map_->getYMin();
  lf_res_ = map_->getResolution();
  // The same constants, in the same precision, as MRPT's
  // COccupancyGridMap2D::computeLikelihoodField_Thrun, so that the table
  // holds the very logs MRPT sums.
  const float std_hit = static_cast<float>(p_.lf_sigma);
  const float z_hit = static_cast<float>(p_.lf_z_hit);
  const float z_random_term =
      static_cast<float>(p_.lf_z_random) / static_cast<float>(p_.lf_max_range);
  const float q = -0.5f / (std_hit * std_hit);
  const float max_corr = static_cast<float>(p_.lf_max_corr_dist);
  const double max_corr_sq = max_corr * max_corr;
  lf_far_ = std::log(z_random_term + z_hit * std::exp(q * max_corr_sq));
  // Squared distances in MRPT's integer units: 100 per squared cell.
  const double res = lf_res_;
  const double units = 100 / (res * res);
  const double cap = std::round(max_corr_sq * units);

  const size_t cells = size_t(sx) * size_t(sy);
  std::vector<double> g(cells);
  const auto occupied = COccupancyGridMap2D::p2l(0.5f);
  const auto& raw = map_->getRawMap();
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
  lf_log_.assign(cells, lf_far_);
  for (int cy = 0; cy + 1 < sy; ++cy)  // the last row and column count as off the map (as in MRPT)
    for (int cx = 0; cx + 1 < sx; ++cx) {
      const size_t k = cx + size_t(cy) * sx;
      const auto dist_units = static_cast<unsigned>(std::min(cap, 100 * g[k]));
      const float dist_sq = static_cast<float>(dist_units / units);
      const double lik = z_random_term + z_hit * std::exp(q * dist_sq);
      lf_log_[k] = std::log(lik);
    }
}

/** The scan's points in the robot frame, as MRPT's likelihood field takes them
 *  (its points map of the scan: points closer than half a cell to the previous
 *  one dropped), every lf_decimation-th (every one under 10 points). */
void Localizer::scanPoints(const mrpt::obs::CObservation2DRangeScan& scan, std::vector<float>& xs,
                           std::vector<float>& ys) const {
  xs.clear();
  ys.clear();
  mrpt::maps::CPointsMap::TInsertionOptions opts;
  opts.minDistBetweenLaserPoints = static_cast<float>(lf_res_ * 0.5f);
  opts.isPlanarMap = true;
  opts.horizontalTolerance = map_->insertionOptions.horizontalTolerance;
  const auto* pm = scan.buildAuxPointsMap<mrpt::maps::CPointsMap>(&opts);
  if (!pm) return;
  const size_t n = pm->size();
  const size_t step = n < 10 ? 1 : static_cast<size_t>(std::max(1, p_.lf_decimation));
  const auto& px = pm->getPointsBufferRef_x();
  const auto& py = pm->getPointsBufferRef_y();
  for (size_t j = 0; j < n; j += step) {
    xs.push_back(px[j]);
    ys.push_back(py[j]);
  }
}

double Localizer::fieldLogLikelihood(const std::vector<float>& xs, const std::vector<float>& ys,
                                     double x, double y, double phi) const {
  if (xs.empty()) return -100;  // as MRPT: no point, no information
  const double c = std::cos(phi), s = std::sin(phi);
  const unsigned sx1 = static_cast<unsigned>(lf_sx_ - 1), sy1 = static_cast<unsigned>(lf_sy_ - 1);
  const double* table = lf_log_.data();
  double sum = 0;
  for (size_t j = 0; j < xs.size(); ++j) {
    const double gx = x + xs[j] * c - ys[j] * s;
    const double gy = y + xs[j] * s + ys[j] * c;
    const int cx = static_cast<int>((gx - lf_xmin_) / lf_res_);
    const int cy = static_cast<int>((gy - lf_ymin_) / lf_res_);
    sum += (static_cast<unsigned>(cx) >= sx1 || static_cast<unsigned>(cy) >= sy1)
               ? lf_far_
               : table[cx + static_cast<size_t>(cy) * lf_sx_];
  }
  return sum;
}

double Localizer::scanLogLikelihood(const mrpt::obs::CObservation2DRangeScan& scan,
                                    const CPose2D& pose) const {
  if (!scan.isPlanarScan(map_->insertionOptions.horizontalTolerance)) return -10;
  std::vector<float> xs, ys;
  scanPoints(scan, xs, ys);
  return fieldLogLikelihood(xs, ys, pose.x(), pose.y(), pose.phi());
}

Localizer::~Localizer() = default;

mrpt::math::TPose2D Localizer::randomPoseIn(const std::vector<size_t>& cells) const {
  auto& rng = mrpt::random::getRandomGenerator();
  const size_t nx = map_->getSizeX();
  const size_t k = cells[rng.drawUniform32bit() % cells.size()];
  const double res = map_->getResolution();
  const double x = map_->idx2x(static_cast<int>(k % nx)) + rng.drawUniform(-0.5, 0.5) * res;
  const double y = map_->idx2y(static_cast<int>(k / nx)) + rng.drawUniform(-0.5, 0.5) * res;
  return {x, y, rng.drawUniform(-M_PI, M_PI)};
}

/** Draws odometry increments from the Gaussian pose change that
 *  CActionRobotMovement2D computes and composes them onto particles, in 2D.
 *  The increment is mean + Z r, Z the covariance's eigenvectors scaled by the
 *  square roots of its eigenvalues and r three standard normal draws: what
 *  MRPT's CPoseRandomSampler draws, in the same order from the same generator
 *  and with the same arithmetic, so a seed gives the same particles. */
struct Localizer::MotionSampler {
  explicit MotionSampler(const mrpt::poses::CPosePDF& pose_change) {
    const auto* g = dynamic_cast<const mrpt::poses::CPosePDFGaussian*>(&pose_change);
    if (!g) throw std::logic_error("Localizer: the motion model must be Gaussian");
    mean = g->mean.asTPose();
    std::vector<double> eig;
    g->cov.eig_symmetric(z, eig);
    for (int i = 0; i < 3; ++i) {
      const double root = std::sqrt(eig[i]);
      for (int d = 0; d < 3; ++d) z(d, i) *= root;
    }
  }
  mrpt::math::TPose2D increment() const {
    auto& rng = mrpt::random::getRandomGenerator();
    double r[3] = {0, 0, 0};
    for (int i = 0; i < 3; ++i) {
      const double n = rng.drawGaussian1D_normalized();
      for (int d = 0; d < 3; ++d) r[d] += z(d, i) * n;
    }
    return {mean.x + r[0], mean.y + r[1], mrpt::math::wrapToPi(mean.phi + r[2])};
  }
  static mrpt::math::TPose2D compose(const mrpt::math::TPose2D& p, const mrpt::math::TPose2D& inc) {
    const double c = std::cos(p.phi), s = std::sin(p.phi);
    return {p.x + c * inc.x - s * inc.y, p.y + s * inc.x + c * inc.y,
            mrpt::math::wrapToPi(p.phi + inc.phi)};
  }
  mrpt::math::TPose2D moved(const mrpt::math::TPose2D& p) const { return compose(p, increment()); }
  mrpt::math::TPose2D mean;
  mrpt::math::CMatrixDouble33 z;
};

// Multinomial draws by weight, the rule of MRPT's
// CParticleFilterCapable::prepareFastDrawSample / fastDrawSample (the draw
// MRPT's KLD-sampling filter makes), computed with the same floating-point
// operations so that a seed still gives the same particles, but with a binary
// search instead of a linear walk: the cumulative weights are cut into
// kBins slices at j / kBins; a draw u in [0, 0.999999) starts at the
// particle that straddles slice j = floor(u (kBins - 0.05)), counts the
// cumulative weight from j / kBins, and takes the first particle where that
// count reaches u.
void Localizer::FastDraw::prepare(const std::vector<double>& log_w) {
  const size_t m = log_w.size();
  pdf.resize(m);
  const double top = *std::max_element(log_w.begin(), log_w.end());
  double sum = 0;
  for (size_t i = 0; i < m; ++i) sum += pdf[i] = std::exp(log_w[i] + -top);
  const double inv = 1.0 / sum;
  for (double& w : pdf) w *= inv;
  // The particle each slice starts at.
  double thresholds[kBins + 1];
  for (size_t j = 0; j < kBins; ++j) thresholds[j] = double(j) / double(kBins);
  thresholds[kBins] = 1.0;
  size_t j = 0;
  double cdf = 0;
  for (size_t i = 0; i < m && j < kBins; ++i) {
    double next = cdf + pdf[i];
    if (i == m - 1) next = 1.0;
    if (next > 1.0) next = 1.0;
    while (thresholds[j] < next) start[j++] = i;
    cdf = next;
  }
  for (; j < kBins; ++j) start[j] = m - 1;
  // Per slice, the counts a draw compares with: from j / kBins, adding the
  // weights from the slice's particle on, up to the largest draw of the slice.
  for (j = 0; j < kBins; ++j) {
    auto& acc = counts[j];
    acc.clear();
    const double last = std::min(0.999999, double(j + 1) / (double(kBins) - 0.05));
    double c = thresholds[j];
    for (size_t i = start[j]; i < m; ++i) {
      c += pdf[i];
      acc.push_back(c);
      if (c >= last) break;
    }
  }
}

size_t Localizer::FastDraw::draw(double u) const {
  const size_t j = static_cast<size_t>(std::floor(u * (double(kBins) - 0.05)));
  const auto& acc = counts[j];
  const size_t k = static_cast<size_t>(std::lower_bound(acc.begin(), acc.end(), u) - acc.begin());
  return std::min(start[j] + k, pdf.size() - 1);
}

// KLD-sampling (Fox 2003, "Adapting the sample size in particle filters
// through KLD-sampling", IJRR 22(12), table 1): particles are drawn by weight
// and moved one at a time until their number reaches n(k) = (k - 1) / (2
// epsilon) chi^2_{k-1, 1-delta}, k the number of occupied bins of kld_bin_xy x
// kld_bin_xy x kld_bin_phi, and at least n_min, at most particles_max. The
// drawn particles start with equal weights. The draws are those of MRPT's
// CMonteCarloLocalization2D with KLD (same order from the same generator), so
// a seed gives the particles it gave when MRPT ran the whole filter.
void Localizer::drawKld(const MotionSampler& motion, size_t n_min) {
  auto& parts = mcl_.m_particles;
  if (parts.empty()) return;
  log_w_.resize(parts.size());
  for (size_t i = 0; i < parts.size(); ++i) log_w_[i] = parts[i].log_w;
  fast_draw_.prepare(log_w_);
  auto& rng = mrpt::random::getRandomGenerator();
  const size_t n_max = static_cast<size_t>(std::max(1, p_.particles_max));
  const double delta_1 = 1 - p_.kld_delta, epsilon_1 = 0.5 / p_.kld_epsilon;
  const double bin_xy = p_.kld_bin_xy, bin_phi = mrpt::DEG2RAD(p_.kld_bin_phi);
  drawn_.clear();
  // Occupied KLD bins: open addressing, at most n_max keys in twice the slots.
  constexpr uint64_t kEmpty = ~uint64_t(0);  // no key is all ones
  int bits = 4;
  while ((size_t(1) << bits) < 2 * n_max) ++bits;
  bins_.assign(size_t(1) << bits, kEmpty);
  const uint64_t mask = (uint64_t(1) << bits) - 1;
  size_t occupied = 0;
  const auto insert = [&](uint64_t key) {  // true when the bin was empty
    for (uint64_t h = (key * 0x9E3779B97F4A7C15ull) >> (64 - bits);; h = (h + 1) & mask) {
      if (bins_[h] == key) return false;
      if (bins_[h] == kEmpty) {
        bins_[h] = key;
        ++occupied;
        return true;
      }
    }
  };
  size_t nx = n_min;
  do {
    const auto inc = motion.increment();
    const auto pose =
        MotionSampler::compose(parts[fast_draw_.draw(rng.drawUniform(0.0, 0.999999))].d, inc);
    drawn_.push_back(pose);
    // Bin key: x and y bins in 22 bits each, heading bin in 20.
    const auto bin = [](double v, double size, int64_t half) {
      const int64_t b = mrpt::round(v / size);
      return static_cast<uint64_t>(std::clamp<int64_t>(b, -half + 1, half - 1) + half);
    };
    const uint64_t key = bin(pose.x, bin_xy, int64_t(1) << 21) << 42 |
                         bin(pose.y, bin_xy, int64_t(1) << 21) << 20 |
                         bin(pose.phi, bin_phi, int64_t(1) << 19);
    if (insert(key) && occupied > 1)
      nx = static_cast<size_t>(mrpt::round(
          epsilon_1 * mrpt::math::chi2inv(delta_1, static_cast<unsigned>(occupied - 1))));
  } while (drawn_.size() < std::max(nx, n_min) && drawn_.size() < n_max);
  parts.resize(drawn_.size());
  for (size_t i = 0; i < drawn_.size(); ++i) {
    parts[i].d = drawn_[i];
    parts[i].log_w = 0;
  }
}

// ESS ratio of the particle weights and their normalisation to a largest log
// weight of 0, computed as MRPT's CParticleFilterDataImpl::ESS and
// normalizeWeights do (same operations in the same order, so the same
// values), without their per-element dynamic_cast.
double Localizer::effectiveSampleRatio() const {
  const auto& parts = mcl_.m_particles;
  double sum = 0;
  for (const auto& part : parts) sum += std::exp(part.log_w);
  double cum = 0;
  for (const auto& part : parts) cum += mrpt::square(std::exp(part.log_w) / sum);
  return cum == 0 ? 0 : 1.0 / (parts.size() * cum);
}

void Localizer::normalizeWeights() {
  auto& parts = mcl_.m_particles;
  if (parts.empty()) return;
  double top = parts.front().log_w;
  for (const auto& part : parts) top = std::max(top, part.log_w);
  for (auto& part : parts) part.log_w -= top;
}

void Localizer::initPose(const CPose2D& pose, double std_x, double std_y, double std_phi) {
  std::ostringstream where;
  where << "initial pose (" << pose.x() << ", " << pose.y() << ")";
  if (pose.x() < map_->getXMin() || pose.x() >= map_->getXMax() || pose.y() < map_->getYMin() ||
      pose.y() >= map_->getYMax()) {
    where << " is outside the map [" << map_->getXMin() << ", " << map_->getXMax() << "] x ["
          << map_->getYMin() << ", " << map_->getYMax() << "]";
    throw InputError(where.str());
  }
  if (map_->getPos(pose.x(), pose.y()) < 0.5f - 1e-3f) {
    where << " lies on an occupied cell of the map";
    throw InputError(where.str());
  }
  auto& rng = mrpt::random::getRandomGenerator();
  mcl_.m_particles.resize(static_cast<size_t>(p_.particles_max));
  for (auto& part : mcl_.m_particles) {
    // One draw per statement: the order of a call's arguments is the
    // compiler's choice (gcc: last first; clang: first first), and a seeded
    // run must not depend on it. This is gcc's order, which the seeded
    // tests against MRPT's filter (built by gcc) were written with.
    const double dphi = rng.drawGaussian1D(0, std_phi);
    const double dy = rng.drawGaussian1D(0, std_y);
    const double dx = rng.drawGaussian1D(0, std_x);
    part.d =
        mrpt::math::TPose2D(pose.x() + dx, pose.y() + dy, mrpt::math::wrapToPi(pose.phi() + dphi));
    part.log_w = 0;
  }
  initialised_ = true;
  global_n_ = 0;
  resetTracking();
  refreshEstimate();
  // A pose given with a tight spread counts as converged from the start, so
  // that a wrong one shows up as a loss.
  converged_ = ever_converged_ = spread_ < p_.converged_spread;
}

void Localizer::initGlobal() { initUniform(free_cells_); }

void Localizer::initInRegion(const std::function<bool(double, double)>& inside,
                             const std::string& what) {
  const size_t nx = map_->getSizeX();
  std::vector<size_t> cells;
  for (size_t k : free_cells_)
    if (inside(map_->idx2x(static_cast<int>(k % nx)), map_->idx2y(static_cast<int>(k / nx))))
      cells.push_back(k);
  if (cells.empty()) throw InputError(what + " contains no free cell of the map");
  initUniform(cells);
}

void Localizer::initUniform(const std::vector<size_t>& cells) {
  const size_t n = static_cast<size_t>(std::min(p_.global_particles, p_.particles_max));
  mcl_.m_particles.resize(n);
  for (auto& part : mcl_.m_particles) {
    part.d = randomPoseIn(cells);
    part.log_w = 0;
  }
  initialised_ = true;
  global_n_ = n;
  resetTracking();
  refreshEstimate();
  converged_ = false;
}

void Localizer::resetTracking() {
  converged_ = ever_converged_ = false;
  pending_ = CPose2D();
  if (rotate_open_) rotate_requests_.back().t_end = last_t_;
  rotate_open_ = false;
  stall_updates_ = 0;
  stall_turn_ = 0;
}

size_t Localizer::globalCount() const {
  return global_n_ > 0 ? global_n_
                       : static_cast<size_t>(std::min(p_.global_particles, p_.particles_max));
}

Localizer::State Localizer::state() const {
  if (converged_) return State::Tracking;
  return ever_converged_ ? State::Lost : State::Converging;
}

// The robot turned `turned_rad` since the previous update, which ended at t.
void Localizer::updateRotateRequest(double turned_rad, double t) {
  if (!p_.rotate_request) return;
  if (converged_) {
    if (rotate_open_) {
      rotate_requests_.back().t_end = t;
      rotate_requests_.back().relocalised = true;
      rotate_open_ = false;
    }
    stall_updates_ = 0;
    stall_turn_ = 0;
    return;
  }
  stall_turn_ += turned_rad;
  const double limit = mrpt::DEG2RAD(p_.rotate_turn);
  if (rotate_open_) {
    // Turned a full rotate_turn since the request and still not converged:
    // the request ends; another may follow after rotate_after_updates.
    if (stall_turn_ >= limit) {
      rotate_requests_.back().t_end = t;
      rotate_open_ = false;
      stall_updates_ = 0;
      stall_turn_ = 0;
    }
    return;
  }
  ++stall_updates_;
  if (stall_turn_ >= limit) {  // the robot is turning by itself: count afresh
    stall_updates_ = 0;
    stall_turn_ = 0;
    return;
  }
  if (stall_updates_ >= static_cast<size_t>(p_.rotate_after_updates)) {
    rotate_open_ = true;
    rotate_requests_.push_back({t, std::nullopt, false});
    stall_turn_ = 0;
  }
}

void Localizer::refreshEstimate() {
  const auto [cov, mean] = mcl_.getCovarianceAndMean();
  cov_ = cov;
  mean_ = mean;
  spread_ = std::sqrt(std::max(0.0, cov_(0, 0) + cov_(1, 1)));
}

CPose2D Localizer::pose() const { return mean_ + pending_; }

size_t Localizer::particleCount() const { return mcl_.m_particles.size(); }

size_t Localizer::inject(double fraction) {
  // The share is taken of the global start's sample size (at least of the
  // current one): a converged set is small (KLD), and a share of it alone
  // would scatter too few random poses over a large map to ever find the
  // robot again. As in AMCL, the set grows by the random particles (KLD
  // shrinks it again once one hypothesis wins).
  const size_t n = mcl_.m_particles.size();
  const size_t cap = static_cast<size_t>(p_.particles_max);
  const size_t k = std::min(
      cap, static_cast<size_t>(std::lround(
               fraction * static_cast<double>(std::max(n, std::min(globalCount(), cap))))));
  if (k == 0) return 0;
  const size_t keep = std::min(n, cap - k);
  // Equal weights first, so that the random particles are neither favoured
  // nor drowned by the weights of the ones they join.
  bool uniform = keep == n;
  for (const auto& part : mcl_.m_particles) uniform = uniform && part.log_w == 0;
  if (!uniform) mcl_.performResampling(filterOptions(p_), keep);
  mcl_.m_particles.resize(keep + k);
  for (size_t i = keep; i < keep + k; ++i) {
    mcl_.m_particles[i].d = randomFreePose();
    mcl_.m_particles[i].log_w = 0;
  }
  return k;
}

StepResult Localizer::step(const CPose2D& odometry,
                           const mrpt::obs::CObservation2DRangeScan::Ptr& scan, double t) {
  if (!initialised_) throw std::logic_error("Localizer::step before initPose/initGlobal");
  pending_ = pending_ + odometry;
  const double moved = std::hypot(pending_.x(), pending_.y());
  const double turned = std::abs(mrpt::RAD2DEG(pending_.phi()));
  const bool every_scan = p_.update_min_d <= 0 && p_.update_min_a <= 0;
  const bool due = !first_update_done_ || every_scan ||
                   (p_.update_min_d > 0 && moved >= p_.update_min_d) ||
                   (p_.update_min_a > 0 && turned >= p_.update_min_a);
  StepResult r;
  last_t_ = t;
  if (due && scan) {
    const auto t0 = std::chrono::steady_clock::now();
    mrpt::obs::CActionRobotMovement2D act;
    mrpt::obs::CActionRobotMovement2D::TMotionModelOptions mm;
    mm.modelSelection = mrpt::obs::CActionRobotMovement2D::mmGaussian;
    // MRPT's model works in metres and radians: std_xy = a1 d + a2 |phi|,
    // std_phi = a3 d + a4 |phi|.
    mm.gaussianModel.a1 = p_.odom_a1;
    mm.gaussianModel.a2 = mrpt::RAD2DEG(p_.odom_a2);
    mm.gaussianModel.a3 = mrpt::DEG2RAD(p_.odom_a3);
    mm.gaussianModel.a4 = p_.odom_a4;
    mm.gaussianModel.minStdXY =
        converged_ ? p_.odom_min_std_xy : std::max(p_.odom_min_std_xy, p_.global_min_std_xy);
    mm.gaussianModel.minStdPHI = mrpt::DEG2RAD(
        converged_ ? p_.odom_min_std_phi : std::max(p_.odom_min_std_phi, p_.global_min_std_phi));
    act.computeFromOdometry(pending_, mm);
    const MotionSampler motion(*act.poseChange);

    // Resampling (KLD draw, which also sets the new sample size) only when
    // the weights have degenerated: ESS ratio below resample_ess (Doucet,
    // Godsill, Andrieu 2000, sec. II.C); otherwise every particle is moved and
    // keeps its weight. While not converged, KLD keeps a share of the global
    // start's particles.
    const CPose2D expected = mean_ + pending_;
    const bool resample = effectiveSampleRatio() < p_.resample_ess;
    auto& prior = prior_;  // log weights before the scan
    prior.clear();
    if (resample) {
      drawKld(motion,
              static_cast<size_t>(
                  converged_ ? p_.particles_min
                             : std::max<double>(p_.particles_min, p_.global_keep * globalCount())));
      prior.assign(mcl_.m_particles.size(), 0.0);
    } else {
      prior.reserve(mcl_.m_particles.size());
      for (auto& part : mcl_.m_particles) {
        part.d = motion.moved(part.d);
        prior.push_back(part.log_w);
      }
    }
    const size_t n = mcl_.m_particles.size();
    auto& ll = ll_;  // log p(z|x) per particle
    ll.resize(n);
    if (!scan->isPlanarScan(map_->insertionOptions.horizontalTolerance)) {
      std::fill(ll.begin(), ll.end(), -10.0);  // as MRPT: a tilted scan says nothing
    } else {
      scanPoints(*scan, pts_x_, pts_y_);
      for (size_t i = 0; i < n; ++i) {
        const auto& d = mcl_.m_particles[i].d;
        ll[i] = fieldLogLikelihood(pts_x_, pts_y_, d.x, d.y, d.phi);
      }
    }
    const double lse_prior = logSumExp(prior);
    for (double& a : prior) a -= lse_prior;  // sum of exp(prior) = 1
    // Mean observation likelihood under the prior weights (untempered), for
    // augmented MCL.
    const double log_w_avg = logSumExp(prior, ll);

    r.beta = converged_ ? 1.0 : temperingExponent(prior, ll, p_.temper_ess, p_.temper_beta_min);
    for (size_t i = 0; i < n; ++i) mcl_.m_particles[i].log_w = prior[i] + r.beta * ll[i];
    normalizeWeights();
    r.resampled = resample;

    if (!averages_set_) {
      log_w_slow_ = log_w_fast_ = log_w_avg;
      averages_set_ = true;
    } else {
      log_w_slow_ =
          logSumExp(std::log1p(-p_.alpha_slow) + log_w_slow_, std::log(p_.alpha_slow) + log_w_avg);
      log_w_fast_ =
          logSumExp(std::log1p(-p_.alpha_fast) + log_w_fast_, std::log(p_.alpha_fast) + log_w_avg);
    }
    r.likelihood_ratio = std::exp(log_w_fast_ - log_w_slow_);
    refreshEstimate();
    // How far the estimate moved beyond what odometry explains.
    const double jump = std::hypot(mean_.x() - expected.x(), mean_.y() - expected.y());
    bool lost_now = false;
    const double turned_rad = std::abs(pending_.phi());
    pending_ = CPose2D();
    first_update_done_ = true;
    ++updates_;

    if (!convergence_time_ && spread_ < p_.converged_spread) convergence_time_ = t;
    if (!converged_ && spread_ < p_.converged_spread) {
      converged_ = true;
      ever_converged_ = true;
      if (!events_.empty() && events_.back().kind == LocalizationEvent::Kind::Loss)
        events_.push_back({LocalizationEvent::Kind::Recovery, t, spread_});
    } else if (converged_ && (spread_ > p_.lost_spread || jump > p_.lost_spread)) {
      // Lost: the cloud spread out, or it jumped (particles injected at
      // another place took over: the old hypothesis was wrong and the new
      // one is a single guess). Either way the filter searches globally again.
      converged_ = false;
      events_.push_back({LocalizationEvent::Kind::Loss, t, std::max(spread_, jump)});
      lost_now = true;
    }

    updateRotateRequest(turned_rad, t);

    if (p_.recovery) {
      const double fraction =
          lost_now ? std::max(p_.lost_inject_fraction, 0.0)
                   : std::min(p_.max_inject_fraction, std::max(0.0, 1 - r.likelihood_ratio));
      r.injected = inject(fraction);
      if (r.injected > 0) {
        ++injections_;
        // As AMCL does: start the averages afresh, or the same drop would
        // keep injecting while the new particles are still being weighed.
        averages_set_ = false;
      }
    }
    r.updated = true;
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  r.pose = pose();
  r.cov = cov_;
  r.particles = particleCount();
  r.spread = spread_;
  if (!r.updated) r.likelihood_ratio = averages_set_ ? std::exp(log_w_fast_ - log_w_slow_) : 1;
  r.rotate_in_place = rotate_open_;
  return r;
}

}  // namespace carenav::localization
