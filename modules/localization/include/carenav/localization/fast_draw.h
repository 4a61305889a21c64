// Multinomial draws of particle indices by weight, with the arithmetic of
// MRPT's CParticleFilterCapable::fastDrawSample and a binary search.
#pragma once

#include <cstddef>
#include <vector>

namespace carenav::localization {

/** Multinomial draws by weight, the rule of MRPT's
 *  CParticleFilterCapable::prepareFastDrawSample / fastDrawSample (the draw
 *  MRPT's KLD-sampling filter makes), computed with the same floating-point
 *  operations so that a seed still gives the same particles, but with a
 *  binary search instead of a linear walk. */
struct FastDraw {
  static constexpr size_t kBins = 20;
  std::vector<double> pdf;
  size_t start[kBins] = {};
  std::vector<double> counts[kBins];
  /** Prepares the draws from the (unnormalised) log weights; at least one. */
  void prepare(const std::vector<double>& log_w);
  /** The index drawn for u in [0, 0.999999). */
  size_t draw(double u) const;
};

}  // namespace carenav::localization
