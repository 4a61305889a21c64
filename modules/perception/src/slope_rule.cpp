// Steep ground: slope per region of the elevation grid against the ground
// plane (docs/perceive.md "Noise-aware voxel rules", rule 4).
#include <carenav/perception/ism.h>

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

bool judged(const ElevationGrid& g, const std::vector<VoxelClass>& classes, uint32_t min_n, int i,
            int j) {
  return classes[static_cast<size_t>(i) * g.cells() + j] == VoxelClass::Ground &&
         g.at(i, j).n >= min_n;
}

/** The box of the judged ground voxels and the tables over it; false when
 *  there is none. */
bool buildSums(const ElevationGrid& g, const PerceptionParams& p, const Point3f* o,
               const std::vector<VoxelClass>& classes, uint32_t min_n, Sums& s) {
  const int m = g.cells();
  int lo_i = m, hi_i = -1, lo_j = m, hi_j = -1;
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j)
      if (judged(g, classes, min_n, i, j)) {
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
      if (judged(g, classes, min_n, i, j)) {
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
};

/** Rule 4 on one window's sums: steeper than tmax against the reference,
 *  and by more than k standard errors, with residuals of the noise's size. */
bool steepWindow(const double w[Sums::kN], const SlopeTest& t) {
  const double n = w[0];
  if (n < t.need) return false;
  const double sii = w[3] - w[1] * w[1] / n, sij = w[4] - w[1] * w[2] / n,
               sjj = w[5] - w[2] * w[2] / n;
  const double siz = w[7] - w[1] * w[6] / n, sjz = w[8] - w[2] * w[6] / n;
  const double det = sii * sjj - sij * sij;
  if (det <= 1e-9) return false;
  const double bi = (sjj * siz - sij * sjz) / det, bj = (sii * sjz - sij * siz) / det;
  // A step inside the window (two surfaces) is no slope: the plane fit must
  // leave residuals of the noise's size (chi-square bound at noise_k).
  const double rss = (w[10] - w[6] * w[6] / n) - bi * siz - bj * sjz;
  const double se2 = w[9] / n;  // mean squared standard error of the cells
  if (rss / (n - 3) > se2 * (1 + t.k * std::sqrt(2 / (n - 3)))) return false;
  const double slope = std::hypot(bi - t.g0i, bj - t.g0j);
  // Standard error of the slope: var(b) ~ se2 / S on each axis.
  const double se = std::sqrt(se2 * 0.5 * (sjj + sii) / det);
  return slope > t.tmax && slope > t.k * se;
}

}  // namespace

size_t markSteepGround(const ElevationGrid& g, const Plane& plane, const PerceptionParams& p,
                       const Point3f* o, std::vector<VoxelClass>& classes) {
  constexpr int kHalf = 3;          // window of 7 x 7 cells (35 cm at d_r = 5 cm)
  constexpr double kMinFill = 0.5;  // share of the window holding judged ground voxels
  if (p.max_slope_deg <= 0 || std::abs(plane.c) < 1e-6) return 0;
  const uint32_t min_n = static_cast<uint32_t>(std::max(1.0, p.d_min));
  thread_local Sums s;
  if (!buildSums(g, p, o, classes, min_n, s)) return 0;
  // Slopes are measured against the plane (the floor the robot stands on,
  // free of the mounting's calibration error) while it is level within the
  // mounting's tilt uncertainty (pitch and roll each off by up to
  // prior_tilt_deg: sqrt(2) times that); a plane tilted more (fitted to a
  // ramp that fills the view) is no reference: the robot frame's level is.
  const double r = g.resolution();
  const bool level =
      std::acos(std::min(1.0, std::abs(plane.c))) <= std::sqrt(2.0) * p.prior_tilt_deg * M_PI / 180;
  const SlopeTest t{level ? -plane.a / plane.c * r : 0.0, level ? -plane.b / plane.c * r : 0.0,
                    std::tan(p.max_slope_deg * M_PI / 180.0) * r,
                    kMinFill * (2 * kHalf + 1) * (2 * kHalf + 1), p.noise_k};
  std::vector<int32_t> steep;
  for (int i = s.i0; i < s.i0 + s.mi; ++i)
    for (int j = s.j0; j < s.j0 + s.mj; ++j) {
      if (!judged(g, classes, min_n, i, j) || (o && nearRangeLimit(g, p, *o, i, j))) continue;
      double w[Sums::kN];
      s.window(i - kHalf, j - kHalf, i + kHalf + 1, j + kHalf + 1, w);
      if (steepWindow(w, t)) steep.push_back(i * g.cells() + j);
    }
  for (const int32_t k : steep) classes[k] = VoxelClass::Obstacle;
  return steep.size();
}

}  // namespace carenav::perception
