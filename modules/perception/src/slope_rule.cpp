// Steep ground: slope per region of the elevation grid against the ground
// plane (docs/perceive.md "Noise-aware voxel rules", rule 4).
#include <carenav/perception/ism.h>

#include <cmath>

namespace carenav::perception {

namespace {

/** Summed-area tables of the least-squares sums of the ground voxels
 *  (cell indices i, j; mean z; squared standard error of the mean). */
struct Sums {
  static constexpr int kN = 11;  // 1 i j ii ij jj z iz jz se2 zz
  int m;
  std::vector<double> t;  // (m + 1)^2 x kN
  explicit Sums(int cells) : m(cells), t(static_cast<size_t>(cells + 1) * (cells + 1) * kN, 0) {}
  double* at(int i, int j) { return &t[(static_cast<size_t>(i) * (m + 1) + j) * kN]; }
  /** Window [i0, i1) x [j0, j1). */
  void window(int i0, int j0, int i1, int j1, double out[kN]) {
    const double *a = at(i1, j1), *b = at(i0, j1), *c = at(i1, j0), *d = at(i0, j0);
    for (int k = 0; k < kN; ++k) out[k] = a[k] - b[k] - c[k] + d[k];
  }
};

void buildSums(const ElevationGrid& g, const PerceptionParams& p, const Point3f* o,
               const std::vector<VoxelClass>& classes, uint32_t min_n, Sums& s) {
  const int m = g.cells();
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      double v[Sums::kN] = {};
      const size_t k = static_cast<size_t>(i) * m + j;
      const ElevationCell& c = g.at(i, j);
      if (classes[k] == VoxelClass::Ground && c.n >= min_n) {
        const double sv = verticalNoise(p, o, g.centre(i), g.centre(j), c.mean);
        const double z = c.mean;
        const double vals[Sums::kN] = {
            1, double(i), double(j), double(i) * i, double(i) * j, double(j) * j,
            z, i * z,     j * z,     sv * sv / c.n, z * z};
        for (int q = 0; q < Sums::kN; ++q) v[q] = vals[q];
      }
      double* out = s.at(i + 1, j + 1);
      const double *up = s.at(i, j + 1), *left = s.at(i + 1, j), *diag = s.at(i, j);
      for (int q = 0; q < Sums::kN; ++q) out[q] = v[q] + up[q] + left[q] - diag[q];
    }
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

}  // namespace

size_t markSteepGround(const ElevationGrid& g, const Plane& plane, const PerceptionParams& p,
                       const Point3f* o, std::vector<VoxelClass>& classes) {
  constexpr int kHalf = 3;          // window of 7 x 7 cells (35 cm at d_r = 5 cm)
  constexpr double kMinFill = 0.5;  // share of the window holding judged ground voxels
  if (p.max_slope_deg <= 0 || std::abs(plane.c) < 1e-6) return 0;
  const int m = g.cells();
  const uint32_t min_n = static_cast<uint32_t>(std::max(1.0, p.d_min));
  thread_local Sums s(m);
  if (s.m != m) s = Sums(m);
  buildSums(g, p, o, classes, min_n, s);
  // Slopes are measured against the plane (the floor the robot stands on,
  // free of the mounting's calibration error) while it is level within the
  // mounting's tilt uncertainty; a plane tilted more (fitted to a ramp that
  // fills the view) is no reference: the robot frame's level is.
  const double r = g.resolution();
  // (pitch and roll each off by up to prior_tilt_deg: a tilt of sqrt(2) times that)
  const bool level =
      std::acos(std::min(1.0, std::abs(plane.c))) <= std::sqrt(2.0) * p.prior_tilt_deg * M_PI / 180;
  const double g0i = level ? -plane.a / plane.c * r : 0.0,
               g0j = level ? -plane.b / plane.c * r : 0.0;
  const double tmax = std::tan(p.max_slope_deg * M_PI / 180.0) * r;  // rise per cell
  const double need = kMinFill * (2 * kHalf + 1) * (2 * kHalf + 1);
  std::vector<int32_t> steep;
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      const size_t k = static_cast<size_t>(i) * m + j;
      if (classes[k] != VoxelClass::Ground || g.at(i, j).n < min_n) continue;
      if (o && nearRangeLimit(g, p, *o, i, j)) continue;
      double w[Sums::kN];
      s.window(std::max(0, i - kHalf), std::max(0, j - kHalf), std::min(m, i + kHalf + 1),
               std::min(m, j + kHalf + 1), w);
      const double n = w[0];
      if (n < need) continue;
      const double sii = w[3] - w[1] * w[1] / n, sij = w[4] - w[1] * w[2] / n,
                   sjj = w[5] - w[2] * w[2] / n;
      const double siz = w[7] - w[1] * w[6] / n, sjz = w[8] - w[2] * w[6] / n;
      const double det = sii * sjj - sij * sij;
      if (det <= 1e-9) continue;
      const double bi = (sjj * siz - sij * sjz) / det - g0i,
                   bj = (sii * sjz - sij * siz) / det - g0j;
      // A step inside the window (two surfaces) is no slope: the plane fit
      // must leave residuals of the noise's size (chi-square bound at noise_k).
      const double bi_abs = bi + g0i, bj_abs = bj + g0j;
      const double rss = (w[10] - w[6] * w[6] / n) - bi_abs * siz - bj_abs * sjz;
      if (rss / (n - 3) > w[9] / n * (1 + p.noise_k * std::sqrt(2 / (n - 3)))) continue;
      const double slope = std::hypot(bi, bj);
      // Standard error of the slope from the cells' standard errors (mean of
      // their squares): var(b) ~ se2 / S for each axis.
      const double se2 = w[9] / n;
      const double se = std::sqrt(se2 * 0.5 * (sjj + sii) / det);
      if (slope > tmax && slope > p.noise_k * se) steep.push_back(static_cast<int32_t>(k));
    }
  for (const int32_t k : steep) classes[k] = VoxelClass::Obstacle;
  return steep.size();
}

}  // namespace carenav::perception
