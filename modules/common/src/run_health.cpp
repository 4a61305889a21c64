#include <carenav/common/run_health.h>

#include <unistd.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <limits>

namespace carenav {

double residentMegabytes() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (!f) return std::numeric_limits<double>::quiet_NaN();
  unsigned long size = 0, resident = 0;
  const int got = std::fscanf(f, "%lu %lu", &size, &resident);
  std::fclose(f);
  if (got != 2) return std::numeric_limits<double>::quiet_NaN();
  return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) /
         (1024.0 * 1024.0);
}

double threadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

DurationHistogram::DurationHistogram(double bin_ms, double max_ms)
    : bin_ms_(bin_ms), bins_(static_cast<size_t>(std::ceil(max_ms / bin_ms)) + 1, 0) {}

void DurationHistogram::add(double ms) {
  if (!(ms >= 0)) ms = 0;  // NaN or negative: counted in the first bin
  const double b = std::floor(ms / bin_ms_);
  const size_t i =
      b >= static_cast<double>(bins_.size() - 1) ? bins_.size() - 1 : static_cast<size_t>(b);
  ++bins_[i];
  ++n_;
  max_ = std::max(max_, ms);
}

void DurationHistogram::clear() {
  std::fill(bins_.begin(), bins_.end(), 0);
  n_ = 0;
  max_ = 0;
}

double DurationHistogram::quantile(double q) const {
  if (n_ == 0) return 0;
  const double want = std::ceil(std::clamp(q, 0.0, 1.0) * static_cast<double>(n_));
  size_t seen = 0;
  for (size_t i = 0; i < bins_.size(); ++i) {
    seen += bins_[i];
    if (static_cast<double>(seen) >= want && seen > 0)
      return i + 1 == bins_.size() ? max_ : std::min(max_, (i + 1) * bin_ms_);
  }
  return max_;
}

}  // namespace carenav
