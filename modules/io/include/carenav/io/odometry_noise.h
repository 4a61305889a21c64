// Seeded wheel-odometry noise for benchmarks: turns a log's reference poses
// into the odometry a real base would have reported, so the same scans can be
// mapped with odometry that is good enough to help and wrong enough to test
// that the mapper treats it as a prior, not as truth.
#pragma once

#include <mrpt/poses/CPose2D.h>

#include <cstdint>
#include <optional>

namespace carenav::io {

/** The noise of each increment between two consecutive odometry readings
 *  (robot frame; d = its length, a = its turn), drawn independently:
 *  - length: d * (1 + dist_frac * n1)            (the wheels' scale error);
 *  - turn:   a + n2 * sqrt((deg_per_m * d)^2 + (turn_frac * a)^2)
 *            (heading drift while driving, and the turn's own scale error);
 *  n1, n2 standard normal. Errors accumulate, as in any odometry. The
 *  defaults (5 %, 1 deg per m, 2 %) are a typical differential drive on
 *  indoor floors [Thrun05, Sec. 5.4]. */
struct OdometryNoiseParams {
  uint64_t seed = 1;        ///< same seed, same noise (portable: own generator)
  double dist_frac = 0.05;  ///< standard deviation of the length, share of it
  double deg_per_m = 1.0;   ///< deg of heading drift per metre driven (std dev)
  double turn_frac = 0.02;  ///< standard deviation of the turn, share of it
};

/** Feeds reference poses in order, returns the noisy odometry poses. The
 *  first reading is returned unchanged (odometry's origin). */
class NoisyOdometry {
 public:
  explicit NoisyOdometry(const OdometryNoiseParams& p);
  mrpt::poses::CPose2D next(const mrpt::poses::CPose2D& reference);

 private:
  double normal();  ///< Box-Muller on a 64-bit xorshift*: same draws on any platform
  double uniform();

  OdometryNoiseParams p_;
  uint64_t state_;
  std::optional<double> spare_;
  std::optional<mrpt::poses::CPose2D> last_ref_;
  mrpt::poses::CPose2D noisy_;
};

}  // namespace carenav::io
