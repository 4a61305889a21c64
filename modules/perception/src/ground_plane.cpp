#include <carenav/perception/ground_plane.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

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

  // 4. (RANSAC over the node centres) is done by the caller, which also
  // refuses trees smaller than min_tree_nodes: no seed plane is ever taken
  // as the ground on its own.
  return res;
}

}  // namespace

namespace {

struct Candidate {
  Plane plane;
  size_t support = 0;  ///< tree nodes within ransac_threshold of the plane
};

/** Planes of a tree's node centres, each supported by at least min_tree_nodes
 *  nodes: RANSAC over the nodes, then again over the nodes the earlier planes
 *  left, up to `max_planes` (a tree that crept from the floor onto a plateau
 *  holds both). `enough` ends the search early (the first plane is the floor
 *  under the robot in the common case). */
template <class Enough>
std::vector<Candidate> nodePlanes(const std::vector<RrtNode>& nodes, const PerceptionParams& p,
                                  std::mt19937& rng, int max_planes, Enough&& enough) {
  std::vector<Candidate> out;
  std::vector<Eigen::Vector3d> pts;
  pts.reserve(nodes.size());
  for (const auto& n : nodes) pts.push_back(n.p);
  const size_t min_support = static_cast<size_t>(std::max(3, p.min_tree_nodes));
  for (int k = 0; k < max_planes && pts.size() >= min_support; ++k) {
    const auto rr = ransacPlane(pts, p.ransac_iterations, p.ransac_threshold, rng);
    if (!rr.plane || rr.inliers < min_support) break;
    out.push_back({*rr.plane, rr.inliers});
    if (enough(out.back())) break;
    std::vector<Eigen::Vector3d> rest;
    for (const auto& q : pts)
      if (rr.plane->distance(q.x(), q.y(), q.z()) > p.ransac_threshold) rest.push_back(q);
    pts.swap(rest);
  }
  return out;
}

}  // namespace

GroundPlaneResult detectGroundRrt(const ElevationGrid& g, const PerceptionParams& p) {
  const int m = g.cells(), s = p.window;
  const Eigen::Vector3d up(0, 0, 1);
  // 1. nearestValidSeed: square rings around the robot cell (robot at the grid
  // centre); a valid seed is a cell with at least d_min samples whose s x s
  // neighbourhood gives a valid, upright plane. First pass: seeds near the
  // floor the robot stands on (|z| <= seed_max_elevation: the robot pose and
  // the sensor mounting are the prior, [Garrote17, Alg. 1]'s initial guess).
  // Second pass, only when the first gave no plane: seeds on the largest level
  // surface at another height (a sensor pose that is off, the robot's own
  // floor out of view); the plane found is reported as far from the prior
  // (prior_offset).
  // Second pass: the largest level surface outside the prior's band, i.e. the
  // 10 cm height bin holding the most dense cells (a horizontal surface fills
  // many cells, a wall few); seeds within one bin of its centre.
  double level = 0;
  auto modalLevel = [&]() {
    constexpr double kBin = 0.1;
    std::vector<int> hist(2048, 0);
    int best_n = 0;
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < m; ++j) {
        if (!g.valid(i, j) || g.at(i, j).n < static_cast<uint32_t>(std::max(1.0, p.d_min)))
          continue;
        const double z = g.at(i, j).mean;
        if (std::abs(z) <= p.seed_max_elevation) continue;
        const int b = std::clamp(static_cast<int>(std::floor(z / kBin)) + 1024, 0, 2047);
        if (++hist[b] > best_n) {
          best_n = hist[b];
          level = (b - 1024 + 0.5) * kBin;
        }
      }
    return best_n > 0;
  };
  auto collect = [&](bool near_prior) {
    std::vector<Seed> seeds;
    const int c0 = m / 2;
    for (int r = 0; r <= m / 2 && static_cast<int>(seeds.size()) < p.seed_attempts; ++r)
      for (int i = c0 - r; i <= c0 + r; ++i)
        for (int j = c0 - r; j <= c0 + r; ++j) {
          if (static_cast<int>(seeds.size()) >= p.seed_attempts) break;
          if (std::max(std::abs(i - c0), std::abs(j - c0)) != r || !g.valid(i, j)) continue;
          if (g.at(i, j).n < static_cast<uint32_t>(std::max(1.0, p.d_min))) continue;  // sparse
          const double zc = g.at(i, j).mean;
          if (near_prior ? std::abs(zc) > p.seed_max_elevation
                         : (std::abs(zc) <= p.seed_max_elevation || std::abs(zc - level) > 0.1))
            continue;
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
    return seeds;
  };
  // 2-4. A tree per seed (the RRT, then RANSAC over its node centres). A tree
  // smaller than min_tree_nodes is refused: a seed on a small flat object
  // cannot expand ([Garrote17, Sec. III-B]) and its plane says nothing about
  // the floor (a 2-node tree gave a 27.9 deg "floor"). Among the planes of the
  // accepted trees (each from >= min_tree_nodes nodes, upright), the one
  // closest to the floor under the robot (|z| at the robot, x = y = 0) wins:
  // a tree that crept from the robot's floor onto a 5 cm plateau holds both
  // planes, and the plateau must not become the ground because it is larger.
  // Seeds are tried until a plane within prior_height_tolerance of the
  // robot's floor is found, up to seed_attempts per pass.
  GroundPlaneResult best, largest;
  double best_off = std::numeric_limits<double>::infinity();
  size_t best_support = 0;
  int grown = 0, refused = 0;
  bool seed_found = false;
  auto consistent = [&](const Candidate& c) {
    const auto z0 = c.plane.zAt(0, 0);
    return z0 && std::abs(*z0) <= p.prior_height_tolerance &&
           (!p.seed_upright || similar(c.plane.normal(), up, p.normal_threshold));
  };
  for (int pass = 0; pass < 2 && !best.plane; ++pass) {
    if (pass == 1 && !modalLevel()) break;
    const auto seeds = collect(pass == 0);
    seed_found = seed_found || !seeds.empty();
    for (const auto& sd : seeds) {
      const uint32_t rs = static_cast<uint32_t>(p.seed) + 7919u * static_cast<uint32_t>(grown++);
      GroundPlaneResult r = growTree(g, p, sd, rs);
      if (static_cast<int>(r.nodes.size()) < p.min_tree_nodes) {
        ++refused;
        if (r.nodes.size() > largest.nodes.size()) largest = std::move(r);
        continue;
      }
      std::mt19937 rng(rs + 1u);
      for (const auto& c : nodePlanes(r.nodes, p, rng, 3, consistent)) {
        if (p.seed_upright && !similar(c.plane.normal(), up, p.normal_threshold)) continue;
        const auto z0 = c.plane.zAt(0, 0);
        if (!z0) continue;
        const double off = std::abs(*z0);
        if (off < best_off - 1e-3 || (off <= best_off + 1e-3 && c.support > best_support)) {
          best_off = off;
          best_support = c.support;
          best = r;  // the tree is kept for the picture
          best.plane = c.plane;
          best.ransac_inliers = c.support;
          best.prior_offset = *z0;
          best.wide_search = pass == 1;
        }
      }
      if (best.plane && best_off <= p.prior_height_tolerance) break;
    }
  }
  GroundPlaneResult& out = best.plane ? best : largest;
  out.seed_found = seed_found;
  out.trees_grown = grown;
  out.trees_refused = refused;
  return out;
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
