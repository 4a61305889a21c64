#include <carenav/common/progress.h>

#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace carenav {

Progress::Progress(std::string label, uint64_t total_bytes, bool force_enable)
    : label_(std::move(label)),
      total_(total_bytes),
      enabled_(force_enable || isatty(STDERR_FILENO)),
      start_(std::chrono::steady_clock::now()),
      last_(start_) {}

Progress::~Progress() { finish(); }

std::string Progress::line(const std::string& label, uint64_t bytes_done, uint64_t total,
                           uint64_t entries, double seconds) {
  char buf[256];
  const double rate = seconds > 0 ? entries / seconds : 0;
  if (total > 0) {
    const double frac = std::min(1.0, static_cast<double>(bytes_done) / total);
    const double eta = frac > 0 ? seconds * (1 - frac) / frac : 0;
    std::snprintf(buf, sizeof buf,
                  "%s: %5.1f%% (%.1f of %.1f MB), %llu entries, %.0f entries/s, ETA %.0f s",
                  label.c_str(), 100 * frac, bytes_done / 1e6, total / 1e6,
                  static_cast<unsigned long long>(entries), rate, eta);
  } else {
    std::snprintf(buf, sizeof buf, "%s: %llu entries, %.0f entries/s", label.c_str(),
                  static_cast<unsigned long long>(entries), rate);
  }
  return buf;
}

void Progress::update(uint64_t bytes_done, uint64_t entries_done) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if (drawn_ && now - last_ < std::chrono::milliseconds(200)) return;
  last_ = now;
  const double s = std::chrono::duration<double>(now - start_).count();
  std::fprintf(stderr, "\r\033[K%s", line(label_, bytes_done, total_, entries_done, s).c_str());
  std::fflush(stderr);
  drawn_ = true;
}

void Progress::finish() {
  if (drawn_) {
    std::fprintf(stderr, "\r\033[K");
    std::fflush(stderr);
    drawn_ = false;
  }
}

}  // namespace carenav
