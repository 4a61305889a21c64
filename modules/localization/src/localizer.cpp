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
  refreshEstimate();
  // A pose given with a tight spread counts as converged from the start, so
  // that a wrong one shows up as a loss.
  converged_ = spread_ < p_.converged_spread;
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
  refreshEstimate();
  converged_ = false;
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
  const size_t n = mcl_.m_particles.size();
  const auto k = static_cast<size_t>(std::lround(fraction * static_cast<double>(n)));
  if (k == 0) return 0;
  // Equal weights first, so that the random particles are neither favoured
  // nor drowned by the weights of the ones they replace.
  bool uniform = true;
  for (const auto& part : mcl_.m_particles) uniform = uniform && part.log_w == 0;
  if (!uniform) mcl_.performResampling(filterOptions(p_));
  auto& rng = mrpt::random::getRandomGenerator();
  for (size_t i = 0; i < k; ++i) {
    auto& part = mcl_.m_particles[rng.drawUniform32bit() % mcl_.m_particles.size()];
    part.d = randomFreePose();
    part.log_w = 0;
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
    mm.gaussianModel.minStdXY = p_.odom_min_std_xy;
    mm.gaussianModel.minStdPHI = mrpt::DEG2RAD(p_.odom_min_std_phi);
    act.computeFromOdometry(pending_, mm);
    act.timestamp = scan->timestamp;
    mrpt::obs::CActionCollection acts;
    acts.insert(act);
    mrpt::obs::CSensoryFrame sf;
    sf.insert(scan);

    const auto pfo = filterOptions(p_);
    mcl_.prediction_and_update(&acts, &sf, pfo);
    // KLD sampling draws the new set from the old weights and gives every
    // new particle log_w = 0 + log p(z|x): the mean likelihood is exact.
    double lse = -std::numeric_limits<double>::infinity();
    for (const auto& part : mcl_.m_particles) lse = logSumExp(lse, part.log_w);
    const double log_w_avg = lse - std::log(static_cast<double>(mcl_.m_particles.size()));
    mcl_.normalizeWeights();
    if (mcl_.ESS() < pfo.BETA) mcl_.performResampling(pfo);

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
    pending_ = CPose2D();
    first_update_done_ = true;
    ++updates_;

    if (!convergence_time_ && spread_ < p_.converged_spread) convergence_time_ = t;
    if (!converged_ && spread_ < p_.converged_spread) {
      converged_ = true;
      if (!events_.empty() && events_.back().kind == LocalizationEvent::Kind::Loss)
        events_.push_back({LocalizationEvent::Kind::Recovery, t, spread_});
    } else if (converged_ && spread_ > p_.lost_spread) {
      converged_ = false;
      events_.push_back({LocalizationEvent::Kind::Loss, t, spread_});
    }

    if (p_.recovery) {
      const double fraction =
          std::min(p_.max_inject_fraction, std::max(0.0, 1 - r.likelihood_ratio));
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
  return r;
}

}  // namespace carenav::localization
