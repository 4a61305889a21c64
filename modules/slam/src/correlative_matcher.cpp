#include <carenav/slam/correlative_matcher.h>

#include <algorithm>
#include <cmath>

namespace carenav::slam {

namespace {
constexpr double kDeg = M_PI / 180;
}  // namespace

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
  // The Gaussian is separable, exp(k (ex² + ey²)) = exp(k ex²) exp(k ey²):
  // 2 (2r + 1) exponentials per point instead of (2r + 1)².
  std::vector<double> fx(2 * r + 1), fy(2 * r + 1);
  for (size_t i = 0; i < xs.size(); ++i) {
    const int cx = static_cast<int>((xs[i] - x0_) / p_.cell);
    const int cy = static_cast<int>((ys[i] - y0_) / p_.cell);
    for (int d = -r; d <= r; ++d) {
      const double ex = x0_ + (cx + d + 0.5) * p_.cell - xs[i];
      const double ey = y0_ + (cy + d + 0.5) * p_.cell - ys[i];
      fx[d + r] = std::exp(k * ex * ex);
      fy[d + r] = std::exp(k * ey * ey);
    }
    for (int dy = -r; dy <= r; ++dy)
      for (int dx = -r; dx <= r; ++dx) {
        const int gx = cx + dx, gy = cy + dy;
        if (gx < 0 || gy < 0 || gx >= w_ || gy >= h_) continue;
        float& c = table_[static_cast<size_t>(gy) * w_ + gx];
        c = std::max(c, static_cast<float>(fx[dx + r] * fy[dy + r]));
      }
  }
  // Closeness g to log-likelihood ratio against an unexplained point (the
  // outlier floor): monotone, so the max over points above is the same.
  // Tabulated (cells far from every point stay 0 = log1p(0)); 4096 steps
  // of closeness are finer than the float closeness needs here.
  constexpr int kSteps = 4096;
  const double odds = (1 - p_.outlier) / p_.outlier;
  std::vector<float> lut(kSteps + 1);
  for (int i = 0; i <= kSteps; ++i) lut[i] = static_cast<float>(std::log1p(odds * i / kSteps));
  for (float& c : table_)
    if (c > 0) c = lut[static_cast<size_t>(std::lround(std::min(1.f, c) * kSteps))];
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
  return sum;
}

double CorrelativeMatcher::closeness(const std::vector<float>& xs, const std::vector<float>& ys,
                                     double x, double y, double yaw) const {
  const double c = std::cos(yaw), s = std::sin(yaw);
  const double odds = (1 - p_.outlier) / p_.outlier;
  double sum = 0;
  for (size_t i = 0; i < xs.size(); ++i)
    sum += std::expm1(lookup(x + c * xs[i] - s * ys[i], y + s * xs[i] + c * ys[i])) / odds;
  return xs.empty() ? 0 : sum / xs.size();
}

double CorrelativeMatcher::logPriorYaw(const Prior& prior, double yaw, double syaw) {
  double a2 = prior.yaws.empty() ? 0 : 1e300;
  for (const double m : prior.yaws) {
    const double a = std::remainder(yaw - m, 2 * M_PI) / syaw;
    a2 = std::min(a2, a * a);
  }
  return -0.5 * a2;
}

void CorrelativeMatcher::windowSums(const std::vector<int>& gx, const std::vector<int>& gy, int nxy,
                                    int step, std::vector<double>& sums) const {
  // Point by point, each point's row segments of the table in order: the
  // table is read along its rows instead of at random, and every pose's sum
  // still adds its points' terms in the same order (the same result, bit
  // for bit, as summing pose by pose).
  const int n = 2 * nxy + 1;
  std::fill(sums.begin(), sums.end(), 0.0);
  for (size_t k = 0; k < gx.size(); ++k) {
    // The offsets i whose cell gx[k] + (i - nxy) step lies inside [0, w).
    const int first = gx[k] - nxy * step;  // the cell of i = 0
    if (first > w_ - 1) continue;
    const int i0 = first >= 0 ? 0 : (-first + step - 1) / step;
    const int i1 = std::min(n, (w_ - 1 - first) / step + 1);
    for (int j = 0; j < n; ++j) {
      const int ty = gy[k] + (j - nxy) * step;
      if (ty < 0 || ty >= h_) continue;
      const float* row = &table_[static_cast<size_t>(ty) * w_];
      double* out = &sums[static_cast<size_t>(j) * n];
      for (int i = i0; i < i1; ++i) out[i] += row[first + i * step];
    }
  }
}

mrpt::poses::CPose2D CorrelativeMatcher::match(const mrpt::maps::CSimplePointsMap& scan,
                                               const mrpt::poses::CPose2D& prior,
                                               double* best_score, double widen_xy,
                                               double widen_yaw) const {
  const Result r = match(scan, {prior}, Prior::at(prior), widen_xy, widen_yaw);
  if (best_score) *best_score = r.closeness;
  return r.pose;
}

CorrelativeMatcher::Result CorrelativeMatcher::match(
    const mrpt::maps::CSimplePointsMap& scan, const std::vector<mrpt::poses::CPose2D>& centres,
    const Prior& motion, double widen_xy, double widen_yaw) const {
  widen_xy = std::max(1.0, widen_xy);
  widen_yaw = std::max(1.0, widen_yaw);
  Search q{motion};
  q.nxy = static_cast<int>(std::round(p_.window_xy * widen_xy / p_.coarse_xy));
  q.nyaw = static_cast<int>(std::round(std::min(180.0, p_.window_yaw * widen_yaw) / p_.coarse_yaw));
  q.sa = p_.prior_along * widen_xy;
  q.sc = p_.prior_across * widen_xy;
  q.syaw = p_.prior_yaw * widen_yaw * kDeg;
  const auto& sx = scan.getPointsBufferRef_x();
  const auto& sy = scan.getPointsBufferRef_y();
  const std::vector<float> all_x(sx.begin(), sx.end()), all_y(sy.begin(), sy.end());
  std::vector<float> cx, cy;
  const size_t stride = std::max<size_t>(1, all_x.size() / std::max<size_t>(1, p_.coarse_points));
  for (size_t i = 0; i < all_x.size(); i += stride) cx.push_back(all_x[i]), cy.push_back(all_y[i]);
  if (centres.empty()) return Result{};
  // Log-likelihood of the scan: the points' log-likelihood ratios, as many
  // of them independent as `independence` says (the coarse pass sums a
  // subset: scaled to all points).
  q.weight = cx.empty() ? 0 : p_.independence * all_x.size() / cx.size();
  const mrpt::poses::CPose2D coarse = coarsePass(q, cx, cy, centres);
  q.weight = p_.independence;
  Result best = finePass(q, all_x, all_y, coarse);
  best.closeness = closeness(all_x, all_y, best.pose.x(), best.pose.y(), best.pose.phi());
  return best;
}

mrpt::poses::CPose2D CorrelativeMatcher::coarsePass(
    const Search& q, const std::vector<float>& cx, const std::vector<float>& cy,
    const std::vector<mrpt::poses::CPose2D>& centres) const {
  // The coarse step is a whole number of table cells, so for each yaw the
  // scan points are rotated and turned into cell indices once, and every
  // translation of the window is an integer offset of those indices
  // ([Olson09csm, Sec. IV]: the rotation is the only costly part of
  // evaluating a pose).
  const int nxy = q.nxy;
  const double cells_per_step = p_.coarse_xy / p_.cell;
  const int step = static_cast<int>(std::lround(cells_per_step));
  const bool integer_steps = step >= 1 && std::abs(cells_per_step - step) < 1e-6;
  std::vector<int> gx(cx.size()), gy(cx.size());
  std::vector<double> sums((2 * nxy + 1) * (2 * nxy + 1));
  double bx = centres[0].x(), by = centres[0].y(), byaw = centres[0].phi(), top = -1e300;
  for (const auto& centre : centres)
    for (int a = -q.nyaw; a <= q.nyaw; ++a) {
      const double yaw = centre.phi() + a * p_.coarse_yaw * kDeg;
      const double yaw_prior = logPriorYaw(q.motion, yaw, q.syaw);
      const double mid = travelDirection(q.motion, yaw);
      const double mc = std::cos(mid), ms = std::sin(mid);
      auto consider = [&](double sum, double x, double y) {
        const double post =
            q.weight * sum + yaw_prior + logPriorXY(q.motion, x, y, mc, ms, q.sa, q.sc);
        if (post > top) top = post, bx = x, by = y, byaw = yaw;
      };
      if (!integer_steps) {
        for (int i = -nxy; i <= nxy; ++i)
          for (int j = -nxy; j <= nxy; ++j) {
            const double x = centre.x() + i * p_.coarse_xy, y = centre.y() + j * p_.coarse_xy;
            consider(score(cx, cy, x, y, yaw), x, y);
          }
        continue;
      }
      const double c = std::cos(yaw), s = std::sin(yaw);
      for (size_t k = 0; k < cx.size(); ++k) {
        gx[k] = static_cast<int>(
            std::floor((centre.x() + c * cx[k] - s * cy[k] - x0_) / p_.cell + 1e-9));
        gy[k] = static_cast<int>(
            std::floor((centre.y() + s * cx[k] + c * cy[k] - y0_) / p_.cell + 1e-9));
      }
      windowSums(gx, gy, nxy, step, sums);
      for (int i = -nxy; i <= nxy; ++i)
        for (int j = -nxy; j <= nxy; ++j)
          consider(sums[(j + nxy) * (2 * nxy + 1) + (i + nxy)], centre.x() + i * p_.coarse_xy,
                   centre.y() + j * p_.coarse_xy);
    }
  return mrpt::poses::CPose2D(bx, by, byaw);
}

CorrelativeMatcher::Result CorrelativeMatcher::finePass(const Search& q,
                                                        const std::vector<float>& xs,
                                                        const std::vector<float>& ys,
                                                        const mrpt::poses::CPose2D& start) const {
  // A quarter of the coarse step, four of them each side, all points.
  double bx = start.x(), by = start.y(), byaw = start.phi(), top = -1e300;
  for (int a = -4; a <= 4; ++a) {
    const double yaw = start.phi() + a * p_.coarse_yaw / 4 * kDeg;
    for (int i = -4; i <= 4; ++i)
      for (int j = -4; j <= 4; ++j) {
        const double x = start.x() + i * p_.coarse_xy / 4, y = start.y() + j * p_.coarse_xy / 4;
        const double post =
            q.weight * score(xs, ys, x, y, yaw) + logPrior(q.motion, x, y, yaw, q.sa, q.sc, q.syaw);
        if (post > top) top = post, bx = x, by = y, byaw = yaw;
      }
  }
  Result r;
  r.pose = mrpt::poses::CPose2D(bx, by, byaw);
  return r;
}

}  // namespace carenav::slam
