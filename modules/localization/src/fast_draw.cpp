#include <carenav/localization/fast_draw.h>

#include <algorithm>
#include <cmath>

namespace carenav::localization {

// Multinomial draws by weight, the rule of MRPT's
// CParticleFilterCapable::prepareFastDrawSample / fastDrawSample (the draw
// MRPT's KLD-sampling filter makes), computed with the same floating-point
// operations so that a seed still gives the same particles, but with a binary
// search instead of a linear walk: the cumulative weights are cut into
// kBins slices at j / kBins; a draw u in [0, 0.999999) starts at the
// particle that straddles slice j = floor(u (kBins - 0.05)), counts the
// cumulative weight from j / kBins, and takes the first particle where that
// count reaches u.
void FastDraw::prepare(const std::vector<double>& log_w) {
  const size_t m = log_w.size();
  pdf.resize(m);
  const double top = *std::max_element(log_w.begin(), log_w.end());
  double sum = 0;
  for (size_t i = 0; i < m; ++i) sum += pdf[i] = std::exp(log_w[i] + -top);
  const double inv = 1.0 / sum;
  for (double& w : pdf) w *= inv;
  // The particle each slice starts at.
  double thresholds[kBins + 1];
  for (size_t j = 0; j < kBins; ++j) thresholds[j] = double(j) / double(kBins);
  thresholds[kBins] = 1.0;
  size_t j = 0;
  double cdf = 0;
  for (size_t i = 0; i < m && j < kBins; ++i) {
    double next = cdf + pdf[i];
    if (i == m - 1) next = 1.0;
    if (next > 1.0) next = 1.0;
    while (thresholds[j] < next) start[j++] = i;
    cdf = next;
  }
  for (; j < kBins; ++j) start[j] = m - 1;
  // Per slice, the counts a draw compares with: from j / kBins, adding the
  // weights from the slice's particle on, up to the largest draw of the slice.
  for (j = 0; j < kBins; ++j) {
    auto& acc = counts[j];
    acc.clear();
    const double last = std::min(0.999999, double(j + 1) / (double(kBins) - 0.05));
    double c = thresholds[j];
    for (size_t i = start[j]; i < m; ++i) {
      c += pdf[i];
      acc.push_back(c);
      if (c >= last) break;
    }
  }
}

size_t FastDraw::draw(double u) const {
  const size_t j = static_cast<size_t>(std::floor(u * (double(kBins) - 0.05)));
  const auto& acc = counts[j];
  const size_t k = static_cast<size_t>(std::lower_bound(acc.begin(), acc.end(), u) - acc.begin());
  return std::min(start[j] + k, pdf.size() - 1);
}

}  // namespace carenav::localization
