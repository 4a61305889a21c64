#include <carenav/common/errors.h>
#include <carenav/localization/localizer.h>

#include <mrpt/bayes/CParticleFilter.h>
#include <mrpt/core/bits_math.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CSensoryFrame.h>
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
  auto& kld = mcl_.options.KLD_params;
  kld.KLD_binSize_XY = p_.kld_bin_xy;
  kld.KLD_binSize_PHI = mrpt::DEG2RAD(p_.kld_bin_phi);
  kld.KLD_delta = p_.kld_delta;
  kld.KLD_epsilon = p_.kld_epsilon;
  kld.KLD_minSampleSize = static_cast<unsigned>(p_.particles_min);
  kld.KLD_maxSampleSize = static_cast<unsigned>(p_.particles_max);
  mrpt::random::getRandomGenerator().randomize(static_cast<uint32_t>(p_.seed));
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
    part.d = mrpt::math::TPose2D(pose.x() + rng.drawGaussian1D(0, std_x),
                                 pose.y() + rng.drawGaussian1D(0, std_y),
                                 mrpt::math::wrapToPi(pose.phi() + rng.drawGaussian1D(0, std_phi)));
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
    act.timestamp = scan->timestamp;
    mrpt::obs::CActionCollection acts;
    acts.insert(act);
    mrpt::obs::CSensoryFrame sf;
    sf.insert(scan);

    // Resampling (MRPT's KLD draw, which also sets the new sample size) only
    // when the weights have degenerated: ESS ratio below resample_ess
    // (Doucet, Godsill, Andrieu 2000, sec. II.C); otherwise every particle is
    // moved and keeps its weight.
    const CPose2D expected = mean_ + pending_;
    auto pfo = filterOptions(p_);
    const bool resample = mcl_.ESS() < p_.resample_ess;
    pfo.adaptiveSampleSize = resample;
    // While not converged, KLD keeps a share of the global start's particles.
    mcl_.options.KLD_params.KLD_minSampleSize = static_cast<unsigned>(
        converged_ ? p_.particles_min
                   : std::max<double>(p_.particles_min, p_.global_keep * globalCount()));
    std::vector<double> prior;  // log weights before the scan, same order as after
    if (!resample) {
      prior.reserve(mcl_.m_particles.size());
      for (const auto& part : mcl_.m_particles) prior.push_back(part.log_w);
    }
    mcl_.prediction_and_update(&acts, &sf, pfo);
    const size_t n = mcl_.m_particles.size();
    // A KLD draw gives every new particle log_w = 0 + log p(z|x).
    std::vector<double> ll(n);
    for (size_t i = 0; i < n; ++i) ll[i] = mcl_.m_particles[i].log_w - (resample ? 0.0 : prior[i]);
    if (resample) prior.assign(n, 0.0);
    double lse_prior = -std::numeric_limits<double>::infinity();
    for (double a : prior) lse_prior = logSumExp(lse_prior, a);
    for (double& a : prior) a -= lse_prior;  // sum of exp(prior) = 1
    // Mean observation likelihood under the prior weights (untempered), for
    // augmented MCL.
    double log_w_avg = -std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < n; ++i) log_w_avg = logSumExp(log_w_avg, prior[i] + ll[i]);

    r.beta = converged_ ? 1.0 : temperingExponent(prior, ll, p_.temper_ess, p_.temper_beta_min);
    for (size_t i = 0; i < n; ++i) mcl_.m_particles[i].log_w = prior[i] + r.beta * ll[i];
    mcl_.normalizeWeights();
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
