// The motion prior of the icp-graph front end: how far the odometry of one
// step can be off, so the scan matcher searches where the robot can be and
// weighs its result against odometry instead of taking either as truth
// ([Thrun05, Sec. 5.4]: odometry noise grows with the distance driven and the
// angle turned; [Olson09csm]: the search window follows the prior's
// uncertainty).
#pragma once

#include <carenav/slam/loop_consistency.h>

#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/poses/CPose2D.h>

namespace carenav::slam {

/** Odometry noise of one increment of length d (m) and turn a (rad), standard
 *  deviations drawn independently:
 *  - heading:  sqrt((deg_per_m d)^2 + (turn_frac a)^2 + min_deg^2)
 *  - position: sqrt((dist_frac d)^2 + (d sigma_heading / 2)^2 + min_xy^2),
 *    the same in every direction (the second term: a heading error made
 *    halfway displaces the end sideways).
 *  The defaults are a pessimistic differential drive on indoor floors
 *  (twice the noise of common wheel odometry): a prior too tight makes
 *  the matcher reject right matches, one too loose only costs search time. */
struct MotionNoise {
  double dist_frac = 0.10;  ///< position std dev, share of the distance
  double deg_per_m = 2.0;   ///< heading drift, deg std dev per m driven
  double turn_frac = 0.05;  ///< heading std dev, share of the turn
  double min_xy = 0.03;     ///< m, floor of the position std dev (wheel slip at rest)
  double min_deg = 1.0;     ///< deg, floor of the heading std dev
};

/** Covariance (x, y, yaw) of an odometry increment, in the frame of the pose
 *  it starts from. */
mrpt::math::CMatrixDouble33 incrementCovariance(const mrpt::poses::CPose2D& inc,
                                                const MotionNoise& n);

/** The covariance of `cov` (robot frame of `frame`) expressed in the world
 *  frame. */
mrpt::math::CMatrixDouble33 toWorld(const mrpt::math::CMatrixDouble33& cov,
                                    const mrpt::poses::CPose2D& frame);

/** Squared Mahalanobis distance between two poses under `cov` (heading
 *  difference wrapped to (-pi, pi]). */
double mahalanobis2(const mrpt::poses::CPose2D& a, const mrpt::poses::CPose2D& b,
                    const mrpt::math::CMatrixDouble33& cov);

/** The product of two Gaussian pose estimates of the same pose (information
 *  form; headings combined around a's). */
PoseGaussian fuse(const PoseGaussian& a, const PoseGaussian& b);

}  // namespace carenav::slam
