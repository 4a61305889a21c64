// KLD-sampling (Fox 2003): a new particle set drawn by weight and moved, its
// size adapted to the number of occupied pose bins.
#pragma once

#include <carenav/localization/fast_draw.h>
#include <carenav/localization/localization_params.h>

#include <mrpt/math/TPose2D.h>
#include <mrpt/poses/CPosePDFParticles.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace carenav::localization {

struct MotionSampler;

/** Draws a new particle set as MRPT's CMonteCarloLocalization2D with KLD
 *  does (same draws in the same order from the same generator). Keeps its
 *  scratch between draws. */
class KldSampler {
 public:
  /** Replaces `parts` (not empty) by particles drawn by weight and moved by
   *  `motion`, with equal weights: at least n_min, at most particles_max of
   *  them, as many as the KLD bound of the occupied kld_bin_* bins asks. */
  void draw(mrpt::poses::CPosePDFParticles::CParticleList& parts, const MotionSampler& motion,
            const LocalizationParams& p, size_t n_min);

 private:
  FastDraw fast_draw_;
  std::vector<mrpt::math::TPose2D> drawn_;
  std::vector<double> log_w_;
  std::vector<uint64_t> bins_;  // occupied KLD bins (hash table)
};

}  // namespace carenav::localization
