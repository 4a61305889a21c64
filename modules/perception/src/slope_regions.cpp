// Rule 6, ramps by region (docs/perceive.md "Noise-aware voxel rules"): the
// slope of a whole smooth region of the elevation grid, with its standard
// error, decides for every voxel of the region.
#include "slope_reference.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

namespace carenav::perception {

namespace {

/** Weighted least-squares sums of z = c + gx x + gy y (x, y in m from the
 *  region's seed; weight 1 / variance of the cell mean). */
struct PlaneSums {
  double w = 0, x = 0, y = 0, xx = 0, xy = 0, yy = 0, z = 0, xz = 0, yz = 0, zz = 0;
  size_t n = 0;
  void add(double wt, double a, double b, double c) {
    w += wt, x += wt * a, y += wt * b, z += wt * c;
    xx += wt * a * a, xy += wt * a * b, yy += wt * b * b;
    xz += wt * a * c, yz += wt * b * c, zz += wt * c * c;
    ++n;
  }
};

/** A weighted plane fit: height at the origin, gradient (per m), the
 *  gradient's variance (sum over x and y) and the chi-square of the fit. */
struct PlaneFit {
  double c = 0, gx = 0, gy = 0, var = 0, chi2 = 0;
  double at(double a, double b) const { return c + gx * a + gy * b; }
};

bool fitPlane(const PlaneSums& s, PlaneFit& f) {
  if (s.n < 3 || s.w <= 0) return false;
  const double mx = s.x / s.w, my = s.y / s.w, mz = s.z / s.w;
  const double sxx = s.xx - s.w * mx * mx, sxy = s.xy - s.w * mx * my, syy = s.yy - s.w * my * my;
  const double sxz = s.xz - s.w * mx * mz, syz = s.yz - s.w * my * mz;
  const double szz = s.zz - s.w * mz * mz;
  const double det = sxx * syy - sxy * sxy;
  if (!(det > 1e-6 * sxx * syy) || det <= 0) return false;  // cells in a line
  f.gx = (syy * sxz - sxy * syz) / det;
  f.gy = (sxx * syz - sxy * sxz) / det;
  f.c = mz - f.gx * mx - f.gy * my;
  f.chi2 = std::max(0.0, szz - f.gx * sxz - f.gy * syz);
  f.var = (sxx + syy) / det;
  return true;
}

/** Per cell of the grid: the mean, the variance a region allows it (< 0:
 *  not judged), its region (-1: none), the margin (cells) a region's slope
 *  fit keeps from its border there, and its distance (cells) to that border. */
struct RegionCells {
  std::vector<float> z, var, blur;
  std::vector<int32_t> label, inner;
  std::vector<uint8_t> far;   ///< judged but within noise_k depth sigmas of depth_max
  std::vector<uint8_t> edge;  ///< near the data's near edge (nearEdge(), judgedFit())
};

/** How far (cells) a kink of max_slope_deg stays within noise_k sqrt(var)
 *  of a region's plane past the region's border. */
double kinkCells(const ElevationGrid& g, const PerceptionParams& p, double var) {
  return p.noise_k * std::sqrt(var) / std::tan(p.max_slope_deg * M_PI / 180) / g.resolution();
}

/** Whether cell (i, j), its centre `dh` m from the sensor's foot along
 *  the ground (unit vector (ux, uy) towards it), lies within one cell plus
 *  `sh` (region_trim_k depth sigmas, their horizontal part) of a cell
 *  without a sample nearer the sensor: the near edge of the data (the
 *  image's lower border, the far side of a shadow). A sample moves along
 *  its ray by the depth noise; the cells at that edge lose the samples
 *  moved nearer and receive none from nearer hits, so their means hold
 *  mostly the samples moved up and nearer (a floor seen from 1.16 m with
 *  2.5 times the noise: the first row 2 cm high), and a short floor's slope
 *  fit, tilted by them, made a 6.7 deg ramp beyond it read 7.4 deg. */
bool nearEdge(const ElevationGrid& g, int i, int j, double ux, double uy, double dh, double sh) {
  const double r = g.resolution();
  const double reach = std::min(dh, 1.5 * r + sh);
  for (double s = 0.5 * r; s <= reach; s += 0.5 * r) {
    const int a = g.cellOf(g.centre(i) + ux * s), b = g.cellOf(g.centre(j) + uy * s);
    if ((a != i || b != j) && (!g.inside(a, b) || g.at(a, b).n == 0)) return true;
  }
  return false;
}

void prepareCells(const ElevationGrid& g, const PerceptionParams& p, const Point3f& o,
                  const std::vector<float>& thr, const std::vector<float>& se,
                  const std::vector<VoxelClass>& classes, RegionCells& cs) {
  const int m = g.cells();
  const size_t mm = static_cast<size_t>(m) * m;
  const uint32_t min_n = static_cast<uint32_t>(std::max(1.0, p.d_min));
  const double tol2 = p.region_tolerance * p.region_tolerance;
  cs.z.resize(mm);
  cs.var.assign(mm, -1.f);
  cs.blur.resize(mm);
  cs.label.assign(mm, -1);
  cs.far.assign(mm, 0);
  cs.edge.assign(mm, 0);
  for (size_t k = 0; k < mm; ++k) {
    if (classes[k] == VoxelClass::None) continue;
    const int i = static_cast<int>(k / m), j = static_cast<int>(k % m);
    const ElevationCell& c = g.at(i, j);
    if (c.n < min_n) continue;
    // Flat within the noise (no step inside, as rule 3): z+ and z- within
    // the rule-1 band, widened by one sigma_v, around the cell's mean.
    const double sv = se[k] * std::sqrt(static_cast<double>(c.n));
    const double flat = thr[k] + sv;
    if (c.z_hi - c.mean > flat || c.mean - c.z_lo > flat) continue;
    // Not within noise_k depth sigmas of depth_max (biased means, rule 4).
    const double dx = g.centre(i) - o.x, dy = g.centre(j) - o.y, dz = c.mean - o.z;
    const double r = std::sqrt(dx * dx + dy * dy + dz * dz);
    if (r + p.noise_k * p.depth_noise_std * r * r > p.depth_max) {
      cs.far[k] = 1;
      continue;
    }
    // Near the data's near edge the means are high: judgedFit() may leave
    // the cells within a cell plus region_trim_k depth sigmas (their
    // horizontal part) of it out of a region's slope fit.
    const double dh = std::hypot(dx, dy), sray = p.depth_noise_std * r * r;
    cs.edge[k] =
        dh > 0 && nearEdge(g, i, j, -dx / dh, -dy / dh, dh, p.region_trim_k * sray * dh / r);
    cs.z[k] = static_cast<float>(c.mean);
    cs.var[k] = static_cast<float>(static_cast<double>(se[k]) * se[k] + tol2);
    // Margin a region's slope fit keeps from its border: a sample moves along
    // its ray by the depth noise (sigma depth_noise_std r^2), so a kink at
    // the border (a ramp's foot) is smeared over trim_k of those; and a kink
    // of max_slope_deg stays within noise_k sqrt(var) of the region's plane
    // for kinkCells() beyond it (the region grown first takes those cells).
    cs.blur[k] = static_cast<float>(p.region_trim_k * p.depth_noise_std * r * r / g.resolution() +
                                    kinkCells(g, p, cs.var[k]));
  }
}

/** The cells of an m x m grid nearest the robot (its centre) first. */
const std::vector<int32_t>& nearestFirst(const ElevationGrid& g) {
  thread_local std::vector<int32_t> order;
  const int m = g.cells();
  if (order.size() != static_cast<size_t>(m) * m) {
    order.resize(static_cast<size_t>(m) * m);
    for (int32_t k = 0; k < m * m; ++k) order[k] = k;
    auto d2 = [&](int32_t k) { return std::hypot(k / m - (m - 1) / 2.0, k % m - (m - 1) / 2.0); };
    std::stable_sort(order.begin(), order.end(),
                     [&](int32_t a, int32_t b) { return d2(a) < d2(b); });
  }
  return order;
}

/** Plane of the unlabelled judged cells of the 7 x 7 window around the seed
 *  (x, y from the seed), when it holds at least half the window and its
 *  residuals are of the noise's size. */
bool seedPlane(const ElevationGrid& g, const RegionCells& cs, double k, int32_t seed, PlaneFit& f) {
  constexpr int kHalf = 3;
  constexpr size_t kMinCells = 25;  // half of 7 x 7
  const int m = g.cells(), si = seed / m, sj = seed % m;
  const double r = g.resolution();
  PlaneSums w;
  for (int di = -kHalf; di <= kHalf; ++di)
    for (int dj = -kHalf; dj <= kHalf; ++dj) {
      if (!g.inside(si + di, sj + dj)) continue;
      const size_t q = static_cast<size_t>(si + di) * m + sj + dj;
      if (cs.var[q] > 0 && cs.label[q] < 0) w.add(1.0 / cs.var[q], di * r, dj * r, cs.z[q]);
    }
  if (w.n < kMinCells || !fitPlane(w, f)) return false;
  const double dof = static_cast<double>(w.n) - 3;
  return f.chi2 / dof <= 1 + k * std::sqrt(2 / dof);
}

/** Grows region `id` from `seed`, breadth first over 4-neighbours whose mean
 *  lies within k sqrt(var) of the region's plane (refitted each time the
 *  region doubles); its cells are appended to `members`, its sums to `s`. */
void growRegion(const ElevationGrid& g, RegionCells& cs, double k, int32_t seed, int32_t id,
                PlaneFit f, std::vector<int32_t>& members, PlaneSums& s) {
  const int m = g.cells(), si = seed / m, sj = seed % m;
  const double r = g.resolution();
  const size_t start = members.size();
  auto take = [&](int32_t q, double x, double y) {
    const double dz = cs.z[q] - f.at(x, y);
    if (dz * dz > k * k * cs.var[q]) return;
    cs.label[q] = id;
    members.push_back(q);
    s.add(1.0 / cs.var[q], x, y, cs.z[q]);
  };
  take(seed, 0, 0);
  size_t fitted = 16;
  for (size_t h = start; h < members.size(); ++h) {
    if (s.n >= 2 * fitted) {
      PlaneFit nf;
      if (fitPlane(s, nf)) f = nf;
      fitted = s.n;
    }
    forEachNeighbour4(g, members[h], [&](int bi, int bj, int32_t q) {
      if (cs.var[q] > 0 && cs.label[q] < 0) take(q, (bi - si) * r, (bj - sj) * r);
    });
  }
}

/** Members of every region (in cell order) from the labels. */
void regroup(const std::vector<int32_t>& label, size_t regions, std::vector<int32_t>& members,
             std::vector<size_t>& starts) {
  starts.assign(regions + 1, 0);
  for (const int32_t l : label)
    if (l >= 0) ++starts[l + 1];
  for (size_t id = 0; id < regions; ++id) starts[id + 1] += starts[id];
  members.resize(starts[regions]);
  std::vector<size_t> at(starts.begin(), starts.end() - 1);
  for (int32_t q = 0; q < static_cast<int32_t>(label.size()); ++q)
    if (label[q] >= 0) members[at[label[q]]++] = q;
}

/** Each region's plane (x, y from its seed), fitted to all its cells. */
struct RegionPlanes {
  std::vector<PlaneFit> fit;
  std::vector<uint8_t> ok;
};

/** Plain weighted fits of every region over all its cells. */
void fitAll(const ElevationGrid& g, const RegionCells& cs, const std::vector<int32_t>& seeds,
            const std::vector<int32_t>& members, const std::vector<size_t>& starts,
            RegionPlanes& pl) {
  const int m = g.cells();
  const double r = g.resolution();
  pl.fit.assign(seeds.size(), PlaneFit{});
  pl.ok.assign(seeds.size(), 0);
  for (size_t id = 0; id < seeds.size(); ++id) {
    PlaneSums s;
    const int si = seeds[id] / m, sj = seeds[id] % m;
    for (size_t h = starts[id]; h < starts[id + 1]; ++h) {
      const int32_t q = members[h];
      s.add(1.0 / cs.var[q], (q / m - si) * r, (q % m - sj) * r, cs.z[q]);
    }
    pl.ok[id] = fitPlane(s, pl.fit[id]);
  }
}

/** Border cells move to the neighbouring region whose plane fits their mean
 *  better (within k sqrt(var)): a region grown first takes the cells past
 *  a kink (a ramp's foot) that fit it within the noise; the region beyond
 *  fits them better. A work list of border cells, until no cell moves. */
void refineBorders(const ElevationGrid& g, const std::vector<int32_t>& seeds, double k,
                   RegionCells& cs, const RegionPlanes& pl) {
  const int m = g.cells();
  const double r = g.resolution();
  auto res2 = [&](int32_t q, int32_t id) {
    const int32_t s = seeds[id];
    const double dz = cs.z[q] - pl.fit[id].at((q / m - s / m) * r, (q % m - s % m) * r);
    return dz * dz / cs.var[q];
  };
  auto usable = [&](int i, int j) {
    if (!g.inside(i, j)) return -1;
    const int32_t l = cs.label[i * m + j];
    return l >= 0 && pl.ok[l] ? l : -1;
  };
  thread_local std::vector<int32_t> work;
  thread_local std::vector<uint8_t> queued;
  work.clear();
  queued.assign(static_cast<size_t>(m) * m, 0);
  auto push = [&](int i, int j) {
    if (usable(i, j) < 0 || queued[i * m + j]) return;
    queued[i * m + j] = 1;
    work.push_back(i * m + j);
  };
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      const int32_t own = usable(i, j);
      if (own >= 0 && (usable(i - 1, j) != own || usable(i + 1, j) != own ||
                       usable(i, j - 1) != own || usable(i, j + 1) != own))
        push(i, j);
    }
  const size_t budget = 8 * work.size();
  for (size_t h = 0; h < work.size() && h < budget; ++h) {
    const int32_t q = work[h], own = cs.label[q];
    const int i = q / m, j = q % m;
    queued[q] = 0;
    const int nbs[4][2] = {{i - 1, j}, {i + 1, j}, {i, j - 1}, {i, j + 1}};
    double best = res2(q, own);
    int32_t to = own;
    for (const auto& b : nbs) {
      const int32_t other = usable(b[0], b[1]);
      if (other < 0 || other == own) continue;
      const double e = res2(q, other);
      if (e < best && e <= k * k) best = e, to = other;
    }
    if (to == own) continue;
    cs.label[q] = to;
    for (const auto& b : nbs) push(b[0], b[1]);
  }
}

/** Whether cell n is a one-cell hole in a region: a voxel no region holds
 *  whose four neighbours all belong to one region (one outlier sample or a
 *  sparse cell inside a surface, no kink or step: those run along a line of
 *  such voxels or between two regions). */
bool holeInRegion(const RegionCells& cs, int m, size_t n) {
  const int i = static_cast<int>(n / static_cast<size_t>(m)),
            j = static_cast<int>(n % static_cast<size_t>(m));
  if (cs.label[n] >= 0 || i < 1 || j < 1 || i + 1 >= m || j + 1 >= m) return false;
  const int32_t l = cs.label[n - static_cast<size_t>(m)];
  return l >= 0 && cs.label[n + static_cast<size_t>(m)] == l && cs.label[n - 1] == l &&
         cs.label[n + 1] == l;
}

/** City-block distance (cells) of every labelled cell to the nearest cell
 *  of another region or voxel no region holds (a kink or a step may lie
 *  there), two passes. No border: cells without data, the grid's edge, the
 *  voxels near depth_max (the end of the view: their means are biased,
 *  they are no other surface; as a border they cut the fit's margin, up to
 *  ~0.7 m at 3.5 m with 3 times the noise, off a ramp running out of range
 *  and left it no interior to judge) and one-cell holes in a region
 *  (holeInRegion(): each cut a disc of the fit's margin out of a far ramp,
 *  whose region then held too few cells to be judged and kept the false
 *  obstacles of rules 1-5). A voxel not judged with another one or a
 *  region other than its neighbours' beside it stays a border: with every
 *  lone voxel taken as none, a steep ramp seen over a few rows at the end
 *  of the view joined a region judged gentle (12 steep ramps clear in 2650
 *  scenes instead of 8). */
void innerDistance(const std::vector<VoxelClass>& classes, int m, RegionCells& cs) {
  const size_t mm = static_cast<size_t>(m) * m;
  cs.inner.assign(mm, 0);
  auto relax = [&](size_t k, bool inside, size_t n) {
    if (!inside || classes[n] == VoxelClass::None || (cs.label[n] < 0 && cs.far[n])) return;
    if (holeInRegion(cs, m, n)) return;
    const int32_t d = cs.label[n] != cs.label[k] ? 1 : cs.inner[n] + 1;
    cs.inner[k] = std::min(cs.inner[k], d);
  };
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      const size_t k = static_cast<size_t>(i) * m + j;
      if (cs.label[k] < 0) continue;
      cs.inner[k] = 1 << 20;
      relax(k, i > 0, k - (i > 0 ? m : 0));
      relax(k, j > 0, k - (j > 0 ? 1 : 0));
    }
  for (int i = m - 1; i >= 0; --i)
    for (int j = m - 1; j >= 0; --j) {
      const size_t k = static_cast<size_t>(i) * m + j;
      if (cs.label[k] < 0) continue;
      relax(k, i + 1 < m, k + (i + 1 < m ? m : 0));
      relax(k, j + 1 < m, k + (j + 1 < m ? 1 : 0));
    }
}

/** The slope fit of a region (its cells `members`, x and y from the seed)
 *  over its cells farther from its border than their blur (a kink at the
 *  border, a ramp's foot or landing, is smeared over that by the noise),
 *  with `skip_edge` not near the data's near edge (nearEdge()), refitted
 *  kTrimPasses times to the cells within trim_k standard errors of the
 *  previous fit, so that the cells taken past a kink do not bias it; `n`
 *  receives the cells of the last fit. */
bool trimmedFit(const ElevationGrid& g, const RegionCells& cs, const std::vector<int32_t>& members,
                int32_t seed, double trim_k, bool skip_edge, PlaneFit& f, size_t& n) {
  constexpr int kTrimPasses = 3;
  const int m = g.cells(), si = seed / m, sj = seed % m;
  const double r = g.resolution();
  size_t interior = 0;
  for (int pass = 0; pass <= kTrimPasses; ++pass) {
    PlaneSums s;
    for (const int32_t q : members) {
      const double x = (q / m - si) * r, y = (q % m - sj) * r;
      if (cs.inner[q] <= cs.blur[q] || (skip_edge && cs.edge[q])) continue;
      const double dz = cs.z[q] - f.at(x, y);
      if (pass == 0 || dz * dz <= trim_k * trim_k * cs.var[q])
        s.add(1.0 / cs.var[q], x, y, cs.z[q]);
      if (pass == 0) ++interior;
    }
    PlaneFit nf;
    if (s.n < interior / 2 || !fitPlane(s, nf)) return pass > 0;
    f = nf;
    n = s.n;
  }
  return true;
}

/** Slope (rad) of the plane with gradient (gx, gy) (per m) against the
 *  reference's: the angle between their normals. */
double slopeAgainst(double gx, double gy, double rgx, double rgy) {
  const double n1[3] = {-gx, -gy, 1}, n2[3] = {-rgx, -rgy, 1};
  const double dot = n1[0] * n2[0] + n1[1] * n2[1] + n1[2] * n2[2];
  const double cx = n1[1] * n2[2] - n1[2] * n2[1], cy = n1[2] * n2[0] - n1[0] * n2[2],
               cz = n1[0] * n2[1] - n1[1] * n2[0];
  return std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz), dot);
}

/** What a region's verdict needs: its fit and the floor slopes are measured
 *  against (gradient per m and its variance). */
struct RegionFit {
  PlaneFit f;
  double se2 = 0;  // variance of the gradient, scaled up when the residuals exceed the model
  size_t n = 0;
};

RegionFit regionFit(const PlaneFit& f, size_t n) {
  const double dof = static_cast<double>(n) - 3;
  return {f, f.var * std::max(1.0, f.chi2 / dof), n};
}

/** Steep: the slope against the reference plus noise_k standard errors (of
 *  the region's and the reference's gradients; a gradient's error bounds the
 *  angle's) above max_slope_deg. */
bool regionSteep(const RegionFit& a, const RegionFit& ref, const PerceptionParams& p) {
  const double theta = slopeAgainst(a.f.gx, a.f.gy, ref.f.gx, ref.f.gy);
  const double se = std::sqrt(a.se2 + ref.se2);
  return theta + p.noise_k * se > p.max_slope_deg * M_PI / 180.0;
}

/** Per region: its verdict (0 not judged, 1 gentle, 2 steep), its fitted
 *  plane (x, y from its seed) and its seed. */
struct Verdicts {
  std::vector<uint8_t> v;
  std::vector<PlaneFit> fit;
  std::vector<double> se2;  ///< variance of the judged fit's gradient (RegionFit)
  std::vector<int32_t> seed;
  double at(const ElevationGrid& g, int32_t id, double i, double j) const {
    const int m = g.cells();
    return fit[id].at((i - seed[id] / m) * g.resolution(), (j - seed[id] % m) * g.resolution());
  }
};

/** Per pair of judged regions sharing a border (4-neighbour cell pairs):
 *  the sum of their planes' height differences at the pairs' midpoints
 *  (the higher id's minus the lower's), the sum of the border cells' var,
 *  the number of pairs, and the sums of the midpoints' cell coordinates. */
using Borders = std::map<std::pair<int32_t, int32_t>, std::array<double, 5>>;

Borders regionBorders(const ElevationGrid& g, const RegionCells& cs, const Verdicts& vd) {
  Borders border;
  const int m = g.cells();
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      const int32_t q = i * m + j, a = cs.label[q];
      if (a < 0 || !vd.v[a]) continue;
      const int nbs[2][2] = {{i + 1, j}, {i, j + 1}};
      for (const auto& nb : nbs) {
        if (!g.inside(nb[0], nb[1])) continue;
        const int32_t q2 = nb[0] * m + nb[1], b = cs.label[q2];
        if (b < 0 || b == a || !vd.v[b]) continue;
        const double mi = 0.5 * (i + nb[0]), mj = 0.5 * (j + nb[1]);
        const double d = vd.at(g, std::max(a, b), mi, mj) - vd.at(g, std::min(a, b), mi, mj);
        auto& e = border[{std::min(a, b), std::max(a, b)}];
        e[0] += d, e[1] += 0.5 * (cs.var[q] + cs.var[q2]), e[2] += 1;
        e[3] += mi, e[4] += mj;
      }
    }
  return border;
}

/** Whether two regions meet without a step along their border `e`: their
 *  planes differ on average by no more than one cell's rise at
 *  max_slope_deg plus noise_k sqrt(var) of the border cells (the growth
 *  band: how far a border may lie from a kink) (a ramp's foot or top: the
 *  planes meet at the border; a curb or a step: they differ by its height
 *  all along). */
bool meetWithoutStep(const std::array<double, 5>& e, const ElevationGrid& g,
                     const PerceptionParams& p) {
  const double rise = std::tan(p.max_slope_deg * M_PI / 180) * g.resolution();
  return std::abs(e[0] / e[2]) <= rise + p.noise_k * std::sqrt(e[1] / e[2]);
}

/** The gentle regions reached from `floor_id` through borders without a
 *  step (meetWithoutStep). */
std::vector<uint8_t> reachedRegions(const Borders& border, const Verdicts& vd, int32_t floor_id,
                                    const ElevationGrid& g, const PerceptionParams& p) {
  std::vector<uint8_t> reach(vd.v.size(), 0);
  if (floor_id < 0) return reach;
  reach[floor_id] = 1;
  for (bool grew = true; grew;) {
    grew = false;
    for (const auto& [key, e] : border) {
      const int32_t a = key.first, b = key.second;
      if (reach[a] == reach[b] || vd.v[reach[a] ? b : a] != 1) continue;
      if (!meetWithoutStep(e, g, p)) continue;
      reach[a] = reach[b] = 1;
      grew = true;
    }
  }
  return reach;
}

/** A step along the border `e` of regions a and b: their planes differ
 *  there by at least mean_step, and by more than meetWithoutStep allows with
 *  the planes' own uncertainty at the border added to the cells' (each
 *  gradient's standard error times the border's distance from the region's
 *  seed, where its fit is anchored: a far region's plane, extrapolated to
 *  its border with the floor, is off by that). */
bool isStep(const std::array<double, 5>& e, const ElevationGrid& g, const PerceptionParams& p,
            const Verdicts& vd, int32_t a, int32_t b) {
  const int m = g.cells();
  const double r = g.resolution(), mi = e[3] / e[2], mj = e[4] / e[2];
  auto dist2 = [&](int32_t id) {
    const double di = (mi - vd.seed[id] / m) * r, dj = (mj - vd.seed[id] % m) * r;
    return di * di + dj * dj;
  };
  const double fit_var = vd.se2[a] * dist2(a) + vd.se2[b] * dist2(b);
  const double diff = std::abs(e[0] / e[2]);
  const double rise = std::tan(p.max_slope_deg * M_PI / 180) * r;
  return diff >= p.mean_step && diff > rise + p.noise_k * std::sqrt(e[1] / e[2] + fit_var);
}

/** Steps between levels: a gentle region not reached that borders a
 *  reached one with a step (isStep: at least mean_step, the height rule 2
 *  calls an obstacle, and beyond the noise), their planes parallel within noise_k
 *  standard errors of their gradients (two levels; a ramp's foot where the
 *  border lies off the kink differs by the ramp's slope), is a level the
 *  walker cannot drive onto from there (a step up, the street past a curb).
 *  Rules 1 and 2 judge heights against the ground plane, which may lie
 *  between the two levels (a 2.3 cm step: the plane 1.1 cm up, both levels
 *  within mean_step of it): the region's ground voxels along that border
 *  become obstacles, the step's line. Returns how many. */
size_t markStepBorders(const ElevationGrid& g, const PerceptionParams& p, const RegionCells& cs,
                       const Verdicts& vd, const Borders& border, const std::vector<uint8_t>& reach,
                       std::vector<VoxelClass>& classes) {
  std::vector<uint8_t> level(vd.v.size(), 0);  // 1: a region past a step from a reached one
  for (const auto& [key, e] : border) {
    const int32_t a = key.first, b = key.second;
    if (reach[a] == reach[b] || vd.v[reach[a] ? b : a] != 1) continue;
    const bool parallel = slopeAgainst(vd.fit[a].gx, vd.fit[a].gy, vd.fit[b].gx, vd.fit[b].gy) <=
                          p.noise_k * std::sqrt(vd.se2[a] + vd.se2[b]);
    if (parallel && isStep(e, g, p, vd, a, b)) level[reach[a] ? b : a] = 1;
  }
  const int m = g.cells();
  size_t marked = 0;
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      const int32_t q = i * m + j, l = cs.label[q];
      if (l < 0 || !level[l] || classes[q] != VoxelClass::Ground) continue;
      const int nbs[4][2] = {{i + 1, j}, {i - 1, j}, {i, j + 1}, {i, j - 1}};
      for (const auto& nb : nbs) {
        if (!g.inside(nb[0], nb[1])) continue;
        const int32_t l2 = cs.label[nb[0] * m + nb[1]];
        if (l2 < 0 || !reach[l2]) continue;
        classes[q] = VoxelClass::Obstacle;
        ++marked;
        break;
      }
    }
  return marked;
}

/** Vertical noise (m) of the samples of voxel q about a surface with the
 *  plane of region l. A sample moves along its ray by the depth noise
 *  (depth_noise_std r^2); its height over the surface at the point where it
 *  lands changes by that times (d_z - grad . d_xy), d the ray's unit
 *  vector: depth_noise_std r H, H the sensor's height over the surface's
 *  plane (vertically). On a level floor H is the sensor's height over the
 *  voxel (sigma_v of rule 1); on a surface rising away from the sensor (a
 *  ramp ahead) H is larger: on a 6 deg ramp from 1.5 m seen from 0.9 m, a
 *  voxel 3 m ahead has H 1.04 m against 0.72 m over it, 1.4 times the
 *  scatter. Never less than rule 1's sigma_v. */
double surfaceNoise(const ElevationGrid& g, const PerceptionParams& p, const Point3f& o,
                    const Verdicts& vd, int32_t l, size_t q) {
  const int m = g.cells(), i = static_cast<int>(q / m), j = static_cast<int>(q % m);
  const ElevationCell& c = g.at(i, j);
  const double dx = g.centre(i) - o.x, dy = g.centre(j) - o.y, dz = c.mean - o.z;
  const double r = std::sqrt(dx * dx + dy * dy + dz * dz);
  const PlaneFit& f = vd.fit[l];
  const double h = o.z - (vd.at(g, l, i, j) - f.gx * dx - f.gy * dy);
  return p.depth_noise_std * r * std::max(h, std::abs(dz));
}

/** Rules 1 and 2 pass for voxel q against the plane of region l, with the
 *  noise about that plane (surfaceNoise()); with `level` (not NaN), against
 *  the nearest of the heights between that plane's and `level` at q. */
bool onRegionPlane(const ElevationGrid& g, const PerceptionParams& p, const Point3f& o,
                   const Verdicts& vd, int32_t l, size_t q, const std::vector<float>& thr,
                   const std::vector<float>& se, double level = std::nan("")) {
  const int m = g.cells(), i = static_cast<int>(q / m), j = static_cast<int>(q % m);
  const ElevationCell& c = g.at(i, j);
  double zp = vd.at(g, l, i, j);
  if (!std::isnan(level)) zp = std::clamp(c.mean, std::min(zp, level), std::max(zp, level));
  const double sv = surfaceNoise(g, p, o, vd, l, q);
  const double t = std::max<double>(thr[q], p.noise_k * sv);
  if (std::max(std::abs(c.z_hi - zp), std::abs(c.z_lo - zp)) > t) return false;
  const double e = std::max<double>(se[q], sv / std::sqrt(static_cast<double>(c.n)));
  return p.mean_step <= 0 || std::abs(c.mean - zp) <= p.mean_step + p.noise_k * e;
}

/** Beyond the reached regions: the voxels no judged region holds (near
 *  depth_max, where the means are biased; not flat within the level-floor
 *  noise model; in a region too small to judge; with fewer than d_min
 *  samples) connected to a reached region other than the floor's, breadth
 *  first, take that region's plane or a level-off of it: an obstacle voxel
 *  becomes ground when it passes rules 1 and 2, with the noise about that
 *  plane (surfaceNoise(); rule 2's error of the mean grows as its samples
 *  get fewer), against a surface
 *  that leaves the region's cell the search started from with the region's
 *  slope or levels off there or anywhere farther (a landing at a ramp's top
 *  or foot, parallel to the floor's plane, gradient `floor_g` per m): the
 *  height nearest its mean between the region's plane and the floor's
 *  parallel through that cell. A drop or a step beyond lies outside both;
 *  a steeper slope rises above the region's plane. The search goes on
 *  through the voxels near depth_max and the ground voxels (an obstacle
 *  stops it: nothing behind a step is reached). A voxel of a sample or two
 *  on that surface is no obstacle either: kept as one, those of a far
 *  landing seen at a grazing angle stopped the search and cut off the rest
 *  of it (a landing 3.4-4.5 m ahead of a camera 0.5 m high: 81 % of it
 *  occupied, 25 % now). */
void extendBeyondRegions(const ElevationGrid& g, const PerceptionParams& p, const Point3f& o,
                         const RegionCells& cs, const Verdicts& vd,
                         const std::vector<uint8_t>& reach, int32_t floor_id,
                         const std::array<double, 2>& floor_g, const std::vector<float>& thr,
                         const std::vector<float>& se, std::vector<VoxelClass>& classes,
                         RegionCounts& rc) {
  const int m = g.cells();
  const double r = g.resolution();
  thread_local std::vector<int32_t> from, start, queue;
  from.assign(classes.size(), -1);
  start.assign(classes.size(), -1);
  queue.clear();
  for (size_t q = 0; q < classes.size(); ++q) {
    const int32_t l = cs.label[q];
    if (l >= 0 && l != floor_id && reach[l] && vd.v[l] == 1)
      from[q] = l, start[q] = static_cast<int32_t>(q), queue.push_back(q);
  }
  for (size_t h = 0; h < queue.size(); ++h) {
    const int32_t k = queue[h];
    forEachNeighbour4(g, k, [&](int bi, int bj, int32_t q) {
      const int32_t l = cs.label[q];
      if (from[q] >= 0 || classes[q] == VoxelClass::None || (l >= 0 && vd.v[l])) return;
      from[q] = from[k];
      start[q] = start[k];
      const int si = start[q] / m, sj = start[q] % m;
      const double level =
          vd.at(g, from[q], si, sj) + (floor_g[0] * (bi - si) + floor_g[1] * (bj - sj)) * r;
      if (classes[q] == VoxelClass::Obstacle &&
          onRegionPlane(g, p, o, vd, from[q], q, thr, se, level)) {
        classes[q] = VoxelClass::Ground;
        ++rc.rescued;
      }
      if (cs.far[q] || classes[q] == VoxelClass::Ground) queue.push_back(q);
    });
  }
}

/** Whether the floor's region (fit `fl`) is the floor the robot stands on:
 *  its plane, extended to under the sensor, lies within
 *  prior_height_tolerance plus noise_k standard errors (of its gradient,
 *  times the distance from its seed) of the robot frame's floor z = 0. A
 *  pitch or roll error turns the view about the sensor and leaves the floor
 *  there; a lower surface seen first (the street past a curb in the blind
 *  zone) is off by the drop. */
bool underRobot(const ElevationGrid& g, const PerceptionParams& p, const Point3f& o,
                const Verdicts& vd, int32_t id, const RegionFit& fl) {
  const int m = g.cells();
  const double x = o.x - g.centre(vd.seed[id] / m), y = o.y - g.centre(vd.seed[id] % m);
  return std::abs(vd.fit[id].at(x, y)) <=
         p.prior_height_tolerance + p.noise_k * std::sqrt(fl.se2) * std::hypot(x, y);
}

/** Applies the verdicts: the ground voxels of steep regions become
 *  obstacles; the obstacle voxels of reached regions (the floor's region
 *  too: it lies under the robot, underRobot(), and its plane is the floor's
 *  where the ground plane may lean, e.g. under a calibration error) become
 *  ground when rules 1 and 2 pass against the
 *  region's own plane with the noise about it (onRegionPlane(); `thr`,
 *  `se`: per cell the rule-1 threshold and the mean's standard error; a
 *  threshold's cells may lie within the growth band, not within these);
 *  every voxel of a judged region is `decided`. */
void applyVerdicts(const ElevationGrid& g, const PerceptionParams& p, const Point3f& o,
                   const RegionCells& cs, const Verdicts& vd, const std::vector<uint8_t>& reach,
                   const std::vector<float>& thr, const std::vector<float>& se,
                   std::vector<VoxelClass>& classes, std::vector<uint8_t>& decided,
                   RegionCounts& rc) {
  for (size_t q = 0; q < classes.size(); ++q) {
    const int32_t l = cs.label[q];
    if (l < 0 || !vd.v[l]) continue;
    // A gentle region's plane holds away from its border: the cells within
    // the distance a max_slope_deg kink stays in its growth band (a steep
    // ramp's first cells taken by the floor's region) keep rule 4's window.
    decided[q] = vd.v[l] == 1 && cs.inner[q] <= kinkCells(g, p, cs.var[q]) ? 0 : vd.v[l];
    if (vd.v[l] == 2 && classes[q] == VoxelClass::Ground) {
      classes[q] = VoxelClass::Obstacle;
      ++rc.steep;
      continue;
    }
    if (!reach[l] || classes[q] != VoxelClass::Obstacle) continue;
    if (!onRegionPlane(g, p, o, vd, l, q, thr, se)) continue;
    classes[q] = VoxelClass::Ground;
    ++rc.rescued;
  }
}

/** The regions: grown nearest the robot first, their borders refined
 *  (twice, with the planes refitted); `members` of region id are
 *  [starts[id], starts[id + 1]). */
struct Regions {
  std::vector<int32_t> seeds, members;
  std::vector<size_t> starts;
};

void growAll(const ElevationGrid& g, const PerceptionParams& p, RegionCells& cs, Regions& rg) {
  rg.seeds.clear(), rg.members.clear(), rg.starts.clear();
  for (const int32_t seed : nearestFirst(g)) {
    if (cs.var[seed] <= 0 || cs.label[seed] >= 0) continue;
    PlaneFit f;
    if (!seedPlane(g, cs, p.noise_k, seed, f)) continue;
    rg.starts.push_back(rg.members.size());
    rg.seeds.push_back(seed);
    PlaneSums s;
    growRegion(g, cs, p.noise_k, seed, static_cast<int32_t>(rg.seeds.size() - 1), f, rg.members, s);
  }
  rg.starts.push_back(rg.members.size());
  thread_local RegionPlanes pl;
  for (int round = 0; round < 2; ++round) {
    fitAll(g, cs, rg.seeds, rg.members, rg.starts, pl);
    refineBorders(g, rg.seeds, p.noise_k, cs, pl);
    regroup(cs.label, rg.seeds.size(), rg.members, rg.starts);
  }
}

/** Plain weighted fit of region `id` over all its cells (x, y from its seed). */
bool plainFit(const ElevationGrid& g, const RegionCells& cs, const Regions& rg, size_t id,
              PlaneFit& f) {
  const int m = g.cells(), si = rg.seeds[id] / m, sj = rg.seeds[id] % m;
  const double r = g.resolution();
  PlaneSums s;
  for (size_t h = rg.starts[id]; h < rg.starts[id + 1]; ++h) {
    const int32_t q = rg.members[h];
    s.add(1.0 / cs.var[q], (q / m - si) * r, (q % m - sj) * r, cs.z[q]);
  }
  return fitPlane(s, f);
}

/** Short views: a region that rule 6's trimmed fit could not judge (too
 *  few cells away from its border: a ramp seen over a few rows at the end
 *  of the view, all of it within the noise's smear of its foot or of the
 *  view's end) is judged by the plain fit over all its cells when that fit
 *  is one plane within the level-floor noise the region was grown with
 *  (the bound of seedPlane(): a region over a blurred step edge is not) and
 *  has the extent to tell a level surface from max_slope_deg (2 noise_k
 *  standard errors at most max_slope_deg): steep, as rule 6, when its slope
 *  against the floor plus noise_k standard errors exceeds max_slope_deg.
 *  The smear flattens a short view (a 13.4 deg ramp seen over 0.2 m read
 *  6.9 +- 0.4 deg), so nothing in that band is safe to call gentle. Only
 *  steep verdicts are given: a region left unjudged keeps what the other
 *  rules said, and nothing is given back as ground. */
void judgeShortViews(const ElevationGrid& g, const PerceptionParams& p, const RegionCells& cs,
                     const Regions& rg, const RegionFit& floor, Verdicts& vd) {
  // At least 9 degrees of freedom for the plane's chi-square test below
  // (region_min_cells, 50, is what the trimmed fit needs).
  constexpr size_t kMinCells = 12;
  const double max_slope = p.max_slope_deg * M_PI / 180.0;
  for (size_t id = 0; id < rg.seeds.size(); ++id) {
    const size_t n = rg.starts[id + 1] - rg.starts[id];
    PlaneFit f;
    if (vd.v[id] || n < kMinCells || !plainFit(g, cs, rg, id, f)) continue;
    const double dof = static_cast<double>(n) - 3;
    if (f.chi2 / dof > 1 + p.noise_k * std::sqrt(2 / dof)) continue;
    const RegionFit a = regionFit(f, n);
    if (2 * p.noise_k * std::sqrt(a.se2 + floor.se2) > max_slope || !regionSteep(a, floor, p))
      continue;
    vd.fit[id] = f;
    vd.v[id] = 2;
  }
}

/** A region's trimmed fit (trimmedFit()) over at least region_min_cells,
 *  without or with the cells near the data's near edge (nearEdge()):
 *  without them when the two fits' gradients differ by more than
 *  region_trim_k standard errors of that difference (nested fits: the root
 *  of the difference of their gradient variances), their means biased (a
 *  0.5 m floor strip seen from 1.16 m with 2.5x the noise: 0.7 deg apart,
 *  4.5 of those); else with them (fewer cells, a larger standard error: a
 *  6.1 deg ramp past a floor of 182 cells at decimation 4 read 5.5 +- 0.65
 *  deg without them, steep). When only one holds region_min_cells, that one
 *  (a floor of a few rows is a better floor than none: rule 4's reference,
 *  a plane that may lean on the ramp beyond, made an 8.9 deg ramp 4.5 deg). */
bool judgedFit(const ElevationGrid& g, const PerceptionParams& p, const RegionCells& cs,
               const std::vector<int32_t>& members, int32_t seed, PlaneFit& f, size_t& n) {
  const size_t min_cells = static_cast<size_t>(p.region_min_cells);
  if (members.size() < min_cells) return false;
  PlaneFit fa, fb;
  size_t na = 0, nb = 0;
  const bool any_edge =
      std::any_of(members.begin(), members.end(), [&](int32_t q) { return cs.edge[q] != 0; });
  const bool a = any_edge && trimmedFit(g, cs, members, seed, p.region_trim_k, true, fa, na) &&
                 na >= min_cells;
  const bool b =
      trimmedFit(g, cs, members, seed, p.region_trim_k, false, fb, nb) && nb >= min_cells;
  if (!a && !b) return false;
  bool skip = a;
  if (a && b) {
    const double d2 = (fa.gx - fb.gx) * (fa.gx - fb.gx) + (fa.gy - fb.gy) * (fa.gy - fb.gy);
    const double v = regionFit(fa, na).se2 - regionFit(fb, nb).se2;
    skip = d2 > p.region_trim_k * p.region_trim_k * std::max(0.0, v);
  }
  f = skip ? fa : fb;
  n = skip ? na : nb;
  return true;
}

/** The verdict on every region of at least region_min_cells (in its slope
 *  fit too); returns the floor's region (-1: none). The floor slopes are
 *  measured against: the first judged region (seeded nearest the robot)
 *  when it is level within the mounting's tilt uncertainty and its plane
 *  passes under the sensor at the robot's floor (underRobot(): a ramp whose
 *  foot hides the floor in view, seen 4 deg tilted under a pitch error, is
 *  not the floor its landing is measured against), else `ref`. */
int32_t judgeAll(const ElevationGrid& g, const PerceptionParams& p, const Point3f& o,
                 const RegionCells& cs, const Regions& rg, const SlopeReference& ref, Verdicts& vd,
                 RegionFit& floor) {
  const double r = g.resolution();
  const double tol = std::tan(std::sqrt(2.0) * p.prior_tilt_deg * M_PI / 180);
  floor = {{0, ref.gi / r, ref.gj / r, 0, 0}, ref.var / (r * r)};
  vd.v.assign(rg.seeds.size(), 0);
  vd.fit.assign(rg.seeds.size(), PlaneFit{});
  vd.se2.assign(rg.seeds.size(), 0.0);
  vd.seed = rg.seeds;
  int32_t floor_id = -1;
  bool first = true;
  thread_local std::vector<int32_t> one;
  for (size_t id = 0; id < rg.seeds.size(); ++id) {
    one.assign(rg.members.begin() + rg.starts[id], rg.members.begin() + rg.starts[id + 1]);
    size_t n = 0;
    if (!judgedFit(g, p, cs, one, rg.seeds[id], vd.fit[id], n)) continue;
    const RegionFit a = regionFit(vd.fit[id], n);
    vd.se2[id] = a.se2;
    if (first && std::hypot(a.f.gx, a.f.gy) <= tol &&
        underRobot(g, p, o, vd, static_cast<int32_t>(id), a))
      floor = a, floor_id = static_cast<int32_t>(id);
    first = false;
    vd.v[id] = regionSteep(a, floor, p) ? 2 : 1;
  }
  return floor_id;
}

}  // namespace

RegionCounts judgeSlopeRegions(const ElevationGrid& g, const PerceptionParams& p, const Point3f& o,
                               const SlopeReference& ref, const std::vector<float>& thr,
                               const std::vector<float>& se, std::vector<VoxelClass>& classes,
                               std::vector<uint8_t>& decided) {
  RegionCounts rc;
  thread_local RegionCells cs;
  thread_local Regions rg;
  thread_local Verdicts vd;
  prepareCells(g, p, o, thr, se, classes, cs);
  growAll(g, p, cs, rg);
  innerDistance(classes, g.cells(), cs);
  RegionFit floor;
  const int32_t floor_id = judgeAll(g, p, o, cs, rg, ref, vd, floor);
  judgeShortViews(g, p, cs, rg, floor, vd);
  if (floor_id >= 0) {
    const double r = g.resolution();
    rc.floor = true;
    rc.floor_ref = {floor.f.gx * r, floor.f.gy * r, floor.se2 * r * r};
  }
  const Borders border = regionBorders(g, cs, vd);
  const std::vector<uint8_t> reach = reachedRegions(border, vd, floor_id, g, p);
  applyVerdicts(g, p, o, cs, vd, reach, thr, se, classes, decided, rc);
  rc.steps = markStepBorders(g, p, cs, vd, border, reach, classes);
  extendBeyondRegions(g, p, o, cs, vd, reach, floor_id, {floor.f.gx, floor.f.gy}, thr, se, classes,
                      rc);
  return rc;
}

}  // namespace carenav::perception
