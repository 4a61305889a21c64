// FSPF+ plane filtering ([InterbotDepth, Alg. 3], after FSPF [Biswas12]; docs/design.md,
// 'Virtual scans'). Same draws, same arithmetic and the same planes as the plain implementation
// kept in tests/unit/perception/virtual_scans_baseline.h; faster by (docs/BENCHMARKS.md, 'Virtual
// scans: speed (issue 17)'): buffers reused from frame to frame (one workspace per thread), the
// depth test on squared distances against equivalent float limits (no sqrt per pixel), the
// window sample held as arrays of doubles, RANSAC's and fitPlane's sums written out in their
// order, and a RANSAC hypothesis abandoned as soon as it can no longer beat the best one (its
// count is only compared with the best; the random draws stay those of ransacPlane).
#include <carenav/perception/ground_plane.h>
#include <carenav/perception/virtual_scans.h>

#include "float_order.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <utility>

namespace carenav::perception {

namespace {

/** Points as three arrays of doubles (the window sample, the inliers of a hypothesis). */
struct Soa {
  std::vector<double> x, y, z;
  void clear() {
    x.clear();
    y.clear();
    z.clear();
  }
  void push(double px, double py, double pz) {
    x.push_back(px);
    y.push_back(py);
    z.push_back(pz);
  }
  size_t size() const { return x.size(); }
  Eigen::Vector3d at(size_t i) const { return {x[i], y[i], z[i]}; }
};

/** Per-thread buffers of fspfPlus, kept between frames (no allocation once warm). */
struct FspfWork {
  std::vector<int> list, where;  ///< eligible pixels; position of a pixel in `list` or -1
  std::vector<double> ang;
  std::vector<int> in;  ///< window inliers (buffer of the largest window so far)
  Soa sample, inliers;
};

/** Points of `s` within `thr` of `pl` (Plane::distance, the same operation order). When
 *  `beat` >= 0, stops as soon as the count can no longer exceed `beat` and returns what it has
 *  (then <= beat). */
CARENAV_VECTOR_CLONES size_t countInliers(const Soa& s, const Plane& pl, double thr, long beat) {
  const size_t n = s.size();
  const double* x = s.x.data();
  const double* y = s.y.data();
  const double* z = s.z.data();
  size_t count = 0;
  constexpr size_t kBlock = 64;
  for (size_t i0 = 0; i0 < n; i0 += kBlock) {
    if (beat >= 0 && static_cast<long>(count + (n - i0)) <= beat) break;
    const size_t i1 = std::min(n, i0 + kBlock);
    for (size_t i = i0; i < i1; ++i)
      count += std::abs(pl.a * x[i] + pl.b * y[i] + pl.c * z[i] + pl.d) <= thr ? 1 : 0;
  }
  return count;
}

/** fitPlane (ground_plane.cpp) on the points of `s`: the same sums in the same order, the same
 *  eigen solver, hence the same plane. */
std::optional<Plane> fitPlaneSoa(const Soa& s) {
  const size_t n = s.size();
  if (n < 3) return std::nullopt;
  double mx = 0, my = 0, mz = 0;
  for (size_t i = 0; i < n; ++i) {
    mx += s.x[i];
    my += s.y[i];
    mz += s.z[i];
  }
  const double dn = static_cast<double>(n);
  mx /= dn;
  my /= dn;
  mz /= dn;
  double xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
  for (size_t i = 0; i < n; ++i) {
    const double qx = s.x[i] - mx, qy = s.y[i] - my, qz = s.z[i] - mz;
    xx += qx * qx;
    xy += qy * qx;
    xz += qz * qx;
    yy += qy * qy;
    yz += qz * qy;
    zz += qz * qz;
  }
  Eigen::Matrix3d cov;
  cov << xx, xy, xz, xy, yy, yz, xz, yz, zz;
  cov /= dn;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  const auto& ev = es.eigenvalues();                      // ascending
  if (ev(1) <= 1e-9 + 1e-6 * ev(2)) return std::nullopt;  // collinear (or one point)
  return Plane::fromPointNormal(Eigen::Vector3d(mx, my, mz), es.eigenvectors().col(0));
}

/** ransacPlane (ground_plane.cpp) on the points of `s`: same draws, same best hypothesis. */
RansacResult ransacSoa(const Soa& s, Soa& inliers, int iterations, double threshold,
                       std::mt19937& rng) {
  RansacResult r;
  const size_t n = s.size();
  if (n < 3) return r;
  std::uniform_int_distribution<size_t> pick(0, n - 1);
  size_t best = 0;
  Plane best_plane;
  for (int it = 0; it < iterations; ++it) {
    const size_t i0 = pick(rng), i1 = pick(rng), i2 = pick(rng);
    if (i0 == i1 || i0 == i2 || i1 == i2) continue;
    const Eigen::Vector3d p0 = s.at(i0);
    const Eigen::Vector3d nrm = (s.at(i1) - p0).cross(s.at(i2) - p0);
    if (nrm.norm() < 1e-9) continue;
    const Plane pl = Plane::fromPointNormal(p0, nrm);
    const size_t count = countInliers(s, pl, threshold, static_cast<long>(best));
    if (count > best) {
      best = count;
      best_plane = pl;
    }
  }
  if (best < 3) return r;
  inliers.clear();
  for (size_t i = 0; i < n; ++i)
    if (best_plane.distance(s.x[i], s.y[i], s.z[i]) <= threshold)
      inliers.push(s.x[i], s.y[i], s.z[i]);
  const auto refined = fitPlaneSoa(inliers);
  r.plane = refined ? *refined : best_plane;
  r.inliers = countInliers(s, *r.plane, threshold, -1);
  return r;
}

/** Squared sensor distance of q in float, the operations of the plain implementation's dist()
 *  before its sqrt. */
float squaredRange(const Point3f& q, const Point3f& o) {
  return (q.x - o.x) * (q.x - o.x) + (q.y - o.y) * (q.y - o.y) + (q.z - o.z) * (q.z - o.z);
}
/** Distance to the sensor as the plain implementation's dist() gives it. */
double range(const Point3f& q, const Point3f& o) { return std::sqrt(squaredRange(q, o)); }

/** Squared-distance limits [lo, hi] equivalent to depth_min <= sqrtf(s) <= depth_max in double
 *  (sqrtf is monotone): the depth test without a sqrt per pixel. */
std::pair<float, float> squaredLimits(double dmin, double dmax) {
  const float big = std::numeric_limits<float>::max();
  const auto above = [&](float s) { return static_cast<double>(std::sqrt(s)) >= dmin; };
  const auto below = [&](float s) { return static_cast<double>(std::sqrt(s)) <= dmax; };
  const float lo = above(0.f) ? -1.f : (above(big) ? detail::lastInside(big, 0.f, above) : 2 * big);
  const float hi = !below(0.f) ? -2.f : (below(big) ? big : detail::lastInside(0.f, big, below));
  return {lo, hi};
}

/** ok[j] = 1 when pts[j] is valid (validPoint) and its squared distance to o is in [lo, hi]:
 *  straight-line code the compiler vectorises. */
CARENAV_VECTOR_CLONES void eligibleFlags(const Point3f* pts, size_t m, const Point3f& o, float lo,
                                         float hi, int32_t* ok) {
  for (size_t j = 0; j < m; ++j) {
    const Point3f& q = pts[j];
    const float s = squaredRange(q, o);
    ok[j] = (std::abs(q.x) < 1e6f) & (std::abs(q.y) < 1e6f) & (std::abs(q.z) < 1e6f) &
            !((q.x == 0.f) & (q.y == 0.f) & (q.z == 0.f)) & (s >= lo) & (s <= hi);
  }
}

/** depthConstraints: eligible pixels (valid, depth_min..depth_max from the sensor) into
 *  w.list / w.where. Branch-free: every pixel is written to the list's end, which advances for
 *  the eligible ones. */
void eligiblePixels(const Cloud& c, const Point3f& o, const PerceptionParams& p, FspfWork& w) {
  const size_t n = c.points.size();
  const auto [lo, hi] = squaredLimits(p.depth_min, p.depth_max);
  w.where.resize(n);
  w.list.resize(n);
  int* where = w.where.data();
  int* list = w.list.data();
  int count = 0;
  constexpr size_t kChunk = 1024;
  int32_t ok[kChunk];
  for (size_t k0 = 0; k0 < n; k0 += kChunk) {
    const size_t m = std::min(kChunk, n - k0);
    eligibleFlags(c.points.data() + k0, m, o, lo, hi, ok);
    for (size_t j = 0; j < m; ++j) {
      where[k0 + j] = ok[j] ? count : -1;
      list[count] = static_cast<int>(k0 + j);
      count += ok[j];
    }
  }
  w.list.resize(static_cast<size_t>(count));
}

/** Focal length (px) from the angle between horizontally adjacent pixels. */
double focalLength(const Cloud& c, const Point3f& origin, FspfWork& w) {
  const size_t W = c.width;
  const Eigen::Vector3d o(origin.x, origin.y, origin.z);
  w.ang.clear();
  for (size_t k = 0; k + 1 < c.points.size() && w.ang.size() < 2000; k += 97) {
    if (w.where[k] < 0 || (k + 1) % W == 0 || w.where[k + 1] < 0) continue;
    const Point3f &qa = c.points[k], &qb = c.points[k + 1];
    const Eigen::Vector3d a = Eigen::Vector3d(qa.x, qa.y, qa.z) - o,
                          b = Eigen::Vector3d(qb.x, qb.y, qb.z) - o;
    const double t = std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0));
    if (t > 1e-6) w.ang.push_back(t);
  }
  double f = static_cast<double>(W) / (2 * std::tan(35.3 * M_PI / 180));  // Kinect One default
  if (!w.ang.empty()) {
    std::nth_element(w.ang.begin(), w.ang.begin() + w.ang.size() / 2, w.ang.end());
    f = 1.0 / w.ang[w.ang.size() / 2];
  }
  return f;
}

void removePixel(FspfWork& w, int k) {
  const int pos = w.where[k];
  if (pos < 0) return;
  const int last = w.list.back();
  w.list[pos] = last;
  w.where[last] = pos;
  w.list.pop_back();
  w.where[k] = -1;
}

/** Two more eligible pixels within +-Omega of k0 (up to 10 draws each); false when missing. */
bool drawNeighbours(const FspfWork& w, int k0, int W, int H, int omega, std::mt19937& rng,
                    int ks[2]) {
  const int u0 = k0 % W, v0 = k0 / W;
  std::uniform_int_distribution<int> off(-omega, omega);
  ks[0] = ks[1] = -1;
  for (int s = 0; s < 2; ++s)
    for (int tries = 0; tries < 10 && ks[s] < 0; ++tries) {
      const int u = u0 + off(rng), v = v0 + off(rng);
      if (u < 0 || v < 0 || u >= W || v >= H) continue;
      const int k = v * W + u;
      if (w.where[k] >= 0 && k != k0) ks[s] = k;
    }
  return ks[0] >= 0 && ks[1] >= 0 && ks[0] != ks[1];
}

/** Image window of a hypothesis: columns u0..u1, rows v0..v1 (inclusive). */
struct Window {
  int u0, u1, v0, v1;
};

/** Eligible pixels of `win` within epsilon of `pl` into in[0, count) (row-major; `in` holds
 *  the window's area), their mean into `cen` (the running sum of the plain implementation:
 *  adding +0.0 for the others leaves it unchanged, as it never is -0.0). Branch-free. */
size_t windowInliers(const Cloud& c, const FspfWork& w, const Window& win, const Plane& pl,
                     double eps, Eigen::Vector3d& cen, int* in) {
  const int W = static_cast<int>(c.width);
  const int* where = w.where.data();
  const Point3f* pts = c.points.data();
  size_t count = 0;
  double cx = 0, cy = 0, cz = 0;
  for (int v = win.v0; v <= win.v1; ++v)
    for (int k = v * W + win.u0, k1 = v * W + win.u1; k <= k1; ++k) {
      const Point3f& q = pts[k];
      const bool ok =
          (where[k] >= 0) & (std::abs(pl.a * q.x + pl.b * q.y + pl.c * q.z + pl.d) <= eps);
      in[count] = k;
      count += ok ? 1 : 0;
      cx += ok ? static_cast<double>(q.x) : 0.0;
      cy += ok ? static_cast<double>(q.y) : 0.0;
      cz += ok ? static_cast<double>(q.z) : 0.0;
    }
  cen = {cx, cy, cz};
  return count;
}

/** normalRectifier: plane class from the normal and the centroid (robot frame). */
PlaneClass classify(const Plane& pl, const Eigen::Vector3d& cen, const Point3f& origin) {
  static const double cos_h = std::cos(25 * M_PI / 180);
  if (std::abs(pl.c) >= cos_h)
    return cen.z() < 0.1 ? PlaneClass::Ground
                         : (cen.z() > origin.z ? PlaneClass::Ceiling : PlaneClass::Other);
  if (std::abs(pl.a) >= std::abs(pl.b)) return PlaneClass::Front;
  return cen.y() > 0 ? PlaneClass::LeftWall : PlaneClass::RightWall;
}

}  // namespace

FspfResult fspfPlus(const Cloud& c, const Point3f& origin, const PerceptionParams& p) {
  FspfResult r;
  if (!c.organised()) return r;
  thread_local FspfWork w;
  const int W = static_cast<int>(c.width), H = static_cast<int>(c.height);
  r.pixel_class.assign(c.points.size(), PlaneClass::None);
  eligiblePixels(c, origin, p, w);
  r.eligible = w.list.size();
  if (w.list.empty()) return r;
  const double f = focalLength(c, origin, w);
  std::mt19937 rng(static_cast<uint32_t>(p.seed));
  const size_t n_required = static_cast<size_t>(p.fspf_stop_fraction * r.eligible);
  const int max_iter = 20000;
  while (w.list.size() > n_required && r.iterations < max_iter) {
    ++r.iterations;
    const int k0 = w.list[std::uniform_int_distribution<size_t>(0, w.list.size() - 1)(rng)];
    const int u0 = k0 % W, v0 = k0 / W;
    int ks[2];
    if (!drawNeighbours(w, k0, W, H, p.fspf_omega, rng, ks)) {
      removePixel(w, k0);  // no support around p0: it cannot seed a plane
      continue;
    }
    const double zbar = (range(c.points[k0], origin) + range(c.points[ks[0]], origin) +
                         range(c.points[ks[1]], origin)) /
                        3;
    const int half = std::max(2, static_cast<int>(0.5 * p.fspf_window * f / zbar));
    const Window win{std::max(0, u0 - half), std::min(W - 1, u0 + half), std::max(0, v0 - half),
                     std::min(H - 1, v0 + half)};
    // imageSearchWindow3DPoints: eligible pixels of the window (sub-sampled for the hypotheses
    // when the window is large).
    const int stride = std::max(1, (2 * half + 1) / 40);
    w.sample.clear();
    for (int v = win.v0; v <= win.v1; v += stride)
      for (int u = win.u0; u <= win.u1; u += stride)
        if (w.where[v * W + u] >= 0) {
          const Point3f& q = c.points[v * W + u];
          w.sample.push(q.x, q.y, q.z);
        }
    const auto rr = ransacSoa(w.sample, w.inliers, 20, p.fspf_epsilon, rng);
    if (!rr.plane || rr.inliers * stride * stride < static_cast<size_t>(p.fspf_n_min)) {
      removePixel(w, k0);
      continue;
    }
    const Plane pl = *rr.plane;
    Eigen::Vector3d cen;
    const size_t area = static_cast<size_t>(win.u1 - win.u0 + 1) * (win.v1 - win.v0 + 1);
    if (w.in.size() < area) w.in.resize(area);
    const size_t n_in = windowInliers(c, w, win, pl, p.fspf_epsilon, cen, w.in.data());
    if (static_cast<int>(n_in) <= p.fspf_n_min) {
      removePixel(w, k0);
      continue;
    }
    cen /= static_cast<double>(n_in);
    const PlaneClass cls = classify(pl, cen, origin);
    const bool drop = cls == PlaneClass::Ground || cls == PlaneClass::Ceiling;
    drop ? ++r.planes_dropped : ++r.planes;
    for (size_t t = 0; t < n_in; ++t) {
      const int k = w.in[t];
      r.pixel_class[k] = cls;
      if (!drop) r.filtered.points.push_back(c.points[k]);
      removePixel(w, k);
    }
  }
  r.filtered.width = r.filtered.points.size();
  return r;
}

}  // namespace carenav::perception
