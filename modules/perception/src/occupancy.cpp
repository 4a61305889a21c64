#include <carenav/io/map_io.h>
#include <carenav/perception/occupancy.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace carenav::perception {

namespace {
inline float logit(float p) { return std::log(p / (1 - p)); }
constexpr float kPMin = 0.02f, kPMax = 0.98f;  // per-measurement clamp (no certainty)
}  // namespace

LocalOccupancy::LocalOccupancy(int cells, double resolution, double logodds_max)
    : m_(cells), r_(resolution), lmax_(logodds_max) {
  reset();
}

void LocalOccupancy::reset() {
  const size_t n = static_cast<size_t>(m_) * m_;
  logodds_.assign(n, 0.f);
  occ_.assign(n, 0.5f);
  free_.assign(n, 0.5f);
  robot_ = mrpt::poses::CPose2D();
  org_i_ = org_j_ = -m_ / 2;
}

void LocalOccupancy::moveTo(const mrpt::poses::CPose2D& robot) {
  robot_ = robot;
  const long ni = static_cast<long>(std::floor(robot.x() / r_)) - m_ / 2;
  const long nj = static_cast<long>(std::floor(robot.y() / r_)) - m_ / 2;
  if (ni == org_i_ && nj == org_j_) return;
  std::vector<float> moved(logodds_.size(), 0.f);
  for (int i = 0; i < m_; ++i)
    for (int j = 0; j < m_; ++j) {
      const long oi = ni + i - org_i_, oj = nj + j - org_j_;  // old grid index
      if (oi < 0 || oj < 0 || oi >= m_ || oj >= m_) continue;
      moved[static_cast<size_t>(i) * m_ + j] = logodds_[static_cast<size_t>(oi) * m_ + oj];
    }
  logodds_.swap(moved);
  org_i_ = ni;
  org_j_ = nj;
}

int LocalOccupancy::cellX(double x) const {
  return static_cast<int>(static_cast<long>(std::floor(x / r_)) - org_i_);
}
int LocalOccupancy::cellY(double y) const {
  return static_cast<int>(static_cast<long>(std::floor(y / r_)) - org_j_);
}
double LocalOccupancy::centreX(int i) const { return (org_i_ + i + 0.5) * r_; }
double LocalOccupancy::centreY(int j) const { return (org_j_ + j + 0.5) * r_; }

void LocalOccupancy::beginFrame() {
  std::fill(occ_.begin(), occ_.end(), 0.5f);
  std::fill(free_.begin(), free_.end(), 0.5f);
}

void LocalOccupancy::addEvidence(int i, int j, float p) {
  if (!inside(i, j)) return;
  const size_t k = static_cast<size_t>(i) * m_ + j;
  if (p > 0.5f)
    occ_[k] = std::max(occ_[k], p);
  else if (p < 0.5f)
    free_[k] = std::min(free_[k], p);
}

void LocalOccupancy::endFrame() {
  const float lm = static_cast<float>(lmax_);
  for (size_t k = 0; k < logodds_.size(); ++k) {
    const float p = occ_[k] > 0.5f ? occ_[k] : free_[k];
    if (p == 0.5f) continue;  // no information
    // [Garrote17, Eq. 3] with p(c) = 0.5: l_t = logit(p(c|z_t)) + l_{t-1}.
    const float l = logodds_[k] + logit(std::clamp(p, kPMin, kPMax));
    logodds_[k] = std::clamp(l, -lm, lm);
  }
}

double LocalOccupancy::prob(int i, int j) const {
  if (!inside(i, j)) return 0.5;
  const float l = logodds_[static_cast<size_t>(i) * m_ + j];
  return 1.0 / (1.0 + std::exp(-static_cast<double>(l)));
}

double LocalOccupancy::probAt(double x, double y) const { return prob(cellX(x), cellY(y)); }

CellCounts LocalOccupancy::counts(double free_below, double occupied_above) const {
  // p > t  <=>  log-odds > logit(t): no exp per cell.
  const double lo = std::log(occupied_above / (1 - occupied_above));
  const double lf = std::log(free_below / (1 - free_below));
  CellCounts c;
  for (const float l : logodds_) {
    if (l > lo)
      ++c.occupied;
    else if (l < lf)
      ++c.free;
    else
      ++c.unknown;
  }
  return c;
}

mrpt::maps::COccupancyGridMap2D LocalOccupancy::toMrpt() const {
  auto g = io::makeGrid(org_i_ * r_, org_j_ * r_, r_, static_cast<size_t>(m_),
                        static_cast<size_t>(m_), 0.5f);
  for (int i = 0; i < m_; ++i)
    for (int j = 0; j < m_; ++j) g.setCell(i, j, static_cast<float>(1.0 - prob(i, j)));
  return g;
}

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

IsmStats classifyVoxels(const ElevationGrid& g, const Plane& plane, const PerceptionParams& p,
                        const Point3f* o, std::vector<VoxelClass>& classes) {
  IsmStats st;
  const int m = g.cells();
  const size_t mm = static_cast<size_t>(m) * m;
  classes.assign(mm, VoxelClass::None);
  // Per voxel: rule-1 threshold and the standard error of the mean (kept for rule 3).
  thread_local std::vector<float> thr, se;
  thr.resize(mm);
  se.resize(mm);
  std::vector<int32_t> queue;
  queue.reserve(mm / 4);
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      const ElevationCell& c = g.at(i, j);
      if (c.n == 0) continue;
      const size_t k = static_cast<size_t>(i) * m + j;
      const double x = g.centre(i), y = g.centre(j);
      const double sv = verticalNoise(p, o, x, y, c.mean);
      const double t = std::max(p.d_pth, p.noise_k * sv);
      const double e = sv / std::sqrt(static_cast<double>(c.n));
      thr[k] = static_cast<float>(t);
      se[k] = static_cast<float>(e);
      // Rule 1 ([Garrote17]): max distance of z+ and z- to the plane.
      bool obstacle = voxelPlaneDistance(c, x, y, plane) > t;
      // Rule 2: the mean of a voxel with enough samples (d_min, [Garrote17, Eq. 4]).
      if (!obstacle && p.mean_step > 0 && c.n >= std::max(1.0, p.d_min))
        obstacle = plane.distance(x, y, c.mean) > p.mean_step + p.noise_k * e;
      classes[k] = obstacle ? VoxelClass::Obstacle : VoxelClass::Ground;
      if (!obstacle) queue.push_back(static_cast<int32_t>(k));
    }
  // Rule 3: breadth first from the ground voxels over off-plane voxels that
  // are flat within the noise and reached through slopes the robot climbs.
  if (p.max_slope_deg > 0) {
    const double rise = std::tan(p.max_slope_deg * M_PI / 180.0) * g.resolution();
    constexpr int kBaseline = 4;  // cells (20 cm at d_r = 5 cm)
    auto cells_mean = [&](int32_t k) { return g.at(k / m, k % m).mean; };
    const uint32_t min_n = static_cast<uint32_t>(std::max(1.0, p.d_min));
    // Differences of means are Gaussian (many samples): mean_k standard errors.
    const double mk = p.mean_k;
    // Chamfer (3-4) distance of every cell to the nearest voxel on the plane
    // (rules 1-2 ground), in cells: a surface that left the plane `dist`
    // away rose at most tan(max_slope) dist above it. This bounds the creep
    // of the breadth-first search over a small step blurred by the noise.
    // Sources: on-plane voxels in connected patches of at least kMinSource
    // cells; a lone noisy voxel that happens to lie near the plane (far on a
    // lower floor) must not seed a "surface" there.
    constexpr size_t kMinSource = 16;  // cells (0.04 m^2 at d_r = 5 cm)
    {
      thread_local std::vector<uint8_t> seen;
      seen.assign(mm, 0);
      std::vector<int32_t> sources, comp;
      sources.reserve(queue.size());
      for (const int32_t s0 : queue) {
        if (seen[s0]) continue;
        comp.clear();
        comp.push_back(s0);
        seen[s0] = 1;
        for (size_t h = 0; h < comp.size(); ++h) {
          const int ci = comp[h] / m, cj = comp[h] % m;
          const int nbs[4][2] = {{ci - 1, cj}, {ci + 1, cj}, {ci, cj - 1}, {ci, cj + 1}};
          for (const auto& q : nbs) {
            if (!g.inside(q[0], q[1])) continue;
            const int32_t b = q[0] * m + q[1];
            if (seen[b] || classes[b] != VoxelClass::Ground) continue;
            seen[b] = 1;
            comp.push_back(b);
          }
        }
        if (comp.size() >= kMinSource) sources.insert(sources.end(), comp.begin(), comp.end());
      }
      queue.swap(sources);
    }
    thread_local std::vector<int32_t> dist, near;
    dist.assign(mm, 1 << 29);
    near.assign(mm, -1);
    for (int32_t k : queue) {
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
    for (size_t h = 0; h < queue.size(); ++h) {
      const int32_t a = queue[h];
      const int ai = a / m, aj = a % m;
      const int dirs[4][2] = {{-1, 0}, {1, 0}, {0, -1}, {0, 1}};
      for (const auto& dv : dirs) {
        const int bi = ai + dv[0], bj = aj + dv[1];
        if (!g.inside(bi, bj)) continue;
        const size_t b = static_cast<size_t>(bi) * m + bj;
        if (classes[b] != VoxelClass::Obstacle) continue;
        const ElevationCell& c = g.at(bi, bj);
        // Too few samples to judge a slope ([Garrote17, Eq. 4]'s d_min): the sparse
        // cells of the noise streak behind a depth edge must not bridge it.
        if (c.n <= min_n) continue;
        // No step inside: z+ and z- within the rule-1 band around the cell's
        // own mean, widened by one sigma_v (a ramp voxel of ~30 samples has a
        // 4-sigma sample now and then; a step inside is larger).
        const double flat = thr[b] + se[b] * std::sqrt(static_cast<double>(c.n));
        if (c.z_hi - c.mean > flat || c.mean - c.z_lo > flat) continue;
        // Height over the nearest on-plane voxel (not the plane: when a ramp
        // and its landing fill the view the plane itself is tilted).
        const int32_t nb = near[b];
        if (nb < 0) continue;
        const double off = std::abs(c.mean - cells_mean(nb));
        const double se2 = static_cast<double>(se[nb]) * se[nb] + se[b] * se[b];
        if (off > rise * dist[b] / 3.0 + mk * std::sqrt(se2)) continue;  // too high too soon
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
        if (!ok) continue;
        classes[b] = VoxelClass::Ground;
        ++st.rescued_voxels;
        queue.push_back(static_cast<int32_t>(b));
      }
    }
  }
  for (size_t k = 0; k < mm; ++k) {
    if (classes[k] == VoxelClass::None) continue;
    ++st.voxels;
    classes[k] == VoxelClass::Obstacle ? ++st.obstacle_voxels : ++st.ground_voxels;
  }
  return st;
}

IsmStats integrateIsm(const ElevationGrid& g, const Plane& plane, const PerceptionParams& p,
                      LocalOccupancy& grid, std::vector<VoxelClass>* classes_out,
                      const Point3f* sensor_origin) {
  thread_local std::vector<VoxelClass> local;
  std::vector<VoxelClass>& classes = classes_out ? *classes_out : local;
  const IsmStats st = classifyVoxels(g, plane, p, sensor_origin, classes);
  const int m = g.cells();
  const double area = g.resolution() * g.resolution();
  const double two_s2 = 2.0 * p.sigma2;
  const double ca = std::cos(grid.robot().phi()), sa = std::sin(grid.robot().phi());
  const double rx = grid.robot().x(), ry = grid.robot().y();
  // Look-up tables over |D| (1 mm steps) for the Gaussian exp(-D^2 / 2 sigma^2)
  // and the ground sigmoid 1 / (1 + exp(-D)) of [Garrote17, Eqs. 5-6].
  constexpr double kStep = 1e-3;
  const size_t n_lut = static_cast<size_t>(grid.cells() * grid.resolution() * 1.5 / kStep) + 2;
  thread_local std::vector<float> gauss, sigm;
  thread_local double lut_s2 = -1;
  if (gauss.size() != n_lut || lut_s2 != two_s2) {
    gauss.resize(n_lut);
    sigm.resize(n_lut);
    for (size_t k = 0; k < n_lut; ++k) {
      const double D = -static_cast<double>(k) * kStep;
      gauss[k] = static_cast<float>(std::exp(-D * D / two_s2));
      sigm[k] = static_cast<float>(1.0 / (1.0 + std::exp(-D)));
    }
    lut_s2 = two_s2;
  }
  auto lut = [&](const std::vector<float>& t, double D) {
    const size_t k = static_cast<size_t>(std::abs(D) / kStep + 0.5);
    return t[std::min(k, n_lut - 1)];
  };
  const float kg = static_cast<float>(p.k_g);
  // Voxels from the farthest to the nearest (the grid is robot-centred: the
  // order is fixed). Each ray is walked from its voxel back to the robot and
  // stops once kSaturated cells in a row already hold free evidence at least
  // as strong as this ray's (a farther voxel's ray through them, processed
  // earlier, said more): same grid, a fraction of the cells visited.
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
  constexpr int kSaturated = 3;
  // Occlusion is not free space: per 1 deg bearing bin, the distance of the
  // nearest voxel holding points in this frame (the near edge of the view).
  // A cell without points farther than that along a ray lies in a shadow
  // (behind a drop-off, a hole, a box): the ray passed above it, it never saw
  // its floor, so it gets no free evidence (it stays unknown, or keeps what
  // earlier frames said). Cells nearer than the edge (the camera's blind zone
  // close to the robot) keep the rays' free evidence, as before.
  constexpr int kBins = 360;
  auto binOf = [&](double x, double y) {
    const int b = static_cast<int>(std::floor((std::atan2(y, x) + M_PI) * kBins / (2 * M_PI)));
    return std::clamp(b, 0, kBins - 1);
  };
  thread_local std::vector<float> edge, edge_raw;
  edge_raw.assign(kBins, std::numeric_limits<float>::infinity());
  for (int32_t k = 0; k < m * m; ++k) {
    if (classes[k] == VoxelClass::None) continue;
    const double x = g.centre(k / m), y = g.centre(k % m);
    float& e = edge_raw[binOf(x, y)];
    e = std::min(e, static_cast<float>(std::hypot(x, y)));
  }
  edge.resize(kBins);
  for (int b = 0; b < kBins; ++b)
    edge[b] = std::min({edge_raw[(b + kBins - 1) % kBins], edge_raw[b], edge_raw[(b + 1) % kBins]});
  for (const int32_t k : order) {
    const VoxelClass vc = classes[k];
    if (vc == VoxelClass::None) continue;
    const int i = k / m, j = k % m;
    const ElevationCell& c = g.at(i, j);
    const bool obstacle = vc == VoxelClass::Obstacle;
    const double x = g.centre(i), y = g.centre(j);
    const double rho = obstacle ? voxelDensity(c, area, p) : 0.0;
    const float amp = static_cast<float>(std::max(rho, 0.5));
    // Voxel in the odometry frame; |c_v| its distance to the robot.
    const double wx = rx + ca * x - sa * y, wy = ry + sa * x + ca * y;
    const double cv = std::hypot(x, y);
    const int vi = grid.cellX(wx), vj = grid.cellY(wy);
    // |c| in [0, |c_v|], [Garrote17, Eq. 5], from the voxel back to the robot.
    int sat = 0;
    const double near_edge = edge[binOf(x, y)] + g.resolution();
    grid.walkSegment(wx, wy, cv, 0.0, [&](int ci, int cj, double dc) {
      const bool at_voxel = ci == vi && cj == vj;
      const double D = at_voxel ? 0.0 : std::min(0.0, dc - cv);
      if (!at_voxel && dc > near_edge && cv > 1e-9) {
        const int ei = g.cellOf(x * dc / cv), ej = g.cellOf(y * dc / cv);
        if (g.inside(ei, ej) && classes[static_cast<size_t>(ei) * m + ej] == VoxelClass::None &&
            (obstacle ? amp * lut(gauss, D) : kg + (0.5f - kg) * lut(sigm, D)) < 0.5f)
          return true;  // a shadow cell: no free evidence
      }
      // (The thesis, [Rosa17, Ch. 3], writes the ground branch with the Gaussian
      // exp(-D^2 / 2 sigma^2) inside the sigmoid; carenav uses the paper's form: docs/design.md,
      // 'Inverse sensor model'.)
      const float pr = obstacle ? amp * lut(gauss, D) : kg + (0.5f - kg) * lut(sigm, D);
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
    if (!obstacle || 2 * rho <= 1) continue;
    const double beyond = std::sqrt(two_s2 * std::log(2 * rho));
    grid.walkSegment(
        wx, wy, cv, cv + 0.75 * grid.resolution() + beyond, [&](int ci, int cj, double dc) {
          if (ci == vi && cj == vj) return true;
          const double D = std::max(0.0, dc - cv);
          grid.addEvidence(ci, cj, std::max(static_cast<float>(rho) * lut(gauss, D), 0.5f));
          return true;
        });
  }
  return st;
}

size_t integrateHeightBand(const Cloud& c, const PerceptionParams& p, LocalOccupancy& grid) {
  const double bin = p.scan_resolution * M_PI / 180.0;
  const int nb = static_cast<int>(std::ceil(2 * M_PI / bin));
  std::vector<double> hit(nb, 1e300), seen(nb, 0.0);
  const double ca = std::cos(grid.robot().phi()), sa = std::sin(grid.robot().phi());
  const double rx = grid.robot().x(), ry = grid.robot().y();
  size_t band = 0;
  for (const auto& q : c.points) {
    if (!validPoint(q)) continue;
    const double r = std::hypot(q.x, q.y);
    const int b = std::clamp(static_cast<int>((std::atan2(q.y, q.x) + M_PI) / bin), 0, nb - 1);
    if (q.z > p.band_z_min && q.z < p.band_z_max) {
      ++band;
      hit[b] = std::min(hit[b], r);
      grid.addEvidence(grid.cellX(rx + ca * q.x - sa * q.y), grid.cellY(ry + sa * q.x + ca * q.y),
                       0.8f);
    }
    seen[b] = std::max(seen[b], r);
  }
  for (int b = 0; b < nb; ++b) {
    const bool has_hit = hit[b] < 1e299;
    const double range = has_hit ? hit[b] : seen[b];
    if (range <= 0) continue;
    const double a = -M_PI + (b + 0.5) * bin + grid.robot().phi();
    const double ex = rx + std::cos(a) * range, ey = ry + std::sin(a) * range;
    const int hi = grid.cellX(ex), hj = grid.cellY(ey);
    grid.walkRay(ex, ey, range, [&](int ci, int cj, double, int) {
      if (has_hit && ci == hi && cj == hj) return;
      grid.addEvidence(ci, cj, 0.35f);
    });
  }
  return band;
}

void integrateScan(const mrpt::obs::CObservation2DRangeScan& scan, LocalOccupancy& grid,
                   float p_free, float p_occ) {
  const mrpt::poses::CPose3D robot3(grid.robot());
  const mrpt::poses::CPose3D sensor = robot3 + scan.sensorPose;
  const size_t n = scan.getScanSize();
  const double a0 = -0.5 * scan.aperture;
  const double da = n > 1 ? scan.aperture / (n - 1) : 0.0;
  for (size_t k = 0; k < n; ++k) {
    if (!scan.getScanRangeValidity(k)) continue;
    const double r = scan.getScanRange(k);
    const double a = scan.rightToLeft ? a0 + k * da : -(a0 + k * da);
    double gx, gy, gz;
    sensor.composePoint(r * std::cos(a), r * std::sin(a), 0.0, gx, gy, gz);
    const int hi = grid.cellX(gx), hj = grid.cellY(gy);
    const double range = std::hypot(gx - grid.robot().x(), gy - grid.robot().y());
    grid.walkRay(gx, gy, range, [&](int ci, int cj, double, int) {
      if (ci == hi && cj == hj) return;
      grid.addEvidence(ci, cj, p_free);
    });
    grid.addEvidence(hi, hj, p_occ);
  }
}

}  // namespace carenav::perception
