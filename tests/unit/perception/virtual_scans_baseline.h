// The virtual-scan implementations as they were before the speed work of issue 17 (FSPF+ and the
// Kinect Obstacle Scan, docs/design.md, 'Virtual scans'), kept verbatim as the reference: the unit
// tests (test_virtual_scans_speed.cpp) compare the optimised versions against them and
// bench_perception measures both in one run (*Baseline). Not used by the library.
#pragma once

#include <carenav/perception/ground_plane.h>
#include <carenav/perception/virtual_scans.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace carenav_test {
using namespace carenav::perception;

namespace baseline_detail {
inline Eigen::Vector3d v3(const Point3f& p) { return {p.x, p.y, p.z}; }
inline double dist(const Point3f& a, const Point3f& b) {
  return std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) +
                   (a.z - b.z) * (a.z - b.z));
}
}  // namespace baseline_detail
using namespace baseline_detail;

inline FspfResult fspfPlusBaseline(const Cloud& c, const Point3f& origin,
                                   const PerceptionParams& p) {
  FspfResult r;
  if (!c.organised()) return r;
  const int W = static_cast<int>(c.width), H = static_cast<int>(c.height);
  r.pixel_class.assign(c.points.size(), PlaneClass::None);
  // depthConstraints: eligible pixels; list + position for O(1) removal.
  std::vector<int> list, where(c.points.size(), -1);
  for (size_t k = 0; k < c.points.size(); ++k) {
    if (!validPoint(c.points[k])) continue;
    const double d = dist(c.points[k], origin);
    if (d < p.depth_min || d > p.depth_max) continue;
    where[k] = static_cast<int>(list.size());
    list.push_back(static_cast<int>(k));
  }
  r.eligible = list.size();
  if (list.empty()) return r;
  auto remove = [&](int k) {
    const int pos = where[k];
    if (pos < 0) return;
    const int last = list.back();
    list[pos] = last;
    where[last] = pos;
    list.pop_back();
    where[k] = -1;
  };
  // Focal length (px) from the angle between horizontally adjacent pixels.
  std::vector<double> ang;
  for (size_t k = 0; k + 1 < c.points.size() && ang.size() < 2000; k += 97) {
    if (where[k] < 0 || (k + 1) % W == 0 || where[k + 1] < 0) continue;
    const Eigen::Vector3d a = v3(c.points[k]) - v3(origin), b = v3(c.points[k + 1]) - v3(origin);
    const double t = std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0));
    if (t > 1e-6) ang.push_back(t);
  }
  double f = W / (2 * std::tan(35.3 * M_PI / 180));  // Kinect One if nothing to measure
  if (!ang.empty()) {
    std::nth_element(ang.begin(), ang.begin() + ang.size() / 2, ang.end());
    f = 1.0 / ang[ang.size() / 2];
  }
  std::mt19937 rng(static_cast<uint32_t>(p.seed));
  const size_t n_required = static_cast<size_t>(p.fspf_stop_fraction * r.eligible);
  const int max_iter = 20000;
  const double cos_h = std::cos(25 * M_PI / 180);
  while (list.size() > n_required && r.iterations < max_iter) {
    ++r.iterations;
    const int k0 = list[std::uniform_int_distribution<size_t>(0, list.size() - 1)(rng)];
    const int u0 = k0 % W, v0 = k0 / W;
    std::uniform_int_distribution<int> off(-p.fspf_omega, p.fspf_omega);
    int ks[2] = {-1, -1};
    for (int s = 0; s < 2; ++s)
      for (int tries = 0; tries < 10 && ks[s] < 0; ++tries) {
        const int u = u0 + off(rng), v = v0 + off(rng);
        if (u < 0 || v < 0 || u >= W || v >= H) continue;
        const int k = v * W + u;
        if (where[k] >= 0 && k != k0) ks[s] = k;
      }
    if (ks[0] < 0 || ks[1] < 0 || ks[0] == ks[1]) {
      remove(k0);  // no support around p0: it cannot seed a plane
      continue;
    }
    const double zbar = (dist(c.points[k0], origin) + dist(c.points[ks[0]], origin) +
                         dist(c.points[ks[1]], origin)) /
                        3;
    const int half = std::max(2, static_cast<int>(0.5 * p.fspf_window * f / zbar));
    // imageSearchWindow3DPoints: eligible pixels of the window (sub-sampled
    // for the hypotheses when the window is large).
    const int stride = std::max(1, (2 * half + 1) / 40);
    std::vector<Eigen::Vector3d> sample;
    for (int v = std::max(0, v0 - half); v <= std::min(H - 1, v0 + half); v += stride)
      for (int u = std::max(0, u0 - half); u <= std::min(W - 1, u0 + half); u += stride)
        if (where[v * W + u] >= 0) sample.push_back(v3(c.points[v * W + u]));
    auto rr = ransacPlane(sample, 20, p.fspf_epsilon, rng);
    if (!rr.plane || rr.inliers * stride * stride < static_cast<size_t>(p.fspf_n_min)) {
      remove(k0);
      continue;
    }
    const Plane pl = *rr.plane;
    std::vector<int> in;
    Eigen::Vector3d cen = Eigen::Vector3d::Zero();
    for (int v = std::max(0, v0 - half); v <= std::min(H - 1, v0 + half); ++v)
      for (int u = std::max(0, u0 - half); u <= std::min(W - 1, u0 + half); ++u) {
        const int k = v * W + u;
        if (where[k] < 0) continue;
        const Point3f& q = c.points[k];
        if (pl.distance(q.x, q.y, q.z) <= p.fspf_epsilon) {
          in.push_back(k);
          cen += v3(q);
        }
      }
    if (static_cast<int>(in.size()) <= p.fspf_n_min) {
      remove(k0);
      continue;
    }
    cen /= static_cast<double>(in.size());
    // normalRectifier: plane class from normal and centroid (robot frame).
    PlaneClass cls;
    if (std::abs(pl.c) >= cos_h) {
      cls = cen.z() < 0.1 ? PlaneClass::Ground
                          : (cen.z() > origin.z ? PlaneClass::Ceiling : PlaneClass::Other);
    } else if (std::abs(pl.a) >= std::abs(pl.b)) {
      cls = PlaneClass::Front;
    } else {
      cls = cen.y() > 0 ? PlaneClass::LeftWall : PlaneClass::RightWall;
    }
    const bool drop = cls == PlaneClass::Ground || cls == PlaneClass::Ceiling;
    drop ? ++r.planes_dropped : ++r.planes;
    for (int k : in) {
      r.pixel_class[k] = cls;
      if (!drop) r.filtered.points.push_back(c.points[k]);
      remove(k);
    }
  }
  r.filtered.width = r.filtered.points.size();
  return r;
}

namespace baseline_detail {
inline size_t binsFor(const PerceptionParams& p) {
  return static_cast<size_t>(std::lround(360.0 / p.scan_resolution));
}
template <class Keep, class Better>
std::vector<float> binRanges(const Cloud& c, size_t n, Keep keep, Better better) {
  std::vector<float> r(n, -1.f);
  const double bin = 2 * M_PI / n;
  for (const auto& q : c.points) {
    if (!validPoint(q) || !keep(q)) continue;
    const float d = std::hypot(q.x, q.y);
    const size_t b = std::min(n - 1, static_cast<size_t>((std::atan2(q.y, q.x) + M_PI) / bin));
    if (r[b] < 0 || better(d, r[b])) r[b] = d;
  }
  return r;
}
}  // namespace baseline_detail

inline mrpt::obs::CObservation2DRangeScan kinectObstacleScanBaseline(const Cloud& c,
                                                                     const PerceptionParams& p) {
  const size_t n = baseline_detail::binsFor(p);
  std::vector<float> merged(n, -1.f);
  for (double h : p.kosHeights()) {
    auto lv = baseline_detail::binRanges(
        c, n, [&](const Point3f& q) { return std::abs(q.z - h) <= p.kos_band; },
        [](float a, float b) { return a < b; });
    for (size_t k = 0; k < n; ++k)
      if (lv[k] > 0 && (merged[k] < 0 || lv[k] < merged[k])) merged[k] = lv[k];
  }
  return makeScan(merged, 0.0, p.depth_max, "KOS");
}

}  // namespace carenav_test
