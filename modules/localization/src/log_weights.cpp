#include "log_weights.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace carenav::localization {

double logSumExp(double a, double b) {
  const double m = std::max(a, b);
  if (m == -std::numeric_limits<double>::infinity()) return m;
  return m + std::log(std::exp(a - m) + std::exp(b - m));
}

double logSumExp(const std::vector<double>& a, const std::vector<double>& b) {
  const auto term = [&](size_t i) { return b.empty() ? a[i] : a[i] + b[i]; };
  double m = -std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < a.size(); ++i) m = std::max(m, term(i));
  if (m == -std::numeric_limits<double>::infinity()) return m;
  double s = 0;
  for (size_t i = 0; i < a.size(); ++i) s += std::exp(term(i) - m);
  return m + std::log(s);
}

double essRatio(const std::vector<double>& a, const std::vector<double>& l, double beta) {
  double m = -std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < a.size(); ++i) m = std::max(m, a[i] + beta * l[i]);
  double s = 0, s2 = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const double w = std::exp(a[i] + beta * l[i] - m);
    s += w;
    s2 += w * w;
  }
  return s2 > 0 ? s * s / s2 / static_cast<double>(a.size()) : 0;
}

double temperingExponent(const std::vector<double>& a, const std::vector<double>& l, double share,
                         double beta_min) {
  if (share <= 0 || a.empty()) return 1;
  const double target = share * essRatio(a, l, 0);
  if (essRatio(a, l, 1) >= target) return 1;
  if (essRatio(a, l, beta_min) < target) return beta_min;
  double lo = std::log(beta_min), hi = 0;  // ESS(exp(lo)) >= target > ESS(exp(hi))
  for (int it = 0; it < 14; ++it) {
    const double mid = 0.5 * (lo + hi);
    (essRatio(a, l, std::exp(mid)) >= target ? lo : hi) = mid;
  }
  return std::exp(lo);
}

}  // namespace carenav::localization
