// Health of a long run: resident memory of the process, and a histogram of
// control-cycle times whose size does not grow with the run (soak tests,
// docs/BENCHMARKS.md "Soak").
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace carenav {

/** Resident set size of this process in MiB (/proc/self/statm); NaN where
 *  it cannot be read. */
double residentMegabytes();

/** CPU time of the calling thread, in ms (CLOCK_THREAD_CPUTIME_ID): the
 *  work a loop does, whatever else the machine runs. */
double threadCpuMs();

/** Durations (ms) counted in fixed bins of `bin_ms` up to `max_ms` (longer
 *  ones in the last bin, and kept exactly in max()): memory is fixed
 *  however long the run, percentiles are exact to one bin. */
class DurationHistogram {
 public:
  explicit DurationHistogram(double bin_ms = 0.01, double max_ms = 1000);
  void add(double ms);
  void clear();
  size_t count() const { return n_; }
  double max() const { return max_; }
  /** The q-quantile (0 < q <= 1), as the upper edge of its bin; 0 when empty. */
  double quantile(double q) const;

 private:
  double bin_ms_;
  std::vector<uint32_t> bins_;
  size_t n_ = 0;
  double max_ = 0;
};

}  // namespace carenav
