// Steep ground: slope per region of the elevation grid against the ground
// plane (docs/perceive.md "Noise-aware voxel rules", rule 4).
#include <carenav/perception/ism.h>

#include "slope_reference.h"

#include <algorithm>
#include <cmath>

namespace carenav::perception {

namespace {

/** Summed-area tables of the least-squares sums of the judged ground voxels
 *  (cell indices i, j relative to the box holding them; mean z; squared
 *  standard error of the mean), over that box only. */
struct Sums {
  static constexpr int kN = 11;        // 1 i j ii ij jj z iz jz se2 zz
  int i0 = 0, j0 = 0, mi = 0, mj = 0;  // box origin and size (cells)
  std::vector<double> t;               // (mi + 1) x (mj + 1) x kN
  double* at(int i, int j) { return &t[(static_cast<size_t>(i) * (mj + 1) + j) * kN]; }
  /** Window [i0, i1) x [j0, j1) in grid cells, clipped to the box. */
  void window(int a0, int b0, int a1, int b1, double out[kN]) {
    a0 = std::clamp(a0 - i0, 0, mi), a1 = std::clamp(a1 - i0, 0, mi);
    b0 = std::clamp(b0 - j0, 0, mj), b1 = std::clamp(b1 - j0, 0, mj);
    const double *a = at(a1, b1), *b = at(a0, b1), *c = at(a1, b0), *d = at(a0, b0);
    for (int k = 0; k < kN; ++k) out[k] = a[k] - b[k] - c[k] + d[k];
  }
};

/** A voxel with enough samples to judge (N_z >= d_min), on the ground
 *  (any: whatever its class). */
bool judged(const ElevationGrid& g, const std::vector<VoxelClass>& classes, uint32_t min_n, int i,
            int j, bool any = false) {
  const VoxelClass vc = classes[static_cast<size_t>(i) * g.cells() + j];
  return (any ? vc != VoxelClass::None : vc == VoxelClass::Ground) && g.at(i, j).n >= min_n;
}

/** The box of the judged ground voxels and the tables over it; false when
 *  there is none. */
bool buildSums(const ElevationGrid& g, const PerceptionParams& p, const Point3f* o,
               const std::vector<VoxelClass>& classes, uint32_t min_n, Sums& s, bool any = false) {
  const int m = g.cells();
  int lo_i = m, hi_i = -1, lo_j = m, hi_j = -1;
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j)
      if (judged(g, classes, min_n, i, j, any)) {
        lo_i = std::min(lo_i, i), hi_i = std::max(hi_i, i);
        lo_j = std::min(lo_j, j), hi_j = std::max(hi_j, j);
      }
  if (hi_i < 0) return false;
  s.i0 = lo_i, s.j0 = lo_j, s.mi = hi_i - lo_i + 1, s.mj = hi_j - lo_j + 1;
  s.t.assign(static_cast<size_t>(s.mi + 1) * (s.mj + 1) * Sums::kN, 0.0);
  for (int li = 0; li < s.mi; ++li)
    for (int lj = 0; lj < s.mj; ++lj) {
      double v[Sums::kN] = {};
      const int i = li + s.i0, j = lj + s.j0;
      if (judged(g, classes, min_n, i, j, any)) {
        const ElevationCell& c = g.at(i, j);
        const double sv = verticalNoise(p, o, g.centre(i), g.centre(j), c.mean);
        const double z = c.mean, a = li, b = lj;
        const double vals[Sums::kN] = {1, a,     b,     a * a,         a * b, b * b,
                                       z, a * z, b * z, sv * sv / c.n, z * z};
        for (int q = 0; q < Sums::kN; ++q) v[q] = vals[q];
      }
      double* out = s.at(li + 1, lj + 1);
      const double *up = s.at(li, lj + 1), *left = s.at(li + 1, lj), *diag = s.at(li, lj);
      for (int q = 0; q < Sums::kN; ++q) out[q] = v[q] + up[q] + left[q] - diag[q];
    }
  return true;
}

/** Whether the voxel lies within noise_k depth sigmas of depth_max: there the
 *  range cut removes the samples the noise pushed beyond it, the cell means
 *  are biased and so is the slope (the far end of the view). */
bool nearRangeLimit(const ElevationGrid& g, const PerceptionParams& p, const Point3f& o, int i,
                    int j) {
  const double dx = g.centre(i) - o.x, dy = g.centre(j) - o.y, dz = g.at(i, j).mean - o.z;
  const double r = std::sqrt(dx * dx + dy * dy + dz * dz);
  return r + p.noise_k * p.depth_noise_std * r * r > p.depth_max;
}

/** What rule 4 needs per window. */
struct SlopeTest {
  double g0i, g0j;  // gradient of the reference (per cell)
  double tmax;      // largest rise per cell
  double need;      // judged voxels a window must hold
  double k;         // noise_k
  int half;         // window half size (cells)
};

/** Least-squares fit of one window's sums: slope against the reference
 *  (rise per cell), its standard error, and whether the residuals are of
 *  the noise's size; false when the window cannot be judged. */
bool fitWindow(const double w[Sums::kN], const SlopeTest& t, double& slope, double& se) {
  const double n = w[0];
  if (n < t.need) return false;
  const double sii = w[3] - w[1] * w[1] / n, sij = w[4] - w[1] * w[2] / n,
               sjj = w[5] - w[2] * w[2] / n;
  const double siz = w[7] - w[1] * w[6] / n, sjz = w[8] - w[2] * w[6] / n;
  const double det = sii * sjj - sij * sij;
  if (det <= 1e-9) return false;
  const double bi = (sjj * siz - sij * sjz) / det, bj = (sii * sjz - sij * siz) / det;
  const double rss = (w[10] - w[6] * w[6] / n) - bi * siz - bj * sjz;
  const double se2 = w[9] / n;
  if (rss / (n - 3) > se2 * (1 + t.k * std::sqrt(2 / (n - 3)))) return false;
  slope = std::hypot(bi - t.g0i, bj - t.g0j);
  se = std::sqrt(se2 * 0.5 * (sjj + sii) / det);
  return true;
}

/** Gradient (rise per cell along i and j) of the least-squares plane of the
 *  ground voxels nearest the robot: those within kNearDepth of the nearest
 *  one (the floor the robot stands on, as far as the camera sees it), and the
 *  variance of that gradient (the sum over i and j, from the fit's
 *  residuals); false with fewer than kMinCells of them, or when that plane
 *  does not pass under the robot at z = 0 (within prior_height_tolerance
 *  plus noise_k standard errors of its gradient times the distance): then
 *  the nearest voxels are no floor the robot stands on (a ramp whose foot
 *  hides the floor, its fit mixed with the little floor in view, leaned 2.3
 *  deg and passed 9 cm below the robot; a level landing measured 6 deg
 *  against it). */
bool nearFloorGradient(const ElevationGrid& g, const PerceptionParams& p,
                       const std::vector<VoxelClass>& classes, uint32_t min_n, double& gi,
                       double& gj, double& var) {
  constexpr double kNearDepth = 0.75;  // m
  constexpr double kMinCells = 20;
  const int m = g.cells();
  double d0 = 1e9;
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j)
      if (judged(g, classes, min_n, i, j)) d0 = std::min(d0, std::hypot(g.centre(i), g.centre(j)));
  double w[10] = {};
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      if (!judged(g, classes, min_n, i, j) ||
          std::hypot(g.centre(i), g.centre(j)) > d0 + kNearDepth)
        continue;
      const double z = g.at(i, j).mean, a = i, b = j;
      const double v[10] = {1, a, b, a * a, a * b, b * b, z, a * z, b * z, z * z};
      for (int q = 0; q < 10; ++q) w[q] += v[q];
    }
  const double n = w[0];
  if (n < kMinCells) return false;
  const double sii = w[3] - w[1] * w[1] / n, sij = w[4] - w[1] * w[2] / n,
               sjj = w[5] - w[2] * w[2] / n;
  const double siz = w[7] - w[1] * w[6] / n, sjz = w[8] - w[2] * w[6] / n;
  const double det = sii * sjj - sij * sij;
  if (det <= 1e-9) return false;
  gi = (sjj * siz - sij * sjz) / det;
  gj = (sii * sjz - sij * siz) / det;
  const double rss = std::max(0.0, (w[9] - w[6] * w[6] / n) - gi * siz - gj * sjz);
  var = rss / (n - 3) * (sii + sjj) / det;
  const double c0 = 0.5 * (m - 1);  // the robot's cell (the grid's centre)
  const double ai = w[1] / n - c0, aj = w[2] / n - c0;
  const double z0 = w[6] / n - gi * ai - gj * aj;
  return std::abs(z0) <= p.prior_height_tolerance + p.noise_k * std::sqrt(var) * std::hypot(ai, aj);
}

}  // namespace

SlopeReference slopeReference(const ElevationGrid& g, const Plane& plane, const PerceptionParams& p,
                              const std::vector<VoxelClass>& classes, uint32_t min_n) {
  // Slopes are measured against the floor the robot stands on: the ground
  // voxels nearest to it (when their plane passes under the robot at z = 0:
  // nearFloorGradient()), else the plane, whichever is level within the
  // mounting's tilt uncertainty first (pitch and roll each off by up to
  // prior_tilt_deg: sqrt(2) times that; it hides the calibration error); a
  // surface tilted more (a plane fitted to a ramp that fills the view) is no
  // reference: the robot frame's level is.
  const double r = g.resolution();
  const double tol = std::tan(std::sqrt(2.0) * p.prior_tilt_deg * M_PI / 180) * r;
  SlopeReference ref;
  if (nearFloorGradient(g, p, classes, min_n, ref.gi, ref.gj, ref.var) &&
      std::hypot(ref.gi, ref.gj) <= tol)
    return ref;
  ref.var = 0;
  ref.gi = -plane.a / plane.c * r, ref.gj = -plane.b / plane.c * r;
  if (std::hypot(ref.gi, ref.gj) > tol) ref.gi = ref.gj = 0;
  return ref;
}

namespace {

SlopeTest slopeTest(const ElevationGrid& g, const Plane& plane, const PerceptionParams& p,
                    const std::vector<VoxelClass>& classes, uint32_t min_n) {
  constexpr int kHalf = 3;          // window of 7 x 7 cells (35 cm at d_r = 5 cm)
  constexpr double kMinFill = 0.5;  // share of the window holding judged voxels
  const SlopeReference ref = slopeReference(g, plane, p, classes, min_n);
  return {ref.gi,
          ref.gj,
          std::tan(p.max_slope_deg * M_PI / 180.0) * g.resolution(),
          kMinFill * (2 * kHalf + 1) * (2 * kHalf + 1),
          p.noise_k,
          kHalf};
}

}  // namespace

size_t markSteepWindows(const ElevationGrid& g, const Plane& plane, const PerceptionParams& p,
                        const Point3f* o, std::vector<VoxelClass>& classes,
                        const std::vector<uint8_t>* decided, std::vector<uint8_t>* gentle,
                        const SlopeReference* ref) {
  if (p.max_slope_deg <= 0 || std::abs(plane.c) < 1e-6) return 0;
  const uint32_t min_n = static_cast<uint32_t>(std::max(1.0, p.d_min));
  thread_local Sums s;
  if (!buildSums(g, p, o, classes, min_n, s)) return 0;
  SlopeTest t = slopeTest(g, plane, p, classes, min_n);
  if (ref) t.g0i = ref->gi, t.g0j = ref->gj;
  std::vector<int32_t> steep;
  for (int i = s.i0; i < s.i0 + s.mi; ++i)
    for (int j = s.j0; j < s.j0 + s.mj; ++j) {
      if (!judged(g, classes, min_n, i, j) || (o && nearRangeLimit(g, p, *o, i, j))) continue;
      const size_t k = static_cast<size_t>(i) * g.cells() + j;
      const uint8_t region = decided ? (*decided)[k] : 0;
      if (region == 2) continue;
      double w[Sums::kN], slope, se;
      s.window(i - t.half, j - t.half, i + t.half + 1, j + t.half + 1, w);
      const bool fit = fitWindow(w, t, slope, se);
      if (fit && (region == 1 ? slope - t.k * se > t.tmax : slope > t.tmax && slope > t.k * se))
        steep.push_back(static_cast<int32_t>(k));
      else if (gentle && (region == 1 || (fit && slope <= t.tmax)))
        (*gentle)[k] = 1;
    }
  for (const int32_t k : steep) classes[k] = VoxelClass::Obstacle;
  return steep.size();
}

size_t markSteepGround(const ElevationGrid& g, const Plane& plane, const PerceptionParams& p,
                       const Point3f* o, std::vector<VoxelClass>& classes,
                       const std::vector<uint8_t>* decided) {
  return markSteepWindows(g, plane, p, o, classes, decided, nullptr);
}

size_t rescueGentleGround(const ElevationGrid& g, const Plane& plane, const PerceptionParams& p,
                          const Point3f* o, std::vector<VoxelClass>& classes) {
  if (p.max_slope_deg <= 0 || std::abs(plane.c) < 1e-6) return 0;
  const uint32_t min_n = static_cast<uint32_t>(std::max(1.0, p.d_min));
  thread_local Sums s;
  if (!buildSums(g, p, o, classes, min_n, s, true)) return 0;
  const SlopeTest t = slopeTest(g, plane, p, classes, min_n);
  const int m = g.cells();
  std::vector<int32_t> queue;
  for (int32_t k = 0; k < m * m; ++k)
    if (classes[k] == VoxelClass::Ground) queue.push_back(k);
  size_t rescued = 0;
  for (size_t h = 0; h < queue.size(); ++h)
    forEachNeighbour4(g, queue[h], [&](int bi, int bj, int32_t k) {
      if (classes[k] != VoxelClass::Obstacle || g.at(bi, bj).n < min_n) return;
      if (o && nearRangeLimit(g, p, *o, bi, bj)) return;
      double w[Sums::kN], slope, se;
      s.window(bi - t.half, bj - t.half, bi + t.half + 1, bj + t.half + 1, w);
      if (!fitWindow(w, t, slope, se) || slope > t.tmax) return;
      classes[k] = VoxelClass::Ground;
      queue.push_back(k);
      ++rescued;
    });
  return rescued;
}

}  // namespace carenav::perception
