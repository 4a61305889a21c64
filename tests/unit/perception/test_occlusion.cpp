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
    const mrpt::poses::CPose3D cam(0.2, 0, h, 0, pitch, 0);
    const Cloud c = renderDepth(s, cam, 700 + k, 1.0, nullptr, 256, 212);
    Pipeline pipe(PerceptionParams{}, Method::RrtGpd);
    FrameInput in;
    in.cloud = &c;
    in.sensor_origin = {0.2f, 0.f, static_cast<float>(h)};
    pipe.process(in, false);
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
