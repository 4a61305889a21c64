// Progress of long runs on stderr (position, rate, ETA), only on a terminal.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

namespace carenav {

class Progress {
 public:
  /** `total_bytes` may be 0 when unknown (no percentage nor ETA then).
   *  Enabled only when stderr is a terminal, unless forced. */
  Progress(std::string label, uint64_t total_bytes, bool force_enable = false);
  ~Progress();
  /** Cheap to call often: redraws at most 5 times a second. */
  void update(uint64_t bytes_done, uint64_t entries_done);
  /** Clears the line. */
  void finish();
  void setEnabled(bool e) { enabled_ = e; }
  bool enabled() const { return enabled_; }
  /** The status line for the given state (exposed for tests). */
  static std::string line(const std::string& label, uint64_t bytes_done, uint64_t total,
                          uint64_t entries, double seconds);

 private:
  std::string label_;
  uint64_t total_;
  bool enabled_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point start_, last_;
};

}  // namespace carenav
