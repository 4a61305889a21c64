#include "no_return_level.h"

#include <algorithm>
#include <cmath>

namespace carenav::io {

namespace {
constexpr double kBin = 0.01;  // m
}

NoReturnFinder::NoReturnFinder(double below)
    : bins_(static_cast<size_t>(std::max(0.0, below) / kBin), 0) {}

void NoReturnFinder::add(double range) {
  if (!(range > 0)) return;
  const double b = range / kBin;
  if (!(b < static_cast<double>(bins_.size()))) return;
  ++bins_[static_cast<size_t>(b)];
  ++total_;
}

uint64_t NoReturnFinder::countBins(size_t from, size_t to) const {
  uint64_t n = 0;
  for (size_t i = from; i < to && i < bins_.size(); ++i) n += bins_[i];
  return n;
}

bool NoReturnFinder::find(NoReturnLevel& out) const {
  const double repeat = std::max<double>(kMinRepeat, kRepeatShare * total_);
  size_t top = bins_.size();
  while (top > 0 && static_cast<double>(bins_[top - 1]) < repeat) --top;
  if (top == 0) return false;
  const size_t level = top - 1;
  const auto band_from = static_cast<size_t>(std::floor(level * (1 - kBand)));
  const auto below_from = static_cast<size_t>(std::floor(level * (1 - 3 * kBand)));
  const uint64_t band = countBins(band_from, level + 2);
  const uint64_t below = countBins(below_from, band_from);
  const uint64_t above = countBins(level + 2, bins_.size());
  // Per metre the band below is twice as wide as the band.
  const bool piled = 2.0 * band >= kDensityRatio * below;
  if (!piled || above > kAboveShare * band || band > kMaxPileShare * total_) return false;
  out.level = level * kBin;
  out.limit = band_from * kBin;
  out.piled = countBins(band_from, bins_.size());
  return true;
}

}  // namespace carenav::io
