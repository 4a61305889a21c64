#include <carenav/slam/correlative_matcher.h>

#include <algorithm>
#include <cmath>

namespace carenav::slam {

void CorrelativeMatcher::setReference(const mrpt::maps::CSimplePointsMap& ref) {
  const auto& xs = ref.getPointsBufferRef_x();
  const auto& ys = ref.getPointsBufferRef_y();
  table_.clear();
  w_ = h_ = 0;
  if (xs.empty()) return;
  const double margin = p_.window_xy + 3 * p_.sigma + 30;  // scans reach far
  const auto [xmin, xmax] = std::minmax_element(xs.begin(), xs.end());
  const auto [ymin, ymax] = std::minmax_element(ys.begin(), ys.end());
  x0_ = *xmin - 3 * p_.sigma;
  y0_ = *ymin - 3 * p_.sigma;
  w_ = static_cast<int>((*xmax - *xmin + 6 * p_.sigma) / p_.cell) + 1;
  h_ = static_cast<int>((*ymax - *ymin + 6 * p_.sigma) / p_.cell) + 1;
  (void)margin;
  table_.assign(static_cast<size_t>(w_) * h_, 0.f);
  const int r = static_cast<int>(std::ceil(3 * p_.sigma / p_.cell));
  const double k = -0.5 / (p_.sigma * p_.sigma);
  for (size_t i = 0; i < xs.size(); ++i) {
    const int cx = static_cast<int>((xs[i] - x0_) / p_.cell);
    const int cy = static_cast<int>((ys[i] - y0_) / p_.cell);
    for (int dy = -r; dy <= r; ++dy)
      for (int dx = -r; dx <= r; ++dx) {
        const int gx = cx + dx, gy = cy + dy;
        if (gx < 0 || gy < 0 || gx >= w_ || gy >= h_) continue;
        const double ex = x0_ + (gx + 0.5) * p_.cell - xs[i];
        const double ey = y0_ + (gy + 0.5) * p_.cell - ys[i];
        float& c = table_[static_cast<size_t>(gy) * w_ + gx];
        c = std::max(c, static_cast<float>(std::exp(k * (ex * ex + ey * ey))));
      }
  }
}

double CorrelativeMatcher::lookup(double x, double y) const {
  const int gx = static_cast<int>((x - x0_) / p_.cell);
  const int gy = static_cast<int>((y - y0_) / p_.cell);
  if (gx < 0 || gy < 0 || gx >= w_ || gy >= h_) return 0;
  return table_[static_cast<size_t>(gy) * w_ + gx];
}

double CorrelativeMatcher::score(const std::vector<float>& xs, const std::vector<float>& ys,
                                 double x, double y, double yaw) const {
  const double c = std::cos(yaw), s = std::sin(yaw);
  double sum = 0;
  for (size_t i = 0; i < xs.size(); ++i)
    sum += lookup(x + c * xs[i] - s * ys[i], y + s * xs[i] + c * ys[i]);
  return xs.empty() ? 0 : sum / xs.size();
}

mrpt::poses::CPose2D CorrelativeMatcher::match(const mrpt::maps::CSimplePointsMap& scan,
                                               const mrpt::poses::CPose2D& prior,
                                               double* best_score) const {
  const auto& sx = scan.getPointsBufferRef_x();
  const auto& sy = scan.getPointsBufferRef_y();
  std::vector<float> all_x(sx.begin(), sx.end()), all_y(sy.begin(), sy.end());
  std::vector<float> cx, cy;
  const size_t stride = std::max<size_t>(1, all_x.size() / std::max<size_t>(1, p_.coarse_points));
  for (size_t i = 0; i < all_x.size(); i += stride) cx.push_back(all_x[i]), cy.push_back(all_y[i]);
  const double deg = M_PI / 180;
  auto penalised = [&](double sc, double x, double y, double yaw) {
    const double d = std::hypot(x - prior.x(), y - prior.y());
    const double a = std::abs(std::remainder(yaw - prior.phi(), 2 * M_PI)) / (10 * deg);
    return sc - p_.prior_weight * (d + a);
  };
  // Coarse pass over the whole window.
  double bx = prior.x(), by = prior.y(), byaw = prior.phi(), best = -1e9;
  const int nxy = static_cast<int>(std::round(p_.window_xy / p_.coarse_xy));
  const int nyaw = static_cast<int>(std::round(p_.window_yaw / p_.coarse_yaw));
  for (int a = -nyaw; a <= nyaw; ++a) {
    const double yaw = prior.phi() + a * p_.coarse_yaw * deg;
    for (int i = -nxy; i <= nxy; ++i)
      for (int j = -nxy; j <= nxy; ++j) {
        const double x = prior.x() + i * p_.coarse_xy, y = prior.y() + j * p_.coarse_xy;
        const double sc = penalised(score(cx, cy, x, y, yaw), x, y, yaw);
        if (sc > best) best = sc, bx = x, by = y, byaw = yaw;
      }
  }
  // Fine pass around the coarse optimum, all points.
  const double fx = bx, fy = by, fyaw = byaw;
  best = -1e9;
  for (int a = -4; a <= 4; ++a) {
    const double yaw = fyaw + a * p_.coarse_yaw / 4 * deg;
    for (int i = -4; i <= 4; ++i)
      for (int j = -4; j <= 4; ++j) {
        const double x = fx + i * p_.coarse_xy / 4, y = fy + j * p_.coarse_xy / 4;
        const double sc = penalised(score(all_x, all_y, x, y, yaw), x, y, yaw);
        if (sc > best) best = sc, bx = x, by = y, byaw = yaw;
      }
  }
  if (best_score) *best_score = score(all_x, all_y, bx, by, byaw);
  return mrpt::poses::CPose2D(bx, by, byaw);
}

}  // namespace carenav::slam
