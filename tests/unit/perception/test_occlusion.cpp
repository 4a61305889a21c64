// Occlusion is not free space: cells a ray only passed over, in the shadow
// behind a drop-off, are never marked free (seeded random stairs and holes).
#include "scene.h"

#include <carenav/perception/pipeline.h>

#include <gtest/gtest.h>

#include <random>

using namespace carenav;
using namespace carenav::perception;
using namespace carenav_test;

namespace {
constexpr double kDeg = M_PI / 180;

/** Free (p < 0.45) and seen (p != 0.5) counts over cells with centres in the box. */
void shares(const LocalOccupancy& g, double x0, double x1, double y0, double y1, size_t& free,
            size_t& cells) {
  free = cells = 0;
  for (int i = 0; i < g.cells(); ++i)
    for (int j = 0; j < g.cells(); ++j) {
      const double x = g.centreX(i), y = g.centreY(j);
      if (x < x0 || x > x1 || y < y0 || y > y1) continue;
      ++cells;
      free += g.prob(i, j) < 0.45 ? 1 : 0;
    }
}
/** One frame of `s` seen by a camera 0.2 m ahead of the axle, `h` high,
 *  pitched `pitch` (rad), W x H pixels, into `pipe` at odometry `odo`. */
FrameResult see(Pipeline& pipe, const Scene& s, double h, double pitch, unsigned seed, int W, int H,
                const mrpt::poses::CPose2D& odo = {}) {
  const Cloud c =
      renderDepth(s, mrpt::poses::CPose3D(0.2, 0, h, 0, pitch, 0), seed, 1.0, nullptr, W, H);
  FrameInput in;
  in.cloud = &c;
  in.sensor_origin = {0.2f, 0.f, static_cast<float>(h)};
  in.odometry = odo;
  return pipe.process(in, false);
}
}  // namespace

TEST(PerceptionOcclusion, ShadowBehindADropIsNeverFree) {
  // A drop of 0.3-0.8 m (stairs down / a wide hole) 1.0-2.0 m ahead; camera
  // 0.5-1.2 m high pitched 15-45 deg. The ray grazing the edge at height H
  // meets the lower floor (depth dz) at x_e + (x_e - x_c) dz / H: the cells
  // in between were never seen and must not be free.
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> U(0, 1);
  size_t shadow_free = 0, shadow_cells = 0, near_free = 0, near_cells = 0;
  for (int k = 0; k < 30; ++k) {
    const double h = 0.5 + 0.7 * U(rng), pitch = (15 + 30 * U(rng)) * kDeg;
    const double xe = 1.0 + U(rng), dz = 0.3 + 0.5 * U(rng);
    Scene s;
    s.floor(-10, xe).box({xe, 10, -10, 10, -2, -dz});
    Pipeline pipe(PerceptionParams{}, Method::RrtGpd);
    see(pipe, s, h, pitch, 700 + k, 256, 212);
    const double x_seen = xe + (xe - 0.2) * dz / h;  // lower floor visible from here
    size_t f = 0, n = 0;
    // The shadow, minus one cell at each end (the edge cell, the first lower cell).
    shares(pipe.grid(), xe + 0.05, x_seen - 0.05, -0.3, 0.3, f, n);
    EXPECT_EQ(f, 0u) << "scene " << k << ": " << f << " of " << n << " shadow cells free (edge "
                     << xe << " drop " << dz << " h " << h << " pitch " << pitch / kDeg << ")";
    shadow_free += f;
    shadow_cells += n;
    // The floor before the edge, in view, stays free.
    const double x_near = 0.2 + h / std::tan(pitch + 30 * kDeg);
    if (xe - 0.3 > x_near + 0.1) {
      shares(pipe.grid(), x_near + 0.1, xe - 0.3, -0.3, 0.3, f, n);
      near_free += f;
      near_cells += n;
    }
  }
  std::printf(
      "[ shadow ] %zu of %zu shadow cells free; %zu of %zu floor cells before the edge "
      "free\n",
      shadow_free, shadow_cells, near_free, near_cells);
  EXPECT_GT(shadow_cells, 100u);
  EXPECT_GT(near_free, near_cells * 9 / 10);
}

namespace {

/** Occupied (p > 0.55) and free (p < 0.45) counts over cells with centres in the box. */
void counts(const LocalOccupancy& g, double x0, double x1, double y0, double y1, size_t& occ,
            size_t& free, size_t& cells) {
  occ = free = cells = 0;
  for (int i = 0; i < g.cells(); ++i)
    for (int j = 0; j < g.cells(); ++j) {
      const double x = g.centreX(i), y = g.centreY(j);
      if (x < x0 || x > x1 || y < y0 || y > y1) continue;
      ++cells;
      occ += g.prob(i, j) > 0.55 ? 1 : 0;
      free += g.prob(i, j) < 0.45 ? 1 : 0;
    }
}

/** A random drop (0.1-0.8 m deep, edge 2.0-3.0 m ahead) seen by a random
 *  mounting (0.5-1.2 m high, pitched 15-45 deg); the robot drives straight
 *  at it in 5 cm steps, one frame each, the grid following its odometry,
 *  until the edge lies inside the camera's blind zone, 0.1 m past the
 *  camera at most. */
struct Approach {
  double xe, dz, h, pitch;
  std::unique_ptr<Pipeline> pipe;
};
Approach approachDrop(std::mt19937& rng, unsigned seed) {
  std::uniform_real_distribution<double> U(0, 1);
  Approach a;
  a.h = 0.5 + 0.7 * U(rng);
  a.pitch = (15 + 30 * U(rng)) * kDeg;
  a.xe = 2.0 + U(rng);
  a.dz = 0.1 + 0.7 * U(rng);
  a.pipe = std::make_unique<Pipeline>(PerceptionParams{}, Method::RrtGpd);
  const double x_near = 0.2 + a.h / std::tan(a.pitch + 30 * kDeg);  // the view's near edge
  for (double r = 0; a.xe - r > std::min(x_near - 0.15, 0.3); r += 0.05) {
    Scene s;  // in the robot frame: the robot at x = r of the world
    s.floor(-10, a.xe - r).box({a.xe - r, 10, -10, 10, -2, -a.dz});
    see(*a.pipe, s, a.h, a.pitch, seed + static_cast<unsigned>(r * 100), 256, 212, {r, 0, 0});
  }
  return a;
}

}  // namespace

TEST(PerceptionOcclusion, ADropEdgeSeenBeforeStaysWhenItEntersTheBlindZone) {
  // The cells nearer than the view's edge (the blind zone under the camera)
  // were not seen in this frame: a ray to the floor beyond passes above
  // them. Given free evidence, they erased the remembered edge as the robot
  // drew near, and the walker drove over a stair edge it had stopped for.
  std::mt19937 rng(57);
  size_t edge_occ = 0, edge_cells = 0, beyond_free = 0;
  for (int k = 0; k < 12; ++k) {
    const Approach a = approachDrop(rng, 900 + 10 * k);
    size_t occ, free, n;
    counts(a.pipe->grid(), a.xe - 0.05, a.xe + 0.1, -0.25, 0.25, occ, free, n);
    EXPECT_GT(occ, n / 2) << "scene " << k << ": the edge at " << a.xe << " (drop " << a.dz
                          << ", h " << a.h << ", pitch " << a.pitch / kDeg << "): " << occ << " of "
                          << n << " cells occupied";
    edge_occ += occ;
    edge_cells += n;
    // Beyond the edge: its shadow and the lower floor, never floor to drive onto.
    counts(a.pipe->grid(), a.xe + 0.05, a.xe + 1.5, -0.3, 0.3, occ, free, n);
    EXPECT_EQ(free, 0u) << "scene " << k << ": " << free << " of " << n
                        << " cells free beyond the edge";
    beyond_free += free;
  }
  std::printf("[ blind zone ] %zu of %zu edge cells occupied, %zu cells free beyond\n", edge_occ,
              edge_cells, beyond_free);
}

TEST(PerceptionOcclusion, TreadsSeenBeyondAStairEdgeAreNeverFree) {
  // Stairs going down seen at a quarter of the Kinect's resolution (the
  // simulator's depth_decimation 4): the treads are seen, few returns per
  // cell, each lower than the floor by more than d_pth, obstacles. A ray to
  // a farther tread passes above the nearer ones; its free evidence made
  // them free (a lower surface is no floor).
  std::mt19937 rng(83);
  std::uniform_real_distribution<double> U(0, 1);
  size_t free_total = 0, cells_total = 0;
  for (int k = 0; k < 20; ++k) {
    const double h = 0.5 + 0.7 * U(rng), pitch = (15 + 30 * U(rng)) * kDeg;
    // The edge 0.3-1.3 m past the view's near edge: the robot's floor in view.
    const double x_near = 0.2 + h / std::tan(pitch + 30 * kDeg);
    const double xe = x_near + 0.3 + U(rng), rise = 0.12 + 0.08 * U(rng),
                 tread = 0.25 + 0.4 * U(rng);
    Scene s;
    s.floor(-10, xe);
    for (int t = 0; t < 8; ++t) s.floor(xe + t * tread, xe + (t + 1) * tread, -rise * (t + 1));
    Pipeline pipe(PerceptionParams{}, Method::RrtGpd);
    see(pipe, s, h, pitch, 300 + k, 128, 106);
    size_t occ, free, n;
    counts(pipe.grid(), xe + 0.05, xe + 2.5, -0.3, 0.3, occ, free, n);
    EXPECT_EQ(free, 0u) << "scene " << k << ": " << free << " of " << n
                        << " cells beyond the edge free (edge " << xe << ", rise " << rise
                        << ", tread " << tread << ", h " << h << ", pitch " << pitch / kDeg << ")";
    free_total += free;
    cells_total += n;
  }
  std::printf("[ treads ] %zu of %zu cells beyond the edges free\n", free_total, cells_total);
}

TEST(PerceptionOcclusion, AStartWithTheDropEdgeInTheBlindZoneIsBlockedAtTheView) {
  // A robot that starts (or has turned) with a drop's edge inside the blind
  // zone sees only the lower floor: RRT-GPD takes it as the ground. With the
  // mounting known right (navigation) it is a lower floor, a drop; and the
  // image columns whose first returns lie below the floor mark where the ray
  // crosses the floor's level: the floor would have been seen there. Before,
  // the lower floor was free ground up to the robot and nothing was occupied
  // before the second step's edge.
  std::mt19937 rng(61);
  std::uniform_real_distribution<double> U(0, 1);
  for (int k = 0; k < 12; ++k) {
    const double h = 0.5 + 0.7 * U(rng), pitch = (15 + 30 * U(rng)) * kDeg;
    const double x_near = 0.2 + h / std::tan(pitch + 30 * kDeg);  // the view's near edge
    const double xe = 0.3 + (x_near - 0.35) * U(rng), dz = 0.15 + 0.6 * U(rng);
    Scene s;
    s.floor(-10, xe).box({xe, 10, -10, 10, -2, -dz});
    PerceptionParams p;
    p.mounting_calibrated = true;
    Pipeline pipe(p, Method::RrtGpd);
    const FrameResult r = see(pipe, s, h, pitch, 500 + k, 256, 212);
    EXPECT_TRUE(r.lower_floor) << "scene " << k << ": " << r.plane_note;
    size_t occ, free, n;
    counts(pipe.grid(), xe + 0.05, xe + 2.0, -0.3, 0.3, occ, free, n);
    EXPECT_EQ(free, 0u) << "scene " << k << ": " << free << " of " << n << " cells beyond free";
    // Occupied at the view's near edge, in every cell column of the corridor.
    const auto& g = pipe.grid();
    for (int j = g.cellY(-0.25); j <= g.cellY(0.25); ++j) {
      bool blocked = false;
      for (int i = g.cellX(xe); i <= g.cellX(x_near + 0.15); ++i) blocked |= g.prob(i, j) > 0.55;
      EXPECT_TRUE(blocked) << "scene " << k << ": column y = " << g.centreY(j) << " open up to "
                           << x_near + 0.15 << " (edge " << xe << ", h " << h << ", pitch "
                           << pitch / kDeg << ")";
    }
  }
}
