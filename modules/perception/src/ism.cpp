#include <carenav/perception/ism.h>

#include "slope_reference.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace carenav::perception {

double voxelDensity(const ElevationCell& c, double cell_area, const PerceptionParams& p) {
  const double h = std::max(
      1e-3, static_cast<double>(c.z_hi - c.z_lo));  // h >= 1 mm (docs/design.md, 'Floored height')
  const double V = h * cell_area;
  // [Garrote17, Eq. 4]: rho = K_m / (1 + exp(-K_n (N_z - d_min) / V)).
  const double e = -p.k_n * (static_cast<double>(c.n) - p.d_min) / V;
  if (e > 700) return 0.0;
  return p.k_m / (1.0 + std::exp(e));
}

double voxelPlaneDistance(const ElevationCell& c, double x, double y, const Plane& pl) {
  return std::max(pl.distance(x, y, c.z_hi), pl.distance(x, y, c.z_lo));
}

double verticalNoise(const PerceptionParams& p, const Point3f* o, double x, double y, double z) {
  if (!o || p.depth_noise_std <= 0) return 0.0;
  const double dx = x - o->x, dy = y - o->y, dz = z - o->z;
  const double r = std::sqrt(dx * dx + dy * dy + dz * dz);
  // sigma(r) = depth_noise_std r^2 along the ray (quadratic depth noise, the
  // simulator's model and Khoshelham & Elberink's for structured light); its
  // vertical share is |dz| / r: sigma_v = depth_noise_std r |dz|.
  return p.depth_noise_std * r * std::abs(dz);
}

double measuredNoiseRatio(const ElevationGrid& g, const PerceptionParams& p, const Point3f* o) {
  constexpr uint32_t kMinSamples = 8;
  constexpr size_t kMinVoxels = 20;
  if (!o || p.depth_noise_std <= 0) return 0.0;
  thread_local std::vector<float> ratio;
  ratio.clear();
  const int m = g.cells();
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      const ElevationCell& c = g.at(i, j);
      if (c.n < kMinSamples) continue;
      const double sv = verticalNoise(p, o, g.centre(i), g.centre(j), c.mean);
      if (sv > 1e-6) ratio.push_back(static_cast<float>(std::sqrt(c.variance()) / sv));
    }
  if (ratio.size() < kMinVoxels) return 0.0;
  auto mid = ratio.begin() + ratio.size() / 2;
  std::nth_element(ratio.begin(), mid, ratio.end());
  return *mid;
}

namespace {

// ------------------------------------------------------------ classification

/** Scratch of one classification: per voxel the rule-1 threshold and the
 *  standard error of the mean (kept for rule 3); the ground voxels found. */
struct VoxelNoise {
  std::vector<float>& thr;
  std::vector<float>& se;
};

/** Rules 1 and 2; returns the ground voxels (cell indices). */
std::vector<int32_t> applyPlaneRules(const ElevationGrid& g, const Plane& plane,
                                     const PerceptionParams& p, const Point3f* o,
                                     std::vector<VoxelClass>& classes, VoxelNoise& noise) {
  const int m = g.cells();
  std::vector<int32_t> queue;
  queue.reserve(static_cast<size_t>(m) * m / 4);
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      const ElevationCell& c = g.at(i, j);
      if (c.n == 0) continue;
      const size_t k = static_cast<size_t>(i) * m + j;
      const double x = g.centre(i), y = g.centre(j);
      const double sv = verticalNoise(p, o, x, y, c.mean);
      const double t = std::max(p.d_pth, p.noise_k * sv);
      const double e = sv / std::sqrt(static_cast<double>(c.n));
      noise.thr[k] = static_cast<float>(t);
      noise.se[k] = static_cast<float>(e);
      // Rule 1 ([Garrote17]): max distance of z+ and z- to the plane.
      bool obstacle = voxelPlaneDistance(c, x, y, plane) > t;
      // Rule 2: the mean of a voxel with enough samples (d_min, [Garrote17, Eq. 4]).
      if (!obstacle && p.mean_step > 0 && c.n >= std::max(1.0, p.d_min))
        obstacle = plane.distance(x, y, c.mean) > p.mean_step + p.noise_k * e;
      classes[k] = obstacle ? VoxelClass::Obstacle : VoxelClass::Ground;
      if (!obstacle) queue.push_back(static_cast<int32_t>(k));
    }
  return queue;
}

/** The ground voxels of `queue` in connected patches (4-neighbours) of at
 *  least kMinSource cells: a lone noisy voxel that happens to lie near the
 *  plane (far on a lower floor) must not seed a "surface" there. */
void keepLargePatches(const ElevationGrid& g, const std::vector<VoxelClass>& classes,
                      std::vector<int32_t>& queue) {
  constexpr size_t kMinSource = 16;  // cells (0.04 m^2 at d_r = 5 cm)
  const int m = g.cells();
  thread_local std::vector<uint8_t> seen;
  seen.assign(static_cast<size_t>(m) * m, 0);
  std::vector<int32_t> sources, comp;
  sources.reserve(queue.size());
  for (const int32_t s0 : queue) {
    if (seen[s0]) continue;
    comp.clear();
    comp.push_back(s0);
    seen[s0] = 1;
    for (size_t h = 0; h < comp.size(); ++h)
      forEachNeighbour4(g, comp[h], [&](int, int, int32_t b) {
        if (seen[b] || classes[b] != VoxelClass::Ground) return;
        seen[b] = 1;
        comp.push_back(b);
      });
    if (comp.size() >= kMinSource) sources.insert(sources.end(), comp.begin(), comp.end());
  }
  queue.swap(sources);
}

/** Chamfer (3-4) distance of every cell of an m x m grid to the nearest
 *  source, in thirds of a cell, and that source. */
void chamferToSources(int m, const std::vector<int32_t>& sources, std::vector<int32_t>& dist,
                      std::vector<int32_t>& near) {
  const size_t mm = static_cast<size_t>(m) * m;
  dist.assign(mm, 1 << 29);
  near.assign(mm, -1);
  for (int32_t k : sources) {
    dist[k] = 0;
    near[k] = k;
  }
  auto relax = [&](size_t k, size_t from, int w) {
    if (dist[from] + w < dist[k]) {
      dist[k] = dist[from] + w;
      near[k] = near[from];
    }
  };
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      const size_t k = static_cast<size_t>(i) * m + j;
      if (i > 0) {
        relax(k, k - m, 3);
        if (j > 0) relax(k, k - m - 1, 4);
        if (j + 1 < m) relax(k, k - m + 1, 4);
      }
      if (j > 0) relax(k, k - 1, 3);
    }
  for (int i = m - 1; i >= 0; --i)
    for (int j = m - 1; j >= 0; --j) {
      const size_t k = static_cast<size_t>(i) * m + j;
      if (i + 1 < m) {
        relax(k, k + m, 3);
        if (j > 0) relax(k, k + m - 1, 4);
        if (j + 1 < m) relax(k, k + m + 1, 4);
      }
      if (j + 1 < m) relax(k, k + 1, 3);
    }
}

/** The constants of rule 3. */
struct SlopeRule {
  explicit SlopeRule(const ElevationGrid& g, const PerceptionParams& p)
      : rise(std::tan(p.max_slope_deg * M_PI / 180.0) * g.resolution()),
        min_n(static_cast<uint32_t>(std::max(1.0, p.d_min))),
        mk(p.mean_k) {}
  double rise;     ///< m, largest rise over one cell
  uint32_t min_n;  ///< samples a voxel needs to be judged
  // Differences of means are Gaussian (many samples): mean_k standard errors.
  double mk;
};

/** Rule 3 for the obstacle voxel b = (bi, bj), reached from a ground voxel
 *  in direction dv: whether it is a traversable surface. */
bool slopeRescues(const ElevationGrid& g, const SlopeRule& rule, const VoxelNoise& noise,
                  const std::vector<VoxelClass>& classes, const std::vector<int32_t>& dist,
                  const std::vector<int32_t>& near, int bi, int bj, const int dv[2]) {
  constexpr int kBaseline = 4;  // cells (20 cm at d_r = 5 cm)
  const int m = g.cells();
  const size_t b = static_cast<size_t>(bi) * m + bj;
  const auto& thr = noise.thr;
  const auto& se = noise.se;
  const double rise = rule.rise, mk = rule.mk;
  const uint32_t min_n = rule.min_n;
  const ElevationCell& c = g.at(bi, bj);
  // Too few samples to judge a slope ([Garrote17, Eq. 4]'s d_min): the sparse
  // cells of the noise streak behind a depth edge must not bridge it.
  if (c.n <= min_n) return false;
  // No step inside: z+ and z- within the rule-1 band around the cell's
  // own mean, widened by one sigma_v (a ramp voxel of ~30 samples has a
  // 4-sigma sample now and then; a step inside is larger).
  const double flat = thr[b] + se[b] * std::sqrt(static_cast<double>(c.n));
  if (c.z_hi - c.mean > flat || c.mean - c.z_lo > flat) return false;
  // Height over the nearest on-plane voxel (not the plane: when a ramp
  // and its landing fill the view the plane itself is tilted).
  const int32_t nb = near[b];
  if (nb < 0) return false;
  const double off = std::abs(c.mean - g.at(nb / m, nb % m).mean);
  const double se2 = static_cast<double>(se[nb]) * se[nb] + se[b] * se[b];
  if (off > rise * dist[b] / 3.0 + mk * std::sqrt(se2)) return false;  // too high too soon
  // The slope from b back to the ground cells 1..kBaseline cells behind
  // it (this direction) stays within max_slope: a step blurred over
  // two or three cells by the noise (a 2 cm box edge) is no ramp.
  bool ok = true;
  for (int k = 1; k <= kBaseline && ok; ++k) {
    const int ci = bi - k * dv[0], cj = bj - k * dv[1];
    if (!g.inside(ci, cj)) break;
    const size_t q = static_cast<size_t>(ci) * m + cj;
    if (classes[q] != VoxelClass::Ground) break;
    const double tol =
        k * rise + mk * std::sqrt(static_cast<double>(se[q]) * se[q] + se[b] * se[b]);
    ok = std::abs(c.mean - g.at(ci, cj).mean) <= tol;
  }
  return ok;
}

/** Rule 3: breadth first from the ground voxels over off-plane voxels that
 *  are flat within the noise and reached through slopes the robot climbs. */
size_t rescueSlopes(const ElevationGrid& g, const PerceptionParams& p, const VoxelNoise& noise,
                    std::vector<VoxelClass>& classes, std::vector<int32_t>& queue) {
  const int m = g.cells();
  const SlopeRule rule(g, p);
  // Chamfer (3-4) distance of every cell to the nearest voxel on the plane
  // (rules 1-2 ground), in cells: a surface that left the plane `dist`
  // away rose at most tan(max_slope) dist above it. This bounds the creep
  // of the breadth-first search over a small step blurred by the noise.
  // Sources: on-plane voxels in connected patches of at least kMinSource
  // cells.
  keepLargePatches(g, classes, queue);
  thread_local std::vector<int32_t> dist, near;
  chamferToSources(m, queue, dist, near);
  size_t rescued = 0;
  for (size_t h = 0; h < queue.size(); ++h) {
    const int32_t a = queue[h];
    const int ai = a / m, aj = a % m;
    const int dirs[4][2] = {{-1, 0}, {1, 0}, {0, -1}, {0, 1}};
    for (const auto& dv : dirs) {
      const int bi = ai + dv[0], bj = aj + dv[1];
      if (!g.inside(bi, bj)) continue;
      const size_t b = static_cast<size_t>(bi) * m + bj;
      if (classes[b] != VoxelClass::Obstacle) continue;
      if (!slopeRescues(g, rule, noise, classes, dist, near, bi, bj, dv)) continue;
      classes[b] = VoxelClass::Ground;
      ++rescued;
      queue.push_back(static_cast<int32_t>(b));
    }
  }
  return rescued;
}

}  // namespace

IsmStats classifyVoxels(const ElevationGrid& g, const Plane& plane, const PerceptionParams& p,
                        const Point3f* o, std::vector<VoxelClass>& classes,
                        std::vector<SlopeVerdict>* verdicts) {
  IsmStats st;
  const int m = g.cells();
  const size_t mm = static_cast<size_t>(m) * m;
  classes.assign(mm, VoxelClass::None);
  thread_local std::vector<float> thr, se;
  thr.resize(mm);
  se.resize(mm);
  VoxelNoise noise{thr, se};
  std::vector<int32_t> queue = applyPlaneRules(g, plane, p, o, classes, noise);
  if (p.max_slope_deg > 0) st.rescued_voxels = rescueSlopes(g, p, noise, classes, queue);
  if (p.max_slope_deg > 0) st.rescued_voxels += rescueGentleGround(g, plane, p, o, classes);
  // Rule 6: smooth regions judged by their own plane; rule 4's window on the rest.
  thread_local std::vector<uint8_t> decided;
  decided.assign(mm, 0);
  RegionCounts rc;
  if (o && p.depth_noise_std > 0 && p.max_slope_deg > 0 && std::abs(plane.c) >= 1e-6) {
    const uint32_t min_n = static_cast<uint32_t>(std::max(1.0, p.d_min));
    const SlopeReference ref = slopeReference(g, plane, p, classes, min_n);
    rc = judgeSlopeRegions(g, p, *o, ref, thr, se, classes, decided);
    st.rescued_voxels += rc.rescued;
    st.steep_voxels += rc.steep;
    st.step_voxels = rc.steps;
    if (rc.floor) {
      st.floor_slope_x_deg = std::atan(rc.floor_ref.gi / g.resolution()) * 180 / M_PI;
      st.floor_slope_y_deg = std::atan(rc.floor_ref.gj / g.resolution()) * 180 / M_PI;
    }
  }
  // Rule 4 measures slopes against the floor's plane rule 6 found (else its own reference).
  thread_local std::vector<VoxelClass> before_rule4;
  before_rule4 = classes;
  thread_local std::vector<uint8_t> gentle;
  gentle.assign(mm, 0);
  st.steep_voxels += markSteepWindows(g, plane, p, o, classes, &decided, &gentle,
                                      rc.floor ? &rc.floor_ref : nullptr);
  if (verdicts) verdicts->assign(mm, SlopeVerdict::None);
  for (size_t k = 0; k < mm; ++k) {
    if (verdicts && classes[k] == VoxelClass::Obstacle && before_rule4[k] == VoxelClass::Ground)
      (*verdicts)[k] = SlopeVerdict::SteepWindow;
    else if (verdicts && classes[k] == VoxelClass::Ground && gentle[k])
      (*verdicts)[k] = SlopeVerdict::Gentle;
    if (classes[k] == VoxelClass::None) continue;
    ++st.voxels;
    classes[k] == VoxelClass::Obstacle ? ++st.obstacle_voxels : ++st.ground_voxels;
  }
  return st;
}

namespace {

// ------------------------------------------------------------ integration

/** Look-up tables over |D| (1 mm steps) for the Gaussian exp(-D^2 / 2 sigma^2)
 *  and the ground sigmoid 1 / (1 + exp(-D)) of [Garrote17, Eqs. 5-6]. */
struct IsmTables {
  static constexpr double kStep = 1e-3;
  std::vector<float> gauss, sigm;
  double two_s2 = -1;
  void prepare(size_t n_lut, double two_sigma2) {
    if (gauss.size() == n_lut && two_s2 == two_sigma2) return;
    gauss.resize(n_lut);
    sigm.resize(n_lut);
    for (size_t k = 0; k < n_lut; ++k) {
      const double D = -static_cast<double>(k) * kStep;
      gauss[k] = static_cast<float>(std::exp(-D * D / two_sigma2));
      sigm[k] = static_cast<float>(1.0 / (1.0 + std::exp(-D)));
    }
    two_s2 = two_sigma2;
  }
  static float at(const std::vector<float>& t, double D) {
    const size_t k = static_cast<size_t>(std::abs(D) / kStep + 0.5);
    return t[std::min(k, t.size() - 1)];
  }
};

/** The voxels of an m x m elevation grid from the farthest to the nearest
 *  (the grid is robot-centred: the order is fixed), kept per thread. */
const std::vector<int32_t>& farthestFirst(const ElevationGrid& g) {
  const int m = g.cells();
  thread_local std::vector<int32_t> order;
  thread_local int order_m = -1;
  thread_local double order_r = -1;
  if (order_m != m || order_r != g.resolution()) {
    order.resize(static_cast<size_t>(m) * m);
    for (int32_t k = 0; k < m * m; ++k) order[k] = k;
    std::vector<double> d2(order.size());
    for (int32_t k = 0; k < m * m; ++k) d2[k] = std::hypot(g.centre(k / m), g.centre(k % m));
    std::stable_sort(order.begin(), order.end(),
                     [&](int32_t a, int32_t b) { return d2[a] > d2[b]; });
    order_m = m;
    order_r = g.resolution();
  }
  return order;
}

constexpr int kEdgeBins = 360;  // bearing bins of the near edge of the view

int bearingBin(double x, double y) {
  const int b = static_cast<int>(std::floor((std::atan2(y, x) + M_PI) * kEdgeBins / (2 * M_PI)));
  return std::clamp(b, 0, kEdgeBins - 1);
}

/** Per voxel of the robot-centred grid (fixed for its size and resolution, kept per thread):
 *  its bearing bin and its centre's distance to the robot, std::hypot. */
struct VoxelPolar {
  std::vector<int16_t> bin;
  std::vector<double> dist;
};
const VoxelPolar& voxelPolar(const ElevationGrid& g) {
  const int m = g.cells();
  thread_local VoxelPolar vp;
  thread_local int vp_m = -1;
  thread_local double vp_r = -1;
  if (vp_m != m || vp_r != g.resolution()) {
    vp.bin.resize(static_cast<size_t>(m) * m);
    vp.dist.resize(vp.bin.size());
    for (int32_t k = 0; k < m * m; ++k) {
      const double x = g.centre(k / m), y = g.centre(k % m);
      vp.bin[k] = static_cast<int16_t>(bearingBin(x, y));
      vp.dist[k] = std::hypot(x, y);
    }
    vp_m = m;
    vp_r = g.resolution();
  }
  return vp;
}

/** Occlusion is not free space: per 1 deg bearing bin, the distance of the
 *  nearest voxel holding points in this frame (the near edge of the view),
 *  the least over the bin and its two neighbours. A cell without points
 *  farther than that along a ray lies in a shadow (behind a drop-off, a
 *  hole, a box): the ray passed above it, it never saw its floor, so it gets
 *  no free evidence (it stays unknown, or keeps what earlier frames said).
 *  Cells nearer than the edge (the camera's blind zone close to the robot)
 *  keep the rays' free evidence. */
const std::vector<float>& viewEdge(const ElevationGrid& g, const std::vector<VoxelClass>& classes) {
  const int m = g.cells();
  thread_local std::vector<float> edge, edge_raw;
  edge_raw.assign(kEdgeBins, std::numeric_limits<float>::infinity());
  const VoxelPolar& vp = voxelPolar(g);
  for (int32_t k = 0; k < m * m; ++k) {
    if (classes[k] == VoxelClass::None) continue;
    float& e = edge_raw[vp.bin[k]];
    e = std::min(e, static_cast<float>(vp.dist[k]));
  }
  edge.resize(kEdgeBins);
  for (int b = 0; b < kEdgeBins; ++b)
    edge[b] = std::min(
        {edge_raw[(b + kEdgeBins - 1) % kEdgeBins], edge_raw[b], edge_raw[(b + 1) % kEdgeBins]});
  return edge;
}

/** What one frame's integration needs for every voxel. */
struct IsmFrame {
  const ElevationGrid& g;
  const std::vector<VoxelClass>& classes;
  const PerceptionParams& p;
  LocalOccupancy& grid;
  const IsmTables& lut;
  const std::vector<float>& edge;
  const VoxelPolar& polar;
  double area, two_s2;
  double ca, sa, rx, ry;  // robot pose in the odometry frame
  float kg;
  const std::vector<SlopeVerdict>& verdict;  // per voxel, from classifyVoxels()
  const std::vector<uint8_t>& below;         // per voxel, lowerSurface()
};

/** Per voxel, whether it is an obstacle lying below the plane by more than
 *  d_pth: a lower surface (the treads beyond a stair edge, the bottom of a
 *  hole). A ray to a farther return passes above it, not through it. */
const std::vector<uint8_t>& lowerSurface(const ElevationGrid& g, const Plane& plane,
                                         const PerceptionParams& p,
                                         const std::vector<VoxelClass>& classes) {
  const int m = g.cells();
  thread_local std::vector<uint8_t> below;
  below.assign(classes.size(), 0);
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      const size_t k = static_cast<size_t>(i) * m + j;
      if (classes[k] != VoxelClass::Obstacle) continue;
      const auto z = plane.zAt(g.centre(i), g.centre(j));
      below[k] = z && *z - g.at(i, j).mean > p.d_pth;
    }
  return below;
}

/** Whether the voxel at (x, y) (robot frame) is ground whose own slope was
 *  judged traversable (rule 4's window or a gentle region of rule 6). A
 *  voxel that rule 4 made an obstacle was measured as a surface, not as a
 *  return at an uncertain range: the Gaussian of [Garrote17, Eqs. 5-6]
 *  that spreads an obstacle along its ray does not carry its slope verdict
 *  over such a neighbour, which the same test found gentle. */
bool gentleVerdict(const IsmFrame& f, double x, double y) {
  const int ei = f.g.cellOf(x), ej = f.g.cellOf(y);
  return f.g.inside(ei, ej) &&
         f.verdict[static_cast<size_t>(ei) * f.g.cells() + ej] == SlopeVerdict::Gentle;
}

/** Whether a ray passing over grid cell (ci, cj), at (x, y) in the robot
 *  frame, gives it no free evidence (nor does a ray to a lower surface: it
 *  passed above whatever lies before it): a lower surface seen there (a drop
 *  is no floor: the ray passed above it); a cell without points in this frame
 *  beyond the near edge of the view (a shadow); or, nearer than that edge
 *  (the blind zone under the camera), a cell that holds a drop remembered
 *  from earlier frames (the blind zone's free evidence would erase the
 *  stair edge the robot stopped for as it enters the blind zone). */
bool noFreeEvidence(const IsmFrame& f, int ci, int cj, double x, double y, bool beyond_edge) {
  const int ei = f.g.cellOf(x), ej = f.g.cellOf(y);
  if (!f.g.inside(ei, ej)) return false;
  const size_t q = static_cast<size_t>(ei) * f.g.cells() + ej;
  if (f.below[q]) return true;
  if (f.classes[q] != VoxelClass::None) return false;
  return beyond_edge || f.grid.drop(ci, cj);
}

/** The rays of voxel k into the grid: [Garrote17, Eq. 5] from the voxel back
 *  to the robot, then Eq. 6 beyond an obstacle. Each ray stops once
 *  kSaturated cells in a row already hold free evidence at least as strong
 *  as this ray's (a farther voxel's ray through them, processed earlier,
 *  said more): same grid, a fraction of the cells visited. */
void integrateVoxel(const IsmFrame& f, int32_t k) {
  constexpr int kSaturated = 3;
  const auto& g = f.g;
  auto& grid = f.grid;
  const int m = g.cells();
  const VoxelClass vc = f.classes[k];
  const int i = k / m, j = k % m;
  const ElevationCell& c = g.at(i, j);
  const bool obstacle = vc == VoxelClass::Obstacle;
  const bool steep_window = obstacle && f.verdict[k] == SlopeVerdict::SteepWindow;
  const double x = g.centre(i), y = g.centre(j);
  const double rho = obstacle ? voxelDensity(c, f.area, f.p) : 0.0;
  const float amp = static_cast<float>(std::max(rho, 0.5));
  const float kg = f.kg;
  const auto& gauss = f.lut.gauss;
  const auto& sigm = f.lut.sigm;
  // Voxel in the odometry frame; |c_v| its distance to the robot.
  const double wx = f.rx + f.ca * x - f.sa * y, wy = f.ry + f.sa * x + f.ca * y;
  const double cv = f.polar.dist[k];
  const int vi = grid.cellX(wx), vj = grid.cellY(wy);
  // |c| in [0, |c_v|], [Garrote17, Eq. 5], from the voxel back to the robot.
  int sat = 0;
  const double near_edge = f.edge[f.polar.bin[k]] + g.resolution();
  if (f.below[k]) grid.setDrop(vi, vj, true);
  if (vc == VoxelClass::Ground) grid.setDrop(vi, vj, false);  // the floor seen in the cell
  grid.walkSegment(wx, wy, cv, 0.0, [&](int ci, int cj, double dc) {
    const bool at_voxel = ci == vi && cj == vj;
    const double D = at_voxel ? 0.0 : std::min(0.0, dc - cv);
    // (The thesis, [Rosa17, Ch. 3], writes the ground branch with the Gaussian
    // exp(-D^2 / 2 sigma^2) inside the sigmoid; carenav uses the paper's form: docs/design.md,
    // 'Inverse sensor model'.)
    const float pr =
        obstacle ? amp * IsmTables::at(gauss, D) : kg + (0.5f - kg) * IsmTables::at(sigm, D);
    // A lower surface's ray passed above the cells before it: no free
    // evidence from it, the walk ends where its obstacle's spread does.
    if (f.below[k] && !at_voxel && pr <= 0.5f) return false;
    if (!at_voxel && pr < 0.5f && cv > 1e-9 &&
        noFreeEvidence(f, ci, cj, x * dc / cv, y * dc / cv, dc > near_edge))
      return true;
    if (pr > 0.5f && steep_window && !at_voxel && gentleVerdict(f, x * dc / cv, y * dc / cv))
      return true;
    if (pr < 0.5f && grid.frameFree(ci, cj) <= pr) {
      if (++sat >= kSaturated) return false;
    } else {
      sat = 0;
    }
    grid.addEvidence(ci, cj, pr);
    return true;
  });
  // |c| in ]|c_v|, max], [Garrote17, Eq. 6]: ground voxels say nothing beyond;
  // obstacles keep p > 0.5 while rho exp(-D^2/2s^2) > 0.5.
  if (!obstacle || 2 * rho <= 1) return;
  const double beyond = std::sqrt(f.two_s2 * std::log(2 * rho));
  grid.walkSegment(
      wx, wy, cv, cv + 0.75 * grid.resolution() + beyond, [&](int ci, int cj, double dc) {
        if (ci == vi && cj == vj) return true;
        if (steep_window && gentleVerdict(f, x * dc / cv, y * dc / cv)) return true;
        const double D = std::max(0.0, dc - cv);
        grid.addEvidence(ci, cj, std::max(static_cast<float>(rho) * IsmTables::at(gauss, D), 0.5f));
        return true;
      });
}

}  // namespace

IsmStats integrateIsm(const ElevationGrid& g, const Plane& plane, const PerceptionParams& p,
                      LocalOccupancy& grid, std::vector<VoxelClass>* classes_out,
                      const Point3f* sensor_origin) {
  thread_local std::vector<VoxelClass> local;
  std::vector<VoxelClass>& classes = classes_out ? *classes_out : local;
  thread_local std::vector<SlopeVerdict> verdicts;
  const IsmStats st = classifyVoxels(g, plane, p, sensor_origin, classes, &verdicts);
  const double two_s2 = 2.0 * p.sigma2;
  thread_local IsmTables lut;
  lut.prepare(static_cast<size_t>(grid.cells() * grid.resolution() * 1.5 / IsmTables::kStep) + 2,
              two_s2);
  const IsmFrame frame{g,
                       classes,
                       p,
                       grid,
                       lut,
                       viewEdge(g, classes),
                       voxelPolar(g),
                       g.resolution() * g.resolution(),
                       two_s2,
                       std::cos(grid.robot().phi()),
                       std::sin(grid.robot().phi()),
                       grid.robot().x(),
                       grid.robot().y(),
                       static_cast<float>(p.k_g),
                       verdicts,
                       lowerSurface(g, plane, p, classes)};
  // Voxels from the farthest to the nearest.
  for (const int32_t k : farthestFirst(g))
    if (classes[k] != VoxelClass::None) integrateVoxel(frame, k);
  return st;
}

}  // namespace carenav::perception
