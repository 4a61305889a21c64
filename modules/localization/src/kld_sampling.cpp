#include <carenav/localization/kld_sampling.h>

#include "motion_sampler.h"

#include <mrpt/core/bits_math.h>
#include <mrpt/core/round.h>
#include <mrpt/math/distributions.h>
#include <mrpt/random/RandomGenerators.h>

#include <algorithm>
#include <cmath>

namespace carenav::localization {

namespace {

constexpr uint64_t kEmpty = ~uint64_t(0);  // no key is all ones

/** Bin key of a pose: x and y bins in 22 bits each, heading bin in 20. */
uint64_t binKey(const mrpt::math::TPose2D& pose, double bin_xy, double bin_phi) {
  const auto bin = [](double v, double size, int64_t half) {
    const int64_t b = mrpt::round(v / size);
    return static_cast<uint64_t>(std::clamp<int64_t>(b, -half + 1, half - 1) + half);
  };
  return bin(pose.x, bin_xy, int64_t(1) << 21) << 42 | bin(pose.y, bin_xy, int64_t(1) << 21) << 20 |
         bin(pose.phi, bin_phi, int64_t(1) << 19);
}

/** The occupied bins: open addressing, at most n_max keys in twice the slots. */
class BinSet {
 public:
  BinSet(std::vector<uint64_t>& slots, size_t n_max) : slots_(slots) {
    while ((size_t(1) << bits_) < 2 * n_max) ++bits_;
    slots_.assign(size_t(1) << bits_, kEmpty);
    mask_ = (uint64_t(1) << bits_) - 1;
  }
  /** True when the bin was empty. */
  bool insert(uint64_t key) {
    for (uint64_t h = (key * 0x9E3779B97F4A7C15ull) >> (64 - bits_);; h = (h + 1) & mask_) {
      if (slots_[h] == key) return false;
      if (slots_[h] == kEmpty) {
        slots_[h] = key;
        ++occupied_;
        return true;
      }
    }
  }
  size_t occupied() const { return occupied_; }

 private:
  std::vector<uint64_t>& slots_;
  int bits_ = 4;
  uint64_t mask_ = 0;
  size_t occupied_ = 0;
};

}  // namespace

// KLD-sampling (Fox 2003, "Adapting the sample size in particle filters
// through KLD-sampling", IJRR 22(12), table 1): particles are drawn by weight
// and moved one at a time until their number reaches n(k) = (k - 1) / (2
// epsilon) chi^2_{k-1, 1-delta}, k the number of occupied bins of kld_bin_xy x
// kld_bin_xy x kld_bin_phi, and at least n_min, at most particles_max. The
// drawn particles start with equal weights. The draws are those of MRPT's
// CMonteCarloLocalization2D with KLD (same order from the same generator), so
// a seed gives the particles it gave when MRPT ran the whole filter.
void KldSampler::draw(mrpt::poses::CPosePDFParticles::CParticleList& parts,
                      const MotionSampler& motion, const LocalizationParams& p, size_t n_min) {
  if (parts.empty()) return;
  log_w_.resize(parts.size());
  for (size_t i = 0; i < parts.size(); ++i) log_w_[i] = parts[i].log_w;
  fast_draw_.prepare(log_w_);
  auto& rng = mrpt::random::getRandomGenerator();
  const size_t n_max = static_cast<size_t>(std::max(1, p.particles_max));
  const double delta_1 = 1 - p.kld_delta, epsilon_1 = 0.5 / p.kld_epsilon;
  const double bin_xy = p.kld_bin_xy, bin_phi = mrpt::DEG2RAD(p.kld_bin_phi);
  drawn_.clear();
  BinSet bins(bins_, n_max);
  size_t nx = n_min;
  do {
    const auto inc = motion.increment();
    const auto pose =
        MotionSampler::compose(parts[fast_draw_.draw(rng.drawUniform(0.0, 0.999999))].d, inc);
    drawn_.push_back(pose);
    if (bins.insert(binKey(pose, bin_xy, bin_phi)) && bins.occupied() > 1)
      nx = static_cast<size_t>(mrpt::round(
          epsilon_1 * mrpt::math::chi2inv(delta_1, static_cast<unsigned>(bins.occupied() - 1))));
  } while (drawn_.size() < std::max(nx, n_min) && drawn_.size() < n_max);
  parts.resize(drawn_.size());
  for (size_t i = 0; i < drawn_.size(); ++i) {
    parts[i].d = drawn_[i];
    parts[i].log_w = 0;
  }
}

}  // namespace carenav::localization
