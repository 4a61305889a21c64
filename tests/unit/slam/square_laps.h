// Shared fixture of the pose-graph tests (robust back end, closure
// consistency): two laps of a 10 x 10 m square with exact truth and drifting
// odometry.
#pragma once

#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/poses/CPosePDFGaussianInf.h>

#include <cmath>
#include <random>
#include <vector>

namespace carenav::slam::test {

constexpr double kDeg = M_PI / 180;

/** Diagonal covariance: sxy (m) in x and y, sth (rad) in heading. */
inline mrpt::math::CMatrixDouble33 diag(double sxy, double sth) {
  mrpt::math::CMatrixDouble33 c;
  c.setZero();
  c(0, 0) = c(1, 1) = sxy * sxy;
  c(2, 2) = sth * sth;
  return c;
}

/** A graph edge with that diagonal uncertainty (as an information matrix). */
inline mrpt::poses::CPosePDFGaussianInf edge(const mrpt::poses::CPose2D& rel, double sxy,
                                             double sth) {
  mrpt::poses::CPosePDFGaussianInf e;
  e.mean = rel;
  e.cov_inv.setZero();
  e.cov_inv(0, 0) = e.cov_inv(1, 1) = 1 / (sxy * sxy);
  e.cov_inv(2, 2) = 1 / (sth * sth);
  return e;
}

/** Two laps of a 10 x 10 m square, a pose every 0.5 m (80 per lap), and the
 *  odometry between consecutive poses: the true increment plus noise (nxy
 *  in x and y, nth in heading, drawn in that order from rng) and a 0.6 deg
 *  heading bias per step, so the chain drifts 48 deg a lap. odometry[i] is
 *  the step from pose i - 1 to i (odometry[0] is the identity). */
struct SquareLaps {
  static constexpr size_t kLap = 80;
  std::vector<mrpt::poses::CPose2D> truth, odometry;
};

inline SquareLaps squareLaps(std::mt19937& rng, std::normal_distribution<double>& nxy,
                             std::normal_distribution<double>& nth) {
  SquareLaps s;
  for (size_t i = 0; i < 2 * SquareLaps::kLap; ++i) {
    const size_t q = i % SquareLaps::kLap, side = q / 20, along = q % 20;
    const double d = 0.5 * along;
    const double x[] = {d, 10, 10 - d, 0}, y[] = {0, d, 10, 10 - d};
    s.truth.emplace_back(x[side], y[side], side * 90 * kDeg);
  }
  s.odometry.emplace_back(0, 0, 0);
  for (size_t i = 1; i < s.truth.size(); ++i) {
    const mrpt::poses::CPose2D t = s.truth[i] - s.truth[i - 1];
    // One draw per statement: argument order is the compiler's choice; this
    // is gcc's (last first), which the tests' thresholds were set with.
    const double dth = nth(rng), dy = nxy(rng), dx = nxy(rng);
    const mrpt::poses::CPose2D z(t.x() + dx, t.y() + dy, t.phi() + 0.6 * kDeg + dth);
    s.odometry.push_back(z);
  }
  return s;
}

}  // namespace carenav::slam::test
