#include "motion_sampler.h"

#include <mrpt/math/wrap2pi.h>
#include <mrpt/poses/CPosePDFGaussian.h>
#include <mrpt/random/RandomGenerators.h>

#include <cmath>
#include <stdexcept>
#include <vector>

namespace carenav::localization {

MotionSampler::MotionSampler(const mrpt::poses::CPosePDF& pose_change) {
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

mrpt::math::TPose2D MotionSampler::increment() const {
  auto& rng = mrpt::random::getRandomGenerator();
  double r[3] = {0, 0, 0};
  for (int i = 0; i < 3; ++i) {
    const double n = rng.drawGaussian1D_normalized();
    for (int d = 0; d < 3; ++d) r[d] += z(d, i) * n;
  }
  return {mean.x + r[0], mean.y + r[1], mrpt::math::wrapToPi(mean.phi + r[2])};
}

mrpt::math::TPose2D MotionSampler::compose(const mrpt::math::TPose2D& p,
                                           const mrpt::math::TPose2D& inc) {
  const double c = std::cos(p.phi), s = std::sin(p.phi);
  return {p.x + c * inc.x - s * inc.y, p.y + s * inc.x + c * inc.y,
          mrpt::math::wrapToPi(p.phi + inc.phi)};
}

}  // namespace carenav::localization
