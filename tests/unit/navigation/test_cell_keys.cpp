// Cell keys of the obstacle memory, the free-space history and the local
// cost map: negative cells (a start inside a wall, behind the origin), cells
// farther than 32 bits of index and non-finite points. The same file is
// built into test_ubsan (tests/CMakeLists.txt) with the undefined-behaviour
// sanitizer, where a shift of a negative value, a signed overflow or an
// out-of-range double-to-integer conversion aborts the test.
#include <carenav/navigation/local_map.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace carenav::navigation {
namespace {

constexpr double kRes = 0.05;
const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

bool holdsCellOf(const std::vector<TPoint2D>& pts, double x, double y) {
  for (const auto& p : pts)
    if (std::abs(p.x - x) <= kRes / 2 + 1e-9 && std::abs(p.y - y) <= kRes / 2 + 1e-9) return true;
  return false;
}

TEST(CellKeys, NegativeCellsComeBackWhereTheyWere) {
  ObstacleMemory mem(kRes, 5.0, 1e9);
  const std::vector<TPoint2D> pts{{-0.3, -0.7}, {-1000.01, 2.52}, {3.3, -4.4}, {-0.01, -0.01}};
  mem.addPoints(pts, 1.0);
  ASSERT_EQ(mem.size(), pts.size());
  const auto back = mem.points();
  for (const auto& p : pts) EXPECT_TRUE(holdsCellOf(back, p.x, p.y)) << p.x << "," << p.y;
  // Pruning around a robot at negative coordinates keeps what is near it.
  mem.prune(2.0, {-0.3, -0.7});
  EXPECT_EQ(mem.size(), pts.size());
}

TEST(CellKeys, ARobotStartingInsideAWallClearsAndMarksNegativeCells) {
  // The sensor sits at negative coordinates, inside an obstacle cell.
  ObstacleMemory mem(kRes, 5.0, 10.0);
  FreeSpaceHistory free(kRes, 10.0);
  mem.addPoints({{-2.02, -3.02}, {-1.52, -3.02}}, 1.0);
  WorldScan s;
  s.origin = {-2.02, -3.02};
  s.ends = {{-0.52, -3.02}, {-2.02, -5.02}};
  s.hit = {1, 1};
  mem.add(s, 2.0);
  free.addScan(s, 2.0);
  const auto pts = mem.points();
  EXPECT_TRUE(holdsCellOf(pts, -0.52, -3.02));
  EXPECT_TRUE(holdsCellOf(pts, -2.02, -5.02));
  EXPECT_FALSE(holdsCellOf(pts, -1.52, -3.02)) << "the ray through it clears it";
  EXPECT_TRUE(free.recentlyFree(-1.02, -3.02, 2.0, 1.0, 0.0));
  EXPECT_FALSE(free.recentlyFree(1.02, 3.02, 2.0, 1.0, 0.0)) << "the mirrored cell was never seen";
}

TEST(CellKeys, CellsFourBillionCellsApartStayApart) {
  // 2^32 cells apart: with the index's high bits shifted out, both were one key.
  const double far = kRes * 4294967296.0 + 0.01;
  ObstacleMemory mem(kRes, 5.0, 1e300);
  mem.addPoints({{0.01, 0.01}, {far, 0.01}, {0.01, far}, {-far, -far}}, 1.0);
  EXPECT_EQ(mem.size(), 4u);
  FreeSpaceHistory free(kRes, 1.0);
  free.markFree(0.01, 0.01, 1.0);
  EXPECT_FALSE(free.recentlyFree(far, 0.01, 1.0, 1.0, 0.0));
  EXPECT_FALSE(free.recentlyFree(0.01, far, 1.0, 1.0, 0.0));
}

TEST(CellKeys, HugeAndNonFinitePoints) {
  ObstacleMemory mem(kRes, 5.0, 1e300);
  mem.addPoints({{kNaN, 0}, {0, kInf}, {-kInf, kNaN}}, 1.0);
  EXPECT_EQ(mem.size(), 0u) << "a point that is not a number is no obstacle";
  mem.addPoints({{1e300, -1e300}, {-1e300, 1e300}}, 1.0);
  EXPECT_EQ(mem.size(), 2u) << "huge points land in the border cells";
  WorldScan s;
  s.origin = {kNaN, 0};
  s.ends = {{1, 0}};
  s.hit = {1};
  mem.add(s, 2.0);
  EXPECT_EQ(mem.size(), 2u);
  s.origin = {0, 0};
  s.ends = {{kInf, 0}, {1e300, 1e300}};
  s.hit = {1, 0};
  FreeSpaceHistory free(kRes, 3.0);
  free.addScan(s, 2.0);  // the finite ray is walked only within the radius
  free.markFree(kNaN, kNaN, 2.0);
  EXPECT_FALSE(free.recentlyFree(kNaN, 0, 2.0, 1.0, 0.0));
  EXPECT_TRUE(free.recentlyFree(1.0, 1.0, 2.0, 1.0, 0.0));
}

TEST(CellKeys, CostmapIgnoresObstaclesOffItsGridHoweverFar) {
  NavigationParams p;
  p.local_size = 4;
  p.resolution = kRes;
  const Footprint fp({{0.25, 0.3}, {-0.45, 0.3}, {-0.45, -0.3}, {0.25, -0.3}}, kRes);
  LocalCostmap map(p, fp);
  map.build({-7.0, -9.0}, {{1e300, 0}, {-1e300, -1e300}, {kNaN, 1}, {-7.0, -8.0}});
  EXPECT_EQ(map.obstacleCells(), 1u);
  EXPECT_EQ(map.distance(1e300, 0), -1);
  EXPECT_EQ(map.distance(kNaN, 0), -1);
  EXPECT_NEAR(map.distance(-7.0, -9.0), 1.0, 2 * kRes);
  EXPECT_TRUE(map.check({1e300, -1e300, 0}).outside);
}

}  // namespace
}  // namespace carenav::navigation
