// nearestOnPolyline against a dense sampling of each segment.
#include <carenav/navigation/polyline.h>

#include <mrpt/math/TPoint2D.h>

#include <gtest/gtest.h>

#include <random>

using carenav::navigation::nearestOnPolyline;
using mrpt::math::TPoint2D;

TEST(Polyline, NearestPointAgreesWithSampling) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> c(-5, 5);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<TPoint2D> path(2 + rng() % 5);
    for (auto& p : path) p = {c(rng), c(rng)};
    const double x = c(rng), y = c(rng);
    double best = 1e18;
    for (size_t i = 0; i + 1 < path.size(); ++i)
      for (int k = 0; k <= 2000; ++k) {
        const double u = k / 2000.0;
        best = std::min(best, std::hypot(path[i].x + u * (path[i + 1].x - path[i].x) - x,
                                         path[i].y + u * (path[i + 1].y - path[i].y) - y));
      }
    const auto n = nearestOnPolyline(path, x, y);
    ASSERT_LE(n.distance, best + 1e-9) << trial;
    ASSERT_GE(n.distance, best - 0.01) << trial;  // the sampling step
    const auto& a = path[n.segment];
    const auto& b = path[n.segment + 1];
    EXPECT_NEAR(std::hypot(a.x + n.u * (b.x - a.x) - x, a.y + n.u * (b.y - a.y) - y), n.distance,
                1e-9);
  }
}

TEST(Polyline, OnePointAndEmpty) {
  const std::vector<TPoint2D> one = {{3, 4}};
  EXPECT_DOUBLE_EQ(nearestOnPolyline(one, 0, 0).distance, 5.0);
  EXPECT_TRUE(std::isinf(nearestOnPolyline(std::vector<TPoint2D>{}, 0, 0).distance));
}
