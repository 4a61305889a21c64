#include <carenav/slam/motion_prior.h>

#include <mrpt/math/wrap2pi.h>

#include <Eigen/Dense>

#include <cmath>

namespace carenav::slam {

using mrpt::math::CMatrixDouble33;
using mrpt::poses::CPose2D;

namespace {
constexpr double kDeg = M_PI / 180;
}

CMatrixDouble33 incrementCovariance(const CPose2D& inc, const MotionNoise& n) {
  const double d = std::hypot(inc.x(), inc.y());
  const double a = std::abs(inc.phi());
  const double drift = n.deg_per_m * kDeg * d, turn = n.turn_frac * a, floor = n.min_deg * kDeg;
  const double var_th = drift * drift + turn * turn + floor * floor;
  const double lin = n.dist_frac * d;
  const double var_xy = lin * lin + 0.25 * d * d * var_th + n.min_xy * n.min_xy;
  CMatrixDouble33 c;
  c.setZero();
  c(0, 0) = c(1, 1) = var_xy;
  c(2, 2) = var_th;
  return c;
}

CMatrixDouble33 toWorld(const CMatrixDouble33& cov, const CPose2D& frame) {
  const double c = std::cos(frame.phi()), s = std::sin(frame.phi());
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  r(0, 0) = c;
  r(0, 1) = -s;
  r(1, 0) = s;
  r(1, 1) = c;
  return CMatrixDouble33(r * cov.asEigen() * r.transpose());
}

double mahalanobis2(const CPose2D& a, const CPose2D& b, const CMatrixDouble33& cov) {
  const Eigen::Vector3d d(a.x() - b.x(), a.y() - b.y(), mrpt::math::wrapToPi(a.phi() - b.phi()));
  return d.dot(cov.asEigen().ldlt().solve(d));
}

PoseGaussian fuse(const PoseGaussian& a, const PoseGaussian& b) {
  const Eigen::Matrix3d ia = a.cov.asEigen().inverse(), ib = b.cov.asEigen().inverse();
  const Eigen::Matrix3d cov = (ia + ib).inverse();
  const Eigen::Vector3d xa(a.mean.x(), a.mean.y(), a.mean.phi());
  const Eigen::Vector3d xb(b.mean.x(), b.mean.y(),
                           a.mean.phi() + mrpt::math::wrapToPi(b.mean.phi() - a.mean.phi()));
  const Eigen::Vector3d x = cov * (ia * xa + ib * xb);
  return PoseGaussian(CPose2D(x(0), x(1), mrpt::math::wrapToPi(x(2))), CMatrixDouble33(cov));
}

}  // namespace carenav::slam
