// Point-to-line ICP with a motion prior (line_icp.h) and the prior itself
// (motion_prior.h).
#include <carenav/slam/line_icp.h>
#include <carenav/slam/motion_prior.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace carenav;
using mrpt::maps::CSimplePointsMap;
using mrpt::poses::CPose2D;

namespace {
constexpr double kDeg = M_PI / 180;

void wall(CSimplePointsMap& m, double x0, double y0, double x1, double y1, double step) {
  const int n = static_cast<int>(std::hypot(x1 - x0, y1 - y0) / step);
  for (int i = 0; i <= n; ++i) m.insertPoint(x0 + (x1 - x0) * i / n, y0 + (y1 - y0) * i / n, 0);
}

/** A room with a pillar, walls sampled every `step` m. */
CSimplePointsMap room(double step) {
  CSimplePointsMap m;
  wall(m, -3, -2, 5, -2, step);
  wall(m, 5, -2, 5, 1, step);
  wall(m, 5, 1, 1, 1, step);
  wall(m, 1, 1, 1, 4, step);
  wall(m, 1, 4, -3, 4, step);
  wall(m, -3, 4, -3, -2, step);
  wall(m, 2, -0.5, 2.5, -0.5, step);
  wall(m, 2.5, -0.5, 2.5, 0, step);
  return m;
}

/** Two parallel walls 2 m apart, 40 m long: nothing fixes the position along them. */
CSimplePointsMap corridor(double step) {
  CSimplePointsMap m;
  wall(m, -20, -1, 20, -1, step);
  wall(m, -20, 1, 20, 1, step);
  return m;
}

/** The points seen from `pose`, in its frame (every point, no occlusion). */
CSimplePointsMap seenFrom(const CSimplePointsMap& world, const CPose2D& pose) {
  CSimplePointsMap s = world;
  s.changeCoordinatesReference(mrpt::poses::CPose3D(-pose));
  return s;
}

}  // namespace

namespace {
slam::PoseGaussian prior(const CPose2D& mean, double sxy, double sdeg) {
  mrpt::math::CMatrixDouble33 c;
  c.setZero();
  c(0, 0) = c(1, 1) = sxy * sxy;
  c(2, 2) = (sdeg * kDeg) * (sdeg * kDeg);
  return slam::PoseGaussian(mean, c);
}
}  // namespace

TEST(LineIcp, AlignsAScanSampledDifferentlyFromTheReference) {
  // Reference every 5 cm, scan every 7 cm: no scan point coincides with a
  // reference point, so point-to-point pairs pull along the walls; lines do not.
  slam::LineIcp icp{slam::LineIcp::Parameters{}};
  icp.setReference(room(0.05));
  EXPECT_GT(icp.lines(), 300u);
  const CPose2D truth(0.4, 0.3, 8 * kDeg);
  const auto r = icp.align(seenFrom(room(0.07), truth), CPose2D(0.25, 0.15, 3 * kDeg));
  EXPECT_NEAR(r.pose.x(), truth.x(), 0.005);
  EXPECT_NEAR(r.pose.y(), truth.y(), 0.005);
  EXPECT_NEAR(r.pose.phi(), truth.phi(), 0.1 * kDeg);
  EXPECT_GT(r.inliers, 0.9);
}

TEST(LineIcp, ACorridorIsHeldAlongItByThePriorAndFixedAcrossIt) {
  slam::LineIcp icp{slam::LineIcp::Parameters{}};
  icp.setReference(corridor(0.05));
  const CPose2D truth(0.0, 0.2, 2 * kDeg);
  const CSimplePointsMap scan = seenFrom(corridor(0.07), truth);
  // Without a prior the position along the corridor is unknown: its variance is huge.
  const auto free = icp.align(scan, CPose2D(0.3, 0.0, 0));
  EXPECT_GT(std::sqrt(free.cov(0, 0)), 1.0);
  EXPECT_NEAR(free.pose.y(), truth.y(), 0.005);
  // With odometry's prior 0.3 m along: across (y) and heading come from the
  // walls, along (x) from the prior, with the prior's uncertainty.
  const slam::PoseGaussian p = prior(CPose2D(0.3, 0.05, 0), 0.1, 3);
  const auto with = icp.align(scan, p.mean, &p);
  EXPECT_NEAR(with.pose.x(), 0.3, 0.01);
  EXPECT_NEAR(with.pose.y(), truth.y(), 0.005);
  EXPECT_NEAR(with.pose.phi(), truth.phi(), 0.1 * kDeg);
  EXPECT_NEAR(std::sqrt(with.cov(0, 0)), 0.1, 0.01);
  EXPECT_LT(std::sqrt(with.cov(1, 1)), 0.01);
}

TEST(LineIcp, WithoutReferencePointsThePriorIsTheAnswer) {
  slam::LineIcp icp{slam::LineIcp::Parameters{}};
  icp.setReference(CSimplePointsMap());
  const slam::PoseGaussian p = prior(CPose2D(1, 2, 0.5), 0.2, 5);
  const auto r = icp.align(seenFrom(room(0.05), CPose2D()), p.mean, &p);
  EXPECT_EQ(r.pairs, 0u);
  EXPECT_NEAR(r.pose.x(), 1, 1e-9);
  EXPECT_NEAR(std::sqrt(r.cov(0, 0)), 0.2, 1e-6);
}

TEST(MotionPrior, UncertaintyGrowsWithDistanceAndTurn) {
  const slam::MotionNoise n;
  const auto still = slam::incrementCovariance(CPose2D(0, 0, 0), n);
  EXPECT_NEAR(std::sqrt(still(0, 0)), n.min_xy, 1e-12);
  EXPECT_NEAR(std::sqrt(still(2, 2)), n.min_deg * kDeg, 1e-12);
  const auto metre = slam::incrementCovariance(CPose2D(1, 0, 0), n);
  const auto two = slam::incrementCovariance(CPose2D(2, 0, 0), n);
  const auto turn = slam::incrementCovariance(CPose2D(1, 0, 60 * kDeg), n);
  EXPECT_GT(two(0, 0), 3.5 * (metre(0, 0) - still(0, 0)));
  EXPECT_GT(turn(2, 2), metre(2, 2));
  // 1 m: 10 % of it and a little from the heading, about 0.11 m.
  EXPECT_NEAR(std::sqrt(metre(0, 0)), 0.105, 0.01);
}

TEST(MotionPrior, FusingTwoEqualEstimatesHalvesTheCovariance) {
  const slam::PoseGaussian a = prior(CPose2D(0, 0, 0.1), 0.2, 4);
  const slam::PoseGaussian b = prior(CPose2D(0.2, 0, 0.1 + 2 * M_PI), 0.2, 4);
  const slam::PoseGaussian f = slam::fuse(a, b);
  EXPECT_NEAR(f.mean.x(), 0.1, 1e-9);
  EXPECT_NEAR(f.mean.phi(), 0.1, 1e-9);  // headings 2 pi apart are the same
  EXPECT_NEAR(f.cov(0, 0), 0.5 * a.cov(0, 0), 1e-12);
  EXPECT_NEAR(slam::mahalanobis2(a.mean, b.mean, a.cov), 1.0, 1e-9);
}

TEST(MotionPrior, ToWorldTurnsTheCovarianceWithTheFrame) {
  mrpt::math::CMatrixDouble33 c;
  c.setZero();
  c(0, 0) = 4, c(1, 1) = 1, c(2, 2) = 0.5;
  const auto w = slam::toWorld(c, CPose2D(3, 4, M_PI / 2));
  EXPECT_NEAR(w(0, 0), 1, 1e-12);
  EXPECT_NEAR(w(1, 1), 4, 1e-12);
  EXPECT_NEAR(w(2, 2), 0.5, 1e-12);
}
