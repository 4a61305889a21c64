#include <carenav/perception/ground_plane.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace carenav::perception {

std::optional<double> Plane::zAt(double x, double y) const {
  if (std::abs(c) < 0.1) return std::nullopt;
  return -(a * x + b * y + d) / c;
}

Plane Plane::fromPointNormal(const Eigen::Vector3d& p, Eigen::Vector3d n) {
  n.normalize();
  if (n.z() < 0) n = -n;
  Plane pl;
  pl.a = n.x();
  pl.b = n.y();
  pl.c = n.z();
  pl.d = -n.dot(p);
  return pl;
}

std::optional<Plane> fitPlane(const std::vector<Eigen::Vector3d>& pts) {
  if (pts.size() < 3) return std::nullopt;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : pts) mean += p;
  mean /= static_cast<double>(pts.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : pts) {
    const Eigen::Vector3d q = p - mean;
    cov += q * q.transpose();
  }
  cov /= static_cast<double>(pts.size());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  const auto& ev = es.eigenvalues();                      // ascending
  if (ev(1) <= 1e-9 + 1e-6 * ev(2)) return std::nullopt;  // collinear (or one point)
  return Plane::fromPointNormal(mean, es.eigenvectors().col(0));
}

RansacResult ransacPlane(const std::vector<Eigen::Vector3d>& pts, int iterations, double threshold,
                         std::mt19937& rng) {
  RansacResult r;
  const size_t n = pts.size();
  if (n < 3) return r;
  std::uniform_int_distribution<size_t> pick(0, n - 1);
  size_t best = 0;
  Plane best_plane;
  for (int it = 0; it < iterations; ++it) {
    const size_t i0 = pick(rng), i1 = pick(rng), i2 = pick(rng);
    if (i0 == i1 || i0 == i2 || i1 == i2) continue;
    const Eigen::Vector3d nrm = (pts[i1] - pts[i0]).cross(pts[i2] - pts[i0]);
    if (nrm.norm() < 1e-9) continue;
    const Plane pl = Plane::fromPointNormal(pts[i0], nrm);
    size_t count = 0;
    for (const auto& p : pts)
      if (pl.distance(p.x(), p.y(), p.z()) <= threshold) ++count;
    if (count > best) {
      best = count;
      best_plane = pl;
    }
  }
  if (best < 3) return r;
  std::vector<Eigen::Vector3d> in;
  in.reserve(best);
  for (const auto& p : pts)
    if (best_plane.distance(p.x(), p.y(), p.z()) <= threshold) in.push_back(p);
  const auto refined = fitPlane(in);
  r.plane = refined ? *refined : best_plane;
  r.inliers = 0;
  for (const auto& p : pts)
    if (r.plane->distance(p.x(), p.y(), p.z()) <= threshold) ++r.inliers;
  return r;
}

std::optional<Plane> localPlane(const ElevationGrid& g, double x, double y, int s) {
  const int ci = g.cellOf(x), cj = g.cellOf(y), h = s / 2;
  thread_local std::vector<Eigen::Vector3d> pts;  // reused: no allocation per call
  pts.clear();
  for (int i = ci - h; i <= ci + h; ++i)
    for (int j = cj - h; j <= cj + h; ++j) {
      if (!g.inside(i, j)) continue;
      const double cx = g.centre(i), cy = g.centre(j);
      std::optional<double> z;
      if (g.valid(i, j))
        z = g.at(i, j).mean;
      else
        z = g.idw(cx, cy, s);  // empty cell: interpolated, dropped when no neighbour
      if (z) pts.emplace_back(cx, cy, *z);
    }
  return fitPlane(pts);
}

namespace {

/** Uniform bucket index of the RRT nodes (bucket = d_n): nearest node and
 *  nodes within a radius, both in insertion order on ties (deterministic). */
class NodeIndex {
 public:
  NodeIndex(double half_extent, double bucket) : h_(half_extent), b_(bucket) {
    n_ = std::max(1, static_cast<int>(std::ceil(2 * half_extent / bucket)));
    buckets_.resize(static_cast<size_t>(n_) * n_);
  }
  void add(int id, double x, double y) {
    buckets_[key(cell(x), cell(y))].push_back(id);
    xs_.push_back(x);
    ys_.push_back(y);
  }
  int nearest(double x, double y) const {
    const int bx = cell(x), by = cell(y);
    int best = -1;
    double bd = 1e300;
    for (int r = 0; r < n_; ++r) {
      // Every node in ring r is at least (r - 1) * b_ away.
      if (best >= 0 && (r - 1) * b_ > std::sqrt(bd)) break;
      // Only the ring's perimeter (ties go to the smaller id: order-free).
      auto visit = [&](int i, int j) {
        if (i < 0 || j < 0 || i >= n_ || j >= n_) return;
        for (int id : buckets_[key(i, j)]) {
          const double d = sq(xs_[id] - x) + sq(ys_[id] - y);
          if (d < bd || (d == bd && id < best)) {
            bd = d;
            best = id;
          }
        }
      };
      if (r == 0) {
        visit(bx, by);
        continue;
      }
      for (int k = -r; k <= r; ++k) {
        visit(bx - r, by + k);
        visit(bx + r, by + k);
      }
      for (int k = -r + 1; k <= r - 1; ++k) {
        visit(bx + k, by - r);
        visit(bx + k, by + r);
      }
    }
    return best;
  }
  std::vector<int> within(double x, double y, double radius) const {
    std::vector<int> out;
    const int r = static_cast<int>(std::ceil(radius / b_));
    const int bx = cell(x), by = cell(y);
    for (int i = std::max(0, bx - r); i <= std::min(n_ - 1, bx + r); ++i)
      for (int j = std::max(0, by - r); j <= std::min(n_ - 1, by + r); ++j)
        for (int id : buckets_[key(i, j)])
          if (sq(xs_[id] - x) + sq(ys_[id] - y) <= radius * radius) out.push_back(id);
    std::sort(out.begin(), out.end());
    return out;
  }

 private:
  static double sq(double v) { return v * v; }
  int cell(double v) const {
    return std::clamp(static_cast<int>(std::floor((v + h_) / b_)), 0, n_ - 1);
  }
  size_t key(int i, int j) const { return static_cast<size_t>(i) * n_ + j; }
  double h_, b_;
  int n_;
  std::vector<std::vector<int>> buckets_;
  std::vector<double> xs_, ys_;
};

bool similar(const Eigen::Vector3d& n1, const Eigen::Vector3d& n2, double n_th) {
  // carenav's normal test (docs/design.md, 'Ground plane'): "similar normals" is 1 - |n1 . n2| <=
  // N_th.
  return 1.0 - std::abs(n1.dot(n2)) <= n_th;
}

}  // namespace

namespace {
struct Seed {
  Eigen::Vector3d p;
  Plane plane;
};

/** One tree grown from `seed` for K iterations, then the RANSAC plane. */
GroundPlaneResult growTree(const ElevationGrid& g, const PerceptionParams& p, const Seed& seed,
                           uint32_t rng_seed) {
  GroundPlaneResult res;
  const int m = g.cells(), s = p.window;
  const double half = 0.5 * m * g.resolution();
  res.seed_found = true;
  const Eigen::Vector3d seed_p = seed.p;
  const std::optional<Plane> seed_plane = seed.plane;
  // 2. initializeTree.
  NodeIndex index(half, p.expansion_distance);
  res.nodes.push_back({seed_p, seed_plane->normal(), -1});
  index.add(0, seed_p.x(), seed_p.y());
  Eigen::Vector2d centroid(seed_p.x(), seed_p.y());

  std::mt19937 rng(rng_seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const double h0 = std::min(half, 2 * p.expansion_distance);
  const double lim = half - 1e-9;
  for (int k = 0; k < p.rrt_iterations; ++k) {
    ++res.iterations;
    // sampleRandomDirection: uniform in the search window. The window starts
    // centred on the seed with half-size 2 d_n, its centre is the geometric
    // centre of the nodes (updateSearchSpace) and it grows linearly with the
    // iterations to the whole local map at iteration K.
    const double hw = h0 + (half - h0) * k / std::max(1, p.rrt_iterations - 1);
    const double xr = std::clamp(centroid.x() + (2 * u01(rng) - 1) * hw, -lim, lim);
    const double yr = std::clamp(centroid.y() + (2 * u01(rng) - 1) * hw, -lim, lim);
    const int near = index.nearest(xr, yr);
    const RrtNode& xn = res.nodes[near];
    const double dx = xr - xn.p.x(), dy = yr - xn.p.y();
    if (dx * dx + dy * dy < 1e-18) continue;  // x_rand on x_near: no direction
    const double th = std::atan2(dy, dx);     // Eq. (1)
    const double xe = xn.p.x() + p.expansion_distance * std::cos(th);  // Eq. (2)
    const double ye = xn.p.y() + p.expansion_distance * std::sin(th);
    if (!g.inside(g.cellOf(xe), g.cellOf(ye))) continue;
    const auto ze = g.idw(xe, ye, s);  // elevation(): skip when no valid neighbour
    if (!ze) continue;
    const auto pl = localPlane(g, xe, ye, s);  // interpolation() + fitPlane()
    if (!pl) continue;
    const auto zp = pl->zAt(xe, ye);
    const double zl = zp ? *zp : *ze;
    const Eigen::Vector3d nl = pl->normal();
    auto accepts = [&](const RrtNode& q) {
      return similar(nl, q.n, p.normal_threshold) &&
             std::abs(zl - q.p.z()) <= p.elevation_threshold;
    };
    int parent = -1;
    if (accepts(xn)) {
      parent = near;
    } else {
      for (int id : index.within(xe, ye, p.expansion_distance + 1e-9))
        if (accepts(res.nodes[id])) {
          parent = id;
          break;
        }
    }
    if (parent < 0) {
      ++res.expansions_rejected;
      continue;
    }
    const int id = static_cast<int>(res.nodes.size());
    res.nodes.push_back({{xe, ye, zl}, nl, parent});
    index.add(id, xe, ye);
    centroid += (Eigen::Vector2d(xe, ye) - centroid) / static_cast<double>(res.nodes.size());
  }

  // 4. RANSAC over the node centres -> g_plane.
  if (res.nodes.size() >= 3) {
    std::vector<Eigen::Vector3d> pts;
    pts.reserve(res.nodes.size());
    for (const auto& n : res.nodes) pts.push_back(n.p);
    auto rr = ransacPlane(pts, p.ransac_iterations, p.ransac_threshold, rng);
    res.plane = rr.plane;
    res.ransac_inliers = rr.inliers;
  }
  if (!res.plane) res.plane = seed_plane;  // a tree that never grew: the seed's plane
  return res;
}

}  // namespace

GroundPlaneResult detectGroundRrt(const ElevationGrid& g, const PerceptionParams& p) {
  const int m = g.cells(), s = p.window;
  const Eigen::Vector3d up(0, 0, 1);
  // 1. nearestValidSeed: square rings around the robot cell (robot at the grid
  // centre); a valid seed is a cell with at least d_min samples near the floor
  // the robot stands on (|z| <= seed_max_elevation: the robot pose is the
  // initial guess) whose s x s neighbourhood gives a valid, upright plane.
  // When a seed's tree stays smaller than min_tree_nodes (a seed on a small
  // flat object cannot expand, [Garrote17, Sec. III-B]), the next valid seed at least
  // d_n away is tried, up to seed_attempts; the largest tree wins.
  std::vector<Seed> seeds;
  const int c0 = m / 2;
  for (int r = 0; r <= m / 2 && static_cast<int>(seeds.size()) < p.seed_attempts; ++r)
    for (int i = c0 - r; i <= c0 + r; ++i)
      for (int j = c0 - r; j <= c0 + r; ++j) {
        if (static_cast<int>(seeds.size()) >= p.seed_attempts) break;
        if (std::max(std::abs(i - c0), std::abs(j - c0)) != r || !g.valid(i, j)) continue;
        if (g.at(i, j).n < static_cast<uint32_t>(std::max(1.0, p.d_min))) continue;  // sparse
        if (std::abs(g.at(i, j).mean) > p.seed_max_elevation) continue;  // not the robot's floor
        const double x = g.centre(i), y = g.centre(j);
        bool far = true;
        for (const auto& sd : seeds)
          if (std::hypot(sd.p.x() - x, sd.p.y() - y) < p.expansion_distance) far = false;
        if (!far) continue;
        auto pl = localPlane(g, x, y, s);
        if (!pl || (p.seed_upright && !similar(pl->normal(), up, p.normal_threshold))) continue;
        const auto z = pl->zAt(x, y);
        seeds.push_back({{x, y, z ? *z : g.at(i, j).mean}, *pl});
      }
  GroundPlaneResult best;
  for (size_t k = 0; k < seeds.size(); ++k) {
    GroundPlaneResult r = growTree(g, p, seeds[k], static_cast<uint32_t>(p.seed) + 7919u * k);
    if (r.nodes.size() > best.nodes.size()) best = std::move(r);
    if (static_cast<int>(best.nodes.size()) >= p.min_tree_nodes) break;
  }
  return best;
}

GroundPlaneResult detectGroundRansac(const Cloud& c, const PerceptionParams& p, size_t max_points) {
  GroundPlaneResult res;
  std::vector<Eigen::Vector3d> pts;
  const size_t valid = c.validCount();
  const size_t stride =
      std::max<size_t>(1, (valid + max_points - 1) / std::max<size_t>(1, max_points));
  size_t k = 0;
  for (const auto& q : c.points) {
    if (!validPoint(q) || q.z < p.z_min || q.z > p.z_max) continue;
    if (k++ % stride == 0) pts.emplace_back(q.x, q.y, q.z);
  }
  std::mt19937 rng(static_cast<uint32_t>(p.seed));
  auto rr = ransacPlane(pts, p.ransac_iterations, p.ransac_threshold, rng);
  res.plane = rr.plane;
  res.ransac_inliers = rr.inliers;
  res.seed_found = rr.plane.has_value();
  return res;
}

}  // namespace carenav::perception
