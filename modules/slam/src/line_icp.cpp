#include <carenav/slam/line_icp.h>

#include <mrpt/math/wrap2pi.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace carenav::slam {

using mrpt::poses::CPose2D;

LineIcp::Line LineIcp::Line::transformed(const CPose2D& frame) const {
  const double c = std::cos(frame.phi()), s = std::sin(frame.phi());
  Line l;
  l.nx = static_cast<float>(c * nx - s * ny);
  l.ny = static_cast<float>(s * nx + c * ny);
  l.mx = static_cast<float>(frame.x() + c * mx - s * my);
  l.my = static_cast<float>(frame.y() + s * mx + c * my);
  return l;
}

std::vector<LineIcp::Line> LineIcp::fitLines(const mrpt::maps::CSimplePointsMap& pts,
                                             const Parameters& p) {
  std::vector<Line> out(pts.size());
  if (pts.size() < p.normal_neighbours) return out;
  const auto& xs = pts.getPointsBufferRef_x();
  const auto& ys = pts.getPointsBufferRef_y();
  for (size_t i = 0; i < pts.size(); ++i) out[i] = fitLine(pts, xs[i], ys[i], p);
  return out;
}

void LineIcp::setReference(const mrpt::maps::CSimplePointsMap& ref) {
  setReference(ref, fitLines(ref, p_));
}

void LineIcp::setReference(const mrpt::maps::CSimplePointsMap& ref, std::vector<Line> lines) {
  ref_ = ref;
  ref_.mark_as_modified();
  line_ = std::move(lines);
  line_.resize(ref_.size());
  lines_ = 0;
  for (const Line& l : line_) lines_ += l.valid();
}

/** The line through the neighbours of (x, y) in `pts`: their mean and the
 *  direction of least spread (principal components of their scatter). */
LineIcp::Line LineIcp::fitLine(const mrpt::maps::CSimplePointsMap& pts, float x, float y,
                               const Parameters& p) {
  const auto& xs = pts.getPointsBufferRef_x();
  const auto& ys = pts.getPointsBufferRef_y();
  std::vector<size_t> idx;
  std::vector<float> d2;
  pts.kdTreeNClosestPoint2DIdx(x, y, p.normal_neighbours, idx, d2);
  const double r2 = p.normal_radius * p.normal_radius;
  double sx = 0, sy = 0;
  size_t n = 0;
  for (size_t k = 0; k < idx.size(); ++k)
    if (d2[k] <= r2) sx += xs[idx[k]], sy += ys[idx[k]], ++n;
  if (n < 3) return {};
  const double mx = sx / n, my = sy / n;
  double cxx = 0, cxy = 0, cyy = 0;
  for (size_t k = 0; k < idx.size(); ++k) {
    if (d2[k] > r2) continue;
    const double dx = xs[idx[k]] - mx, dy = ys[idx[k]] - my;
    cxx += dx * dx, cxy += dx * dy, cyy += dy * dy;
  }
  cxx /= n, cxy /= n, cyy /= n;
  // Smaller eigenvalue of the 2x2 scatter and its eigenvector (the normal).
  const double tr = cxx + cyy, det = cxx * cyy - cxy * cxy;
  const double lmin = 0.5 * tr - std::sqrt(std::max(0.0, 0.25 * tr * tr - det));
  if (lmin > p.max_line_rms * p.max_line_rms) return {};
  double nx = cxy, ny = lmin - cxx;  // (A - lmin I) v = 0
  if (std::abs(nx) + std::abs(ny) < 1e-12) nx = lmin - cyy, ny = cxy;
  const double norm = std::hypot(nx, ny);
  if (norm < 1e-12) return {};
  return {static_cast<float>(nx / norm), static_cast<float>(ny / norm), static_cast<float>(mx),
          static_cast<float>(my)};
}

LineIcp::Result LineIcp::align(const mrpt::maps::CSimplePointsMap& scan, const CPose2D& start,
                               const PoseGaussian* prior) const {
  Result res;
  res.pose = start;
  const auto& px = scan.getPointsBufferRef_x();
  const auto& py = scan.getPointsBufferRef_y();
  Eigen::Matrix3d prior_info = Eigen::Matrix3d::Zero();
  if (prior) prior_info = prior->cov.asEigen().inverse();
  const double w0 = p_.independence / (p_.sigma * p_.sigma);
  Eigen::Matrix3d h = prior_info;
  double x = start.x(), y = start.y(), th = start.phi();
  for (int it = 0; it < p_.iterations; ++it) {
    const double frac = p_.iterations > 1 ? std::min(1.0, 2.0 * it / p_.iterations) : 1.0;
    const double pair = p_.pair_first + (p_.pair_last - p_.pair_first) * frac;
    const double c = std::cos(th), s = std::sin(th);
    h = prior_info;
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    size_t pairs = 0;
    if (ref_.size() > 0)
      for (size_t i = 0; i < px.size(); ++i) {
        const double qx = x + c * px[i] - s * py[i], qy = y + s * px[i] + c * py[i];
        float d2 = 0, fx, fy;
        const size_t j =
            ref_.kdTreeClosestPoint2D(static_cast<float>(qx), static_cast<float>(qy), fx, fy, d2);
        if (d2 > pair * pair) continue;
        const Line& l = line_[j];
        if (!l.valid()) continue;
        const double r = l.nx * (qx - l.mx) + l.ny * (qy - l.my);
        const double k = p_.huber * p_.sigma;
        const double w = w0 * (std::abs(r) <= k ? 1.0 : k / std::abs(r));
        const Eigen::Vector3d jac(l.nx, l.ny,
                                  l.nx * (-s * px[i] - c * py[i]) + l.ny * (c * px[i] - s * py[i]));
        h += w * jac * jac.transpose();
        g += w * jac * r;
        ++pairs;
      }
    if (prior) {
      const Eigen::Vector3d e(x - prior->mean.x(), y - prior->mean.y(),
                              mrpt::math::wrapToPi(th - prior->mean.phi()));
      g += prior_info * e;
    }
    res.pairs = pairs;
    if (pairs < 3 && !prior) break;
    const Eigen::Vector3d dx = -(h + 1e-9 * Eigen::Matrix3d::Identity()).ldlt().solve(g);
    x += dx(0), y += dx(1), th = mrpt::math::wrapToPi(th + dx(2));
    if (frac >= 1.0 && dx.head<2>().norm() < 1e-4 && std::abs(dx(2)) < 1e-5) break;
  }
  res.pose = CPose2D(x, y, th);
  res.inliers = px.empty() ? 0.0 : static_cast<double>(res.pairs) / px.size();
  res.cov = mrpt::math::CMatrixDouble33((h + 1e-9 * Eigen::Matrix3d::Identity()).inverse());
  return res;
}

}  // namespace carenav::slam
