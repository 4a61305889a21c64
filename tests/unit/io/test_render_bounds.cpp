// Overlays far off the map (odometry of 1e300 m, NaN) are drawn clipped or
// left out: the pixel arithmetic never overflows. Built into test_ubsan too
// (tests/CMakeLists.txt), where a signed overflow aborts the test.
#include <carenav/io/map_io.h>
#include <carenav/io/map_render.h>

#include <gtest/gtest.h>

#include <limits>

namespace carenav::io {
namespace {

TEST(RenderBounds, HugeAndNonFiniteOverlayPointsAreClippedOrSkipped) {
  const auto grid = makeGrid(-1, -1, 0.05, 40, 40, 0.5f);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  RenderOptions o;
  Overlay dots;
  dots.points = {{1e300, -1e300}, {-1e300, 1e300}, {nan, 0}, {0, 0}, {1e9, 2e9}};
  dots.points_only = true;
  Overlay path;
  path.points = {{0, 0}, {1e300, 1e300}, {nan, nan}, {-1e300, 5}, {0.5, 0.5}};
  path.start_end_markers = true;
  path.label = "far";
  Overlay lone;
  lone.points = {{-1e300, -1e300}};
  o.overlays = {dots, path, lone};
  RenderGeometry g;
  const auto img = renderGridMap(grid, o, &g);
  EXPECT_EQ(static_cast<int>(img.getWidth()), g.width);
  EXPECT_GE(g.width, 800);
  EXPECT_EQ(g.px(1e300), 16777216);
  EXPECT_EQ(g.px(-1e300), -16777216);
  EXPECT_EQ(g.py(nan), -16777216);
  EXPECT_NEAR(g.px(0.0), g.width / 2, 1);
}

}  // namespace
}  // namespace carenav::io
