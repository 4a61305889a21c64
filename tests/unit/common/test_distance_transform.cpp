// The one distance transform (common/distance_transform.h) against brute force.
#include <carenav/common/distance_transform.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <utility>
#include <vector>

using carenav::squaredDistanceTransform;

TEST(DistanceTransform, MatchesBruteForceOnRandomGrids) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 20; ++trial) {
    const int nx = 5 + static_cast<int>(rng() % 40), ny = 5 + static_cast<int>(rng() % 40);
    std::vector<uint8_t> free(static_cast<size_t>(nx) * ny, 1);
    const int obstacles = static_cast<int>(rng() % 12);  // 0: no obstacle at all
    std::vector<std::pair<int, int>> obs;
    for (int k = 0; k < obstacles; ++k) {
      const int x = static_cast<int>(rng() % nx), y = static_cast<int>(rng() % ny);
      free[static_cast<size_t>(y) * nx + x] = 0;
      obs.emplace_back(x, y);
    }
    const auto d2 = squaredDistanceTransform(free, nx, ny);
    const auto f2 = squaredDistanceTransform<float>(free, nx, ny);
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x) {
        double best = std::numeric_limits<double>::infinity();
        for (const auto& [ox, oy] : obs)
          best = std::min(best, double(x - ox) * (x - ox) + double(y - oy) * (y - oy));
        const double got = d2[static_cast<size_t>(y) * nx + x];
        const float got_f = f2[static_cast<size_t>(y) * nx + x];
        if (std::isinf(best)) {
          EXPECT_TRUE(std::isinf(got));
          EXPECT_TRUE(std::isinf(got_f));
        } else {
          ASSERT_EQ(got, best) << trial << " at " << x << "," << y;
          ASSERT_EQ(got_f, static_cast<float>(best)) << trial << " at " << x << "," << y;
        }
      }
  }
}

TEST(DistanceTransform, LinesAndDegenerateGrids) {
  // One row, one column, a single cell; whole numbers even far away.
  EXPECT_EQ(squaredDistanceTransform({1, 1, 0, 1}, 4, 1), (std::vector<double>{4, 1, 0, 1}));
  EXPECT_EQ(squaredDistanceTransform({0, 1, 1}, 1, 3), (std::vector<double>{0, 1, 4}));
  EXPECT_TRUE(std::isinf(squaredDistanceTransform({1}, 1, 1)[0]));
  std::vector<uint8_t> wide(5000, 1);
  wide[0] = 0;
  EXPECT_EQ(squaredDistanceTransform(wide, 5000, 1).back(), 4999.0 * 4999.0);
}
