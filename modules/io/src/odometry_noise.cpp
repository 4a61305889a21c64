// Seeded odometry noise (odometry_noise.h).
#include <carenav/io/odometry_noise.h>

#include <cmath>

namespace carenav::io {

NoisyOdometry::NoisyOdometry(const OdometryNoiseParams& p)
    : p_(p), state_(p.seed * 0x9E3779B97F4A7C15ULL + 0x2545F4914F6CDD1DULL) {
  if (state_ == 0) state_ = 1;
}

double NoisyOdometry::uniform() {
  // xorshift64* [Vigna16]: a fixed sequence for a seed on every platform,
  // unlike std::normal_distribution, whose algorithm the library chooses.
  state_ ^= state_ >> 12;
  state_ ^= state_ << 25;
  state_ ^= state_ >> 27;
  const uint64_t r = state_ * 0x2545F4914F6CDD1DULL;
  return (static_cast<double>(r >> 11) + 0.5) * (1.0 / 9007199254740992.0);  // (0, 1)
}

double NoisyOdometry::normal() {
  if (spare_) {
    const double s = *spare_;
    spare_.reset();
    return s;
  }
  const double r = std::sqrt(-2.0 * std::log(uniform()));
  const double a = 2.0 * M_PI * uniform();
  spare_ = r * std::sin(a);
  return r * std::cos(a);
}

mrpt::poses::CPose2D NoisyOdometry::next(const mrpt::poses::CPose2D& reference) {
  if (!last_ref_) {
    last_ref_ = reference;
    noisy_ = reference;
    return noisy_;
  }
  const mrpt::poses::CPose2D inc = reference - *last_ref_;
  last_ref_ = reference;
  const double d = std::hypot(inc.x(), inc.y());
  const double a = inc.phi();
  const double scale = 1.0 + p_.dist_frac * normal();
  const double drift = p_.deg_per_m * M_PI / 180 * d;
  const double turn_sd = std::sqrt(drift * drift + p_.turn_frac * a * p_.turn_frac * a);
  const mrpt::poses::CPose2D noisy_inc(inc.x() * scale, inc.y() * scale, a + turn_sd * normal());
  noisy_ = noisy_ + noisy_inc;
  return noisy_;
}

}  // namespace carenav::io
