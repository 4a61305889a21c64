// Odometry increments drawn from MRPT's Gaussian motion model, in 2D.
#pragma once

#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/math/TPose2D.h>
#include <mrpt/poses/CPosePDF.h>

namespace carenav::localization {

/** Draws odometry increments from the Gaussian pose change that
 *  CActionRobotMovement2D computes and composes them onto particles, in 2D.
 *  The increment is mean + Z r, Z the covariance's eigenvectors scaled by the
 *  square roots of its eigenvalues and r three standard normal draws: what
 *  MRPT's CPoseRandomSampler draws, in the same order from the same generator
 *  and with the same arithmetic, so a seed gives the same particles. */
struct MotionSampler {
  /** Throws std::logic_error when pose_change is not a CPosePDFGaussian. */
  explicit MotionSampler(const mrpt::poses::CPosePDF& pose_change);
  /** One increment, three draws of MRPT's random generator. */
  mrpt::math::TPose2D increment() const;
  static mrpt::math::TPose2D compose(const mrpt::math::TPose2D& p, const mrpt::math::TPose2D& inc);
  mrpt::math::TPose2D moved(const mrpt::math::TPose2D& p) const { return compose(p, increment()); }
  mrpt::math::TPose2D mean;
  mrpt::math::CMatrixDouble33 z;
};

}  // namespace carenav::localization
