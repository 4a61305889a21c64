// lookaheadPoint on the shortest paths: a goal with an empty route gives
// GoalDwa a one-point path. Also built into test_ubsan with the standard
// library's bounds checks on goal_dwa.cpp, where a read past the point fails.
#include <carenav/navigation/local_planner.h>

#include <gtest/gtest.h>

namespace carenav::navigation {
namespace {

TEST(Lookahead, AOnePointPathGivesItsPointWithoutReadingPastIt) {
  std::vector<TPoint2D> path = {{2.0, 1.0}, {1e300, -1e300}};
  path.pop_back();  // the stale point stays in the vector's storage
  for (const double corner : {M_PI, 0.2}) {
    const TPoint2D p = lookaheadPoint(path, 0.0, 0.0, 1.0, corner);
    EXPECT_EQ(p.x, 2.0);
    EXPECT_EQ(p.y, 1.0);
  }
}

TEST(Lookahead, AnEmptyPathGivesTheQueryPoint) {
  const TPoint2D p = lookaheadPoint({}, 0.5, -0.25, 1.0);
  EXPECT_EQ(p.x, 0.5);
  EXPECT_EQ(p.y, -0.25);
}

TEST(Lookahead, ATwoPointPathIsWalkedAlong) {
  const TPoint2D p = lookaheadPoint({{0, 0}, {4, 0}}, 1.0, 0.5, 1.0);
  EXPECT_NEAR(p.x, 2.0, 1e-12);
  EXPECT_NEAR(p.y, 0.0, 1e-12);
}

}  // namespace
}  // namespace carenav::navigation
