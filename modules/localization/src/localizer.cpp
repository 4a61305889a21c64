#include <carenav/common/errors.h>
#include <carenav/localization/localizer.h>

#include "log_weights.h"
#include "motion_sampler.h"

#include <mrpt/bayes/CParticleFilter.h>
#include <mrpt/core/bits_math.h>
#include <mrpt/math/wrap2pi.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/random/RandomGenerators.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace carenav::localization {

using mrpt::maps::COccupancyGridMap2D;
using mrpt::poses::CPose2D;

namespace {

mrpt::bayes::CParticleFilter::TParticleFilterOptions filterOptions(const LocalizationParams& p) {
  mrpt::bayes::CParticleFilter::TParticleFilterOptions o;
  o.PF_algorithm = mrpt::bayes::CParticleFilter::pfStandardProposal;
  // MRPT's KLD sampling only draws with the multinomial method.
  o.resamplingMethod = mrpt::bayes::CParticleFilter::prMultinomial;
  o.adaptiveSampleSize = true;
  o.BETA = p.resample_ess;
  return o;
}

// MRPT's generator keeps the second value of its last Gaussian pair
// (std::normal_distribution) across randomize(seed): a seeded run would
// depend on how many Gaussians were drawn before it. Its reset() is reached
// through a member pointer named in a derived class.
struct GaussianCache : mrpt::random::CRandomGenerator {
  static void clear(mrpt::random::CRandomGenerator& g) {
    (g.*(&GaussianCache::m_normdistribution)).reset();
  }
};

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
  own_rng_.seed(static_cast<uint32_t>(p_.seed));
  field_ = LikelihoodField(*map_, p_);
  mrpt::random::getRandomGenerator().randomize(static_cast<uint32_t>(p_.seed));
  GaussianCache::clear(mrpt::random::getRandomGenerator());
}

double Localizer::scanLogLikelihood(const mrpt::obs::CObservation2DRangeScan& scan,
                                    const CPose2D& pose) const {
  if (!scan.isPlanarScan(map_->insertionOptions.horizontalTolerance)) return -10;
  std::vector<float> xs, ys;
  field_.scanPoints(scan, xs, ys);
  return field_.logLikelihood(xs, ys, pose.x(), pose.y(), pose.phi());
}

double Localizer::scanAgreement(const mrpt::obs::CObservation2DRangeScan& scan,
                                const CPose2D& pose) const {
  if (!scan.isPlanarScan(map_->insertionOptions.horizontalTolerance)) return 1;
  std::vector<float> xs, ys;
  field_.scanPoints(scan, xs, ys, 1);
  return agreementOf(xs, ys, scan.sensorPose.x(), scan.sensorPose.y(), pose);
}

// True when the segment passes through an occupied cell (free probability
// below 1 - free_threshold); a segment leaving the map contradicts nothing
// beyond it.
bool Localizer::crossesObstacle(double x0, double y0, double x1, double y1) const {
  const double len = std::hypot(x1 - x0, y1 - y0);
  const double step = 0.5 * map_->getResolution();
  const int n = static_cast<int>(std::ceil(len / step));
  const double occupied = 1 - p_.free_threshold;
  const int sx = static_cast<int>(map_->getSizeX()), sy = static_cast<int>(map_->getSizeY());
  for (int i = 0; i <= n; ++i) {
    const double a = n == 0 ? 0 : static_cast<double>(i) / n;
    const int cx = map_->x2idx(x0 + a * (x1 - x0)), cy = map_->y2idx(y0 + a * (y1 - y0));
    if (cx < 0 || cy < 0 || cx >= sx || cy >= sy) return false;
    if (map_->getCell(cx, cy) < occupied) return true;
  }
  return false;
}

// The share of points (robot frame; sensor at sx, sy) whose beam from pose
// reaches to within lf_max_corr_dist of the point without crossing an
// occupied cell: a beam may end short of the map's walls (something not on
// the map), it must not see through them. The first lf_max_corr_dist of a
// beam is not checked either: a map may hold an obstacle where the robot
// now stands (a person mapped there earlier).
double Localizer::agreementOf(const std::vector<float>& xs, const std::vector<float>& ys, double sx,
                              double sy, const CPose2D& pose) const {
  if (xs.empty()) return 1;
  const double c = std::cos(pose.phi()), s = std::sin(pose.phi());
  const double ox = pose.x() + c * sx - s * sy, oy = pose.y() + s * sx + c * sy;
  const double margin = p_.lf_max_corr_dist;
  size_t agree = 0;
  for (size_t i = 0; i < xs.size(); ++i) {
    const double ex = pose.x() + c * xs[i] - s * ys[i], ey = pose.y() + s * xs[i] + c * ys[i];
    const double len = std::hypot(ex - ox, ey - oy);
    if (len <= 2 * margin) {
      ++agree;
      continue;
    }
    const double k0 = margin / len, k1 = (len - margin) / len;
    if (!crossesObstacle(ox + k0 * (ex - ox), oy + k0 * (ey - oy), ox + k1 * (ex - ox),
                         oy + k1 * (ey - oy)))
      ++agree;
  }
  return static_cast<double>(agree) / static_cast<double>(xs.size());
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
  low_updates_ = disagree_updates_ = consistent_updates_ = 0;
  closeChallenge();
  pending_ = CPose2D();
  rotate_.reset(last_t_);
}

size_t Localizer::globalCount() const {
  return global_n_ > 0 ? global_n_
                       : static_cast<size_t>(std::min(p_.global_particles, p_.particles_max));
}

Localizer::State Localizer::state() const {
  if (converged_) return State::Tracking;
  return ever_converged_ ? State::Lost : State::Converging;
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

// The odometry since the last update as MRPT's Gaussian motion model.
MotionSampler Localizer::odometryMotion() const {
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
  return MotionSampler(*act.poseChange);
}

// Resampling (KLD draw, which also sets the new sample size) only when the
// weights have degenerated: ESS ratio below resample_ess (Doucet, Godsill,
// Andrieu 2000, sec. II.C); otherwise every particle is moved and keeps its
// weight. While not converged, KLD keeps a share of the global start's
// particles. prior_: the log weights before the scan.
void Localizer::predict(const MotionSampler& motion, bool resample) {
  prior_.clear();
  if (resample) {
    kld_.draw(mcl_.m_particles, motion, p_,
              static_cast<size_t>(
                  converged_ ? p_.particles_min
                             : std::max<double>(p_.particles_min, p_.global_keep * globalCount())));
    prior_.assign(mcl_.m_particles.size(), 0.0);
  } else {
    prior_.reserve(mcl_.m_particles.size());
    for (auto& part : mcl_.m_particles) {
      part.d = motion.moved(part.d);
      prior_.push_back(part.log_w);
    }
  }
}

// While a challenger runs, the estimate's filter draws from a generator of
// its own (own_rng_), so that the challenger's global search, which draws
// from MRPT's, is the search a loss declared when it opened would have run.
// Every particle is moved by the motion model (the draw MotionSampler makes,
// from own_rng_); below resample_ess the set is first redrawn by systematic
// resampling, same size. Returns whether it resampled.
bool Localizer::predictOwn(const MotionSampler& motion) {
  auto& parts = mcl_.m_particles;
  const bool resample = effectiveSampleRatio() < p_.resample_ess;
  if (resample && !parts.empty()) {
    std::vector<double> cum(parts.size());
    double sum = 0;
    for (size_t i = 0; i < parts.size(); ++i) cum[i] = sum += std::exp(parts[i].log_w);
    const double step = sum / static_cast<double>(parts.size());
    double u = std::uniform_real_distribution<double>(0, step)(own_rng_);
    mrpt::poses::CPosePDFParticles::CParticleList drawn(parts.size());
    size_t j = 0;
    for (auto& part : drawn) {
      while (j + 1 < parts.size() && cum[j] < u) ++j;
      part.d = parts[j].d;
      part.log_w = 0;
      u += step;
    }
    parts.swap(drawn);
  }
  std::normal_distribution<double> normal;
  prior_.clear();
  for (auto& part : parts) {
    double r[3] = {0, 0, 0};
    for (int i = 0; i < 3; ++i) {
      const double n = normal(own_rng_);
      for (int d = 0; d < 3; ++d) r[d] += motion.z(d, i) * n;
    }
    const mrpt::math::TPose2D inc(motion.mean.x + r[0], motion.mean.y + r[1],
                                  mrpt::math::wrapToPi(motion.mean.phi + r[2]));
    part.d = MotionSampler::compose(part.d, inc);
    prior_.push_back(part.log_w);
  }
  return resample;
}

// The scan's points (decimated for the likelihood, all of them for the
// agreement), then ll_ for every particle.
void Localizer::weighScan(const mrpt::obs::CObservation2DRangeScan& scan) {
  scan_planar_ = scan.isPlanarScan(map_->insertionOptions.horizontalTolerance);
  if (!scan_planar_) {
    pts_x_.clear();
    pts_y_.clear();
    all_x_.clear();
    all_y_.clear();
  } else {
    field_.scanPoints(scan, pts_x_, pts_y_);
    field_.scanPoints(scan, all_x_, all_y_, 1);
    sensor_x_ = scan.sensorPose.x();
    sensor_y_ = scan.sensorPose.y();
  }
  weighParticles();
}

// ll_: log p(z|x) per particle of the latest scan (weighScan).
void Localizer::weighParticles() {
  const size_t n = mcl_.m_particles.size();
  ll_.resize(n);
  if (!scan_planar_) {
    std::fill(ll_.begin(), ll_.end(), -10.0);  // as MRPT: a tilted scan says nothing
    return;
  }
  for (size_t i = 0; i < n; ++i) {
    const auto& d = mcl_.m_particles[i].d;
    ll_[i] = field_.logLikelihood(pts_x_, pts_y_, d.x, d.y, d.phi);
  }
}

// The new weights, prior times the (tempered) scan likelihood; returns the
// log of the mean observation likelihood under the prior weights
// (untempered), for augmented MCL.
double Localizer::updateWeights(StepResult& r) {
  const double lse_prior = logSumExp(prior_);
  for (double& a : prior_) a -= lse_prior;  // sum of exp(prior) = 1
  const double log_w_avg = logSumExp(prior_, ll_);
  r.beta = converged_ ? 1.0 : temperingExponent(prior_, ll_, p_.temper_ess, p_.temper_beta_min);
  for (size_t i = 0; i < ll_.size(); ++i) mcl_.m_particles[i].log_w = prior_[i] + r.beta * ll_[i];
  normalizeWeights();
  return log_w_avg;
}

// Augmented MCL's short- and long-term averages of the mean observation
// likelihood ([Thrun05, Table 8.3]), in the log domain.
void Localizer::updateAverages(double log_w_avg) {
  if (!averages_set_) {
    log_w_slow_ = log_w_fast_ = log_w_avg;
    averages_set_ = true;
    return;
  }
  log_w_slow_ =
      logSumExp(std::log1p(-p_.alpha_slow) + log_w_slow_, std::log(p_.alpha_slow) + log_w_avg);
  log_w_fast_ =
      logSumExp(std::log1p(-p_.alpha_fast) + log_w_fast_, std::log(p_.alpha_fast) + log_w_avg);
}

// Convergence, loss and recovery events after an update at t; true when the
// filter was lost just now. jump: how far the estimate moved beyond what
// odometry explains.
bool Localizer::updateConvergence(double jump, double t) {
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
    return true;
  }
  return false;
}

// The recovery guard: the share of random particles after an update that
// found no loss. While the cloud is wide (spread >= converged_spread: a
// global search, no estimate to keep), augmented MCL's 1 - w_fast / w_slow
// (at most max_inject_fraction). While it is tight: nothing when its
// estimate agrees with the scan; max_inject_fraction after recovery_patience
// updates in a row that disagree (w_slow may have learnt a wrong pose's
// level): see restartSearch; augmented MCL's share only after
// recovery_patience updates in a row with w_fast / w_slow below
// recovery_ratio.
double Localizer::guardedFraction(const StepResult& r) {
  const bool tight = spread_ < p_.converged_spread;
  const bool rule = p_.consistent_beams > 0;
  const bool disagrees = rule && r.agreement < p_.consistent_beams;
  low_updates_ = r.likelihood_ratio < p_.recovery_ratio ? low_updates_ + 1 : 0;
  disagree_updates_ = tight && disagrees ? disagree_updates_ + 1 : 0;
  const int patience = std::max(1, p_.recovery_patience);
  const double augmented = std::min(p_.max_inject_fraction, std::max(0.0, 1 - r.likelihood_ratio));
  if (!tight) return augmented;  // no estimate to keep: a global search, plain augmented MCL
  if (rule && !disagrees) return 0;
  return low_updates_ >= patience ? augmented : 0;
}

// A tight cloud whose estimate the map contradicted recovery_patience
// updates in a row: a loss. Its particles are evidence of nothing (they
// would only pull the search back to a look-alike near them), so they give
// way to a global search over the free space, as at a global start.
size_t Localizer::restartSearch() {
  converged_ = false;
  events_.push_back({LocalizationEvent::Kind::Loss, last_t_, spread_});
  const size_t n = globalCount();
  mcl_.m_particles.resize(n);
  for (auto& part : mcl_.m_particles) {
    part.d = randomFreePose();
    part.log_w = 0;
  }
  refreshEstimate();
  return n;
}

void Localizer::recover(bool lost_now, StepResult& r) {
  if (!p_.recovery) return;
  if (p_.challenge)
    recoverChallenged(lost_now, r);
  else
    recoverTight(lost_now, r);
}

// challenge false: augmented MCL's recovery behind the guard above, or
// lost_inject_fraction just after a loss.
void Localizer::recoverTight(bool lost_now, StepResult& r) {
  const double fraction = lost_now ? std::max(p_.lost_inject_fraction, 0.0) : guardedFraction(r);
  const bool contradicted = !lost_now && disagree_updates_ >= std::max(1, p_.recovery_patience);
  r.injected = contradicted ? restartSearch() : inject(fraction);
  if (r.injected > 0) {
    ++injections_;
    low_updates_ = disagree_updates_ = 0;
    // As AMCL does: start the averages afresh, or the same drop would
    // keep injecting while the new particles are still being weighed.
    averages_set_ = false;
  }
}

// challenge true. Not converged (a global search, no estimate to keep):
// augmented MCL as is, lost_inject_fraction just after a loss. Converged: no
// random particle joins the cloud; an estimate is challenged when the map
// contradicts it recovery_patience updates in a row, or when its likelihood
// has been low that long and the map contradicts it now (never while it is
// consistent, whatever the likelihood says).
void Localizer::recoverChallenged(bool lost_now, StepResult& r) {
  if (converged_) {
    countContradictions(r);
    const int patience = std::max(1, p_.recovery_patience);
    if (challenger_.open)
      judgeChallenge();
    else if (disagree_updates_ >= patience || (low_updates_ >= patience && disagree_updates_ > 0))
      r.injected = openChallenge();
    return;
  }
  closeChallenge();
  low_updates_ = disagree_updates_ = consistent_updates_ = 0;
  const double augmented = std::min(p_.max_inject_fraction, std::max(0.0, 1 - r.likelihood_ratio));
  r.injected = inject(lost_now ? std::max(p_.lost_inject_fraction, 0.0) : augmented);
  if (r.injected > 0) {
    ++injections_;
    averages_set_ = false;  // as recoverTight
  }
}

// Consecutive updates of a converged estimate that the map contradicts
// (consistent_beams), whose likelihood is low (recovery_ratio), or neither.
void Localizer::countContradictions(const StepResult& r) {
  const bool disagrees = p_.consistent_beams > 0 && r.agreement < p_.consistent_beams;
  const bool low = r.likelihood_ratio < p_.recovery_ratio;
  low_updates_ = low ? low_updates_ + 1 : 0;
  disagree_updates_ = disagrees ? disagree_updates_ + 1 : 0;
  consistent_updates_ = disagrees || low ? 0 : consistent_updates_ + 1;
}

// A challenger: global_particles random poses over the free space, a global
// search that runs beside the estimate (updateChallenger) until judged.
size_t Localizer::openChallenge() {
  challenger_ = Challenger{};
  challenger_.open = true;
  challenger_.t_open = last_t_;
  const size_t n = globalCount();
  challenger_.particles.resize(n);
  double sx = 0, sy = 0, sxx = 0, syy = 0;
  for (auto& part : challenger_.particles) {
    part.d = randomFreePose();
    part.log_w = 0;
    sx += part.d.x;
    sy += part.d.y;
    sxx += part.d.x * part.d.x;
    syy += part.d.y * part.d.y;
  }
  const double k = static_cast<double>(n);
  challenger_.spread =
      std::sqrt(std::max(0.0, sxx / k - mrpt::square(sx / k) + syy / k - mrpt::square(sy / k)));
  ++challenges_;
  ++injections_;
  low_updates_ = disagree_updates_ = consistent_updates_ = 0;
  return n;
}

// One update of the challenger with the odometry and scan the estimate was
// just updated with, as the filter runs a global search: the global phase
// (tempering, roughening, global_keep) and augmented MCL with its own
// averages until its spread falls below converged_spread, then tracking.
void Localizer::updateChallenger(double tracker_log_w_avg) {
  const CPose2D mean = mean_;
  const auto cov = cov_;
  const double spread = spread_;
  const bool converged = converged_, set = averages_set_;
  const double slow = log_w_slow_, fast = log_w_fast_;
  std::swap(mcl_.m_particles, challenger_.particles);
  converged_ = challenger_.converged;
  averages_set_ = challenger_.averages_set;
  log_w_slow_ = challenger_.log_w_slow;
  log_w_fast_ = challenger_.log_w_fast;
  predict(odometryMotion(), effectiveSampleRatio() < p_.resample_ess);
  weighParticles();
  StepResult ignored;
  const double log_evidence = updateWeights(ignored);
  updateAverages(log_evidence);
  refreshEstimate();
  challenger_.mean = mean_;
  challenger_.spread = spread_;
  challenger_.converged =
      spread_ < p_.converged_spread || (challenger_.converged && spread_ <= p_.lost_spread);
  if (!challenger_.converged &&
      inject(std::min(p_.max_inject_fraction,
                      std::max(0.0, 1 - std::exp(log_w_fast_ - log_w_slow_)))) > 0)
    averages_set_ = false;
  challenger_.averages_set = averages_set_;
  challenger_.log_w_slow = log_w_slow_;
  challenger_.log_w_fast = log_w_fast_;
  std::swap(mcl_.m_particles, challenger_.particles);
  mean_ = mean;
  cov_ = cov;
  spread_ = spread;
  converged_ = converged;
  averages_set_ = set;
  log_w_slow_ = slow;
  log_w_fast_ = fast;
  weighEvidence(log_evidence, tracker_log_w_avg);
}

// While the challenger is one place (spread at most lost_spread: not a search
// over the map, whose best of many random poses may fit a scan the map
// explains poorly better than the right pose does) more than lost_spread
// from the estimate,
// the log Bayes factor of each scan (the log of its mean observation
// likelihood under the challenger minus under the estimate) is kept, the
// latest recovery_patience of them.
void Localizer::weighEvidence(double challenger_log_w_avg, double tracker_log_w_avg) {
  const double apart =
      std::hypot(challenger_.mean.x() - mean_.x(), challenger_.mean.y() - mean_.y());
  if (challenger_.spread <= p_.lost_spread && apart > p_.lost_spread) {
    ++challenger_.away;
    challenger_.log_factors.push_back(challenger_log_w_avg - tracker_log_w_avg);
    if (challenger_.log_factors.size() > static_cast<size_t>(std::max(1, p_.recovery_patience)))
      challenger_.log_factors.pop_front();
  } else {
    challenger_.away = 0;
    challenger_.log_factors.clear();
  }
}

// One place away from the estimate for recovery_patience updates and the
// scans of those updates likelier under the challenger (a Bayes factor above
// 1): the estimate is lost and the challenger takes over. A converged one
// that does not win then (a look-alike that explains less), or that
// converged on the estimate, is dropped; so is one still searching once the
// estimate has been consistent again for recovery_patience updates.
void Localizer::judgeChallenge() {
  const int patience = std::max(1, p_.recovery_patience);
  double log_factor = 0;
  for (double f : challenger_.log_factors) log_factor += f;
  if (challenger_.away >= patience && log_factor > 0)
    adoptChallenger();
  else if (challenger_.converged && (challenger_.away == 0 || challenger_.away >= patience))
    closeChallenge();
  else if (!challenger_.converged && consistent_updates_ >= patience)
    closeChallenge();
}

// The estimate was wrong: a loss now. The challenger's cloud is the filter
// from here (once converged, an update reports the recovery).
void Localizer::adoptChallenger() {
  events_.push_back({LocalizationEvent::Kind::Loss, last_t_, spread_});
  std::swap(mcl_.m_particles, challenger_.particles);
  refreshEstimate();
  converged_ = false;
  ++challenges_won_;
  // The challenger's averages go with it: the filter goes on as the global
  // search it was.
  averages_set_ = challenger_.averages_set;
  log_w_slow_ = challenger_.log_w_slow;
  log_w_fast_ = challenger_.log_w_fast;
  closeChallenge();
  low_updates_ = disagree_updates_ = consistent_updates_ = 0;
}

void Localizer::closeChallenge() { challenger_ = Challenger{}; }

void Localizer::filterUpdate(const mrpt::obs::CObservation2DRangeScan& scan, double t,
                             StepResult& r) {
  const auto t0 = std::chrono::steady_clock::now();
  const MotionSampler motion = odometryMotion();
  const CPose2D expected = mean_ + pending_;
  bool resample = false;
  if (challenger_.open) {
    resample = predictOwn(motion);
  } else {
    resample = effectiveSampleRatio() < p_.resample_ess;
    predict(motion, resample);
  }
  weighScan(scan);
  const double log_w_avg = updateWeights(r);
  r.resampled = resample;
  updateAverages(log_w_avg);
  r.likelihood_ratio = std::exp(log_w_fast_ - log_w_slow_);
  refreshEstimate();
  r.agreement = agreementOf(all_x_, all_y_, sensor_x_, sensor_y_, mean_);
  const double jump = std::hypot(mean_.x() - expected.x(), mean_.y() - expected.y());
  if (challenger_.open) updateChallenger(log_w_avg);
  const double turned_rad = std::abs(pending_.phi());
  pending_ = CPose2D();
  first_update_done_ = true;
  ++updates_;
  const bool lost_now = updateConvergence(jump, t);
  rotate_.update(converged_, turned_rad, t, p_);
  recover(lost_now, r);
  r.challenge = challenger_.open;
  r.challenger_spread = challenger_.open ? challenger_.spread : 0;
  r.updated = true;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

namespace {

/** Valid ranges shorter than the sensor's maximum: what a scan holds to weigh. */
size_t returnsInRange(const mrpt::obs::CObservation2DRangeScan& scan) {
  size_t n = 0;
  for (size_t i = 0; i < scan.getScanSize(); ++i)
    n += scan.getScanRangeValidity(i) && scan.getScanRange(i) < scan.maxRange * 0.999f &&
         scan.getScanRange(i) > 0;
  return n;
}

}  // namespace

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
    if (returnsInRange(*scan) < static_cast<size_t>(std::max(0, p_.min_returns)))
      r.dead_reckoning = true;  // nothing to weigh against: pending_ keeps the odometry
    else
      filterUpdate(*scan, t, r);
  }
  r.pose = pose();
  r.cov = cov_;
  r.particles = particleCount();
  r.spread = spread_;
  if (!r.updated) r.likelihood_ratio = averages_set_ ? std::exp(log_w_fast_ - log_w_slow_) : 1;
  r.rotate_in_place = rotate_.open();
  return r;
}

}  // namespace carenav::localization
