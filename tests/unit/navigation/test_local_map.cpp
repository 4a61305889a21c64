// Local cost map: footprint queries, obstacle memory.
#include <carenav/common/errors.h>
#include <carenav/navigation/local_map.h>

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <set>

namespace carenav::navigation {
namespace {

NavigationParams params() {
  NavigationParams p;
  p.local_size = 6;
  p.resolution = 0.05;
  return p;
}

// The walker's outline (ini/isr-aiwalker.ini): 0.25 ahead of the axle, 0.45
// behind, 0.325 to each side.
Footprint walker() {
  return Footprint({{0.25, 0.325}, {-0.45, 0.325}, {-0.45, -0.325}, {0.25, -0.325}}, 0.05);
}

std::vector<TPoint2D> wallAtX(double x, double y0, double y1) {
  std::vector<TPoint2D> w;
  for (double y = y0; y <= y1; y += 0.02) w.push_back({x, y});
  return w;
}

TEST(Footprint, RadiiAndSamples) {
  const Footprint f = walker();
  EXPECT_NEAR(f.inscribed, 0.25, 1e-9);
  EXPECT_NEAR(f.circumscribed, std::hypot(0.45, 0.325), 1e-9);
  EXPECT_GT(f.boundary.size(), 40u);
  EXPECT_GT(f.interior.size(), 100u);
  EXPECT_TRUE(f.contains(0, 0));
  EXPECT_FALSE(f.contains(0.3, 0));
  EXPECT_THROW(Footprint({{0, 0}, {1, 0}}, 0.05), InputError);
  EXPECT_THROW(Footprint({{0, 0}, {1, 0}, {2, 0}}, 0.05), InputError);
}

TEST(LocalCostmap, ClearanceToAWallAheadMatchesTheGeometry) {
  LocalCostmap m(params(), walker());
  m.build({0, 0}, wallAtX(1.0, -1, 1));
  // Front of the footprint at 0.25: 0.75 m to the wall (within a cell).
  const auto c = m.check({0, 0, 0});
  EXPECT_FALSE(c.collision);
  EXPECT_NEAR(c.clearance, 0.75, 0.06);
  // Facing away, the rear (0.45 m behind the axle) is what comes closest.
  EXPECT_NEAR(m.check({0, 0, M_PI}).clearance, 0.55, 0.06);
  // Moved up to the wall: collision.
  EXPECT_TRUE(m.check({0.76, 0, 0}).collision);
  EXPECT_EQ(m.cellCost(1.0, 0.0), 100);
  EXPECT_EQ(m.cellCost(-1.0, 0.0), 0);
  // A cap bounds the answer far from everything.
  EXPECT_NEAR(m.check({-1.5, 0, 0}, 0.3).clearance, 0.3, 1e-9);
}

TEST(LocalCostmap, GroupedFootprintCheckAnswersAsSampleBySample) {
  // check() skips runs of samples far from everything; its answers must be
  // those of testing every sample (the rule written out here).
  const Footprint fp = walker();
  ASSERT_FALSE(fp.boundary_groups.empty());
  ASSERT_FALSE(fp.interior_groups.empty());
  size_t in_groups = 0;
  for (const auto& g : fp.interior_groups) in_groups += g.end - g.begin;
  EXPECT_EQ(in_groups, fp.interior.size());
  const NavigationParams p = params();
  LocalCostmap m(p, fp);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-3.5, 3.5), a(-M_PI, M_PI);
  std::vector<TPoint2D> obstacles;
  for (int i = 0; i < 60; ++i) obstacles.push_back({u(rng), u(rng)});
  m.build({0, 0}, obstacles);
  const double res = m.resolution();
  const double contact = std::max(res * 0.5, p.footprint_padding + res * 0.5);
  int collisions = 0, near = 0;
  for (int k = 0; k < 20000; ++k) {
    const TPose2D pose{u(rng), u(rng), a(rng)};
    const double cap = k % 2 ? 0.3 : 2.0;
    const double c = std::cos(pose.phi), s = std::sin(pose.phi);
    // sample by sample, after the bound by the centre's distance
    bool outside = false, collision = false;
    double clearance = std::numeric_limits<double>::infinity();
    const double dc = m.distance(pose.x, pose.y);
    if (dc < 0) {
      EXPECT_TRUE(m.check(pose, cap).outside);
      continue;
    }
    if (dc - fp.circumscribed - res - contact >= cap) {
      const double r = fp.circumscribed;
      const FootprintCheck got = m.check(pose, cap);
      EXPECT_EQ(got.outside,
                !m.inside(pose.x + r, pose.y + r) || !m.inside(pose.x - r, pose.y - r));
      EXPECT_FALSE(got.collision);
      EXPECT_EQ(got.clearance, cap);
      continue;
    }
    for (const auto& b : fp.boundary) {
      const double wx = pose.x + c * b.x - s * b.y, wy = pose.y + s * b.x + c * b.y;
      if (m.distance(wx, wy) < 0) {
        outside = true;
        break;
      }
      if (m.sampleContact(wx, wy, pose, c, s, clearance)) {
        collision = true;
        break;
      }
    }
    if (!outside && !collision && m.distance(pose.x, pose.y) < fp.circumscribed + res)
      for (const auto& q : fp.interior)
        if (m.interiorContact(pose.x + c * q.x - s * q.y, pose.y + s * q.x + c * q.y, pose, c, s)) {
          collision = true;
          break;
        }
    const FootprintCheck got = m.check(pose, cap);
    if (outside) {
      EXPECT_TRUE(got.outside) << k;
      continue;
    }
    ASSERT_FALSE(got.outside) << k;
    ASSERT_EQ(got.collision, collision) << k;
    if (collision) {
      ++collisions;
      continue;
    }
    if (clearance < cap) ++near;
    ASSERT_NEAR(got.clearance, std::min(clearance, cap), 1e-9) << k;
  }
  EXPECT_GT(collisions, 100);
  EXPECT_GT(near, 1000);
}

namespace {

/** The surface of a 0.15 m post (points every ~1 cm) centred at (x, y). */
std::vector<TPoint2D> post(double x, double y) {
  std::vector<TPoint2D> pts;
  for (int k = 0; k < 48; ++k)
    pts.push_back({x + 0.075 * std::cos(k * M_PI / 24), y + 0.075 * std::sin(k * M_PI / 24)});
  return pts;
}

}  // namespace

TEST(LocalCostmap, ContactIsMeasuredToTheSensedPointsNotToTheirCells) {
  // The walker's side is at y = -0.325; a post whose surface is `gap` metres
  // beside it, at every offset of the 5 cm cells.
  const NavigationParams p = params();  // padding 0.02 m
  LocalCostmap m(p, walker());
  int contact_3cm = 0, contact_1cm = 0, n = 0;
  for (double off = 0; off < 0.05; off += 0.005, ++n) {
    m.build({0, 0}, post(0.0, -0.325 - 0.03 - 0.075 - off));
    contact_3cm += m.check({0, -off, 0}).collision;
    const double clearance = m.check({0, -off, 0}).clearance;
    EXPECT_NEAR(clearance, 0.03, 0.011) << off;
    m.build({0, 0}, post(0.0, -0.325 - 0.01 - 0.075 - off));
    contact_1cm += m.check({0, -off, 0}).collision;
  }
  EXPECT_EQ(contact_3cm, 0) << "3 cm is beyond the 2 cm padding wherever the cells lie";
  EXPECT_EQ(contact_1cm, n) << "1 cm is within it";
}

TEST(LocalCostmap, OutlineClearanceTellsAMoveAwayFromAPostFromOneTowardsIt) {
  const NavigationParams p = params();
  LocalCostmap m(p, walker());
  m.build({0, 0}, post(0.0, -0.325 - 0.01 - 0.075));  // touching: 1 cm from the side
  const double d0 = m.outlineClearance({0, 0, 0});
  EXPECT_NEAR(d0, 0.01, 0.005);
  EXPECT_GT(m.outlineClearance({0, 0.02, 0}), d0) << "sideways, away";
  EXPECT_LT(m.outlineClearance({0, -0.005, 0}), d0) << "sideways, towards";
  // A point inside the footprint: negative.
  m.build({0, 0}, {{0.0, 0.0}});
  EXPECT_LT(m.outlineClearance({0, 0, 0}), 0);
}

TEST(LocalCostmap, AnObstacleInsideTheFootprintIsACollision) {
  LocalCostmap m(params(), walker());
  // A single post under the middle of the walker, far from its outline.
  m.build({0, 0}, {{-0.1, 0.0}});
  const auto c = m.check({0, 0, 0});
  EXPECT_TRUE(c.collision);
  EXPECT_EQ(c.clearance, 0);
  EXPECT_FALSE(m.check({1.0, 0, 0}).collision);
}

TEST(LocalCostmap, LeavingTheGridIsReported) {
  LocalCostmap m(params(), walker());
  m.build({0, 0}, {});
  EXPECT_TRUE(m.check({2.9, 0, 0}).outside);
  EXPECT_TRUE(m.check({10, 0, 0}).outside);
  EXPECT_FALSE(m.check({1, 0, 0}).outside);
  EXPECT_LT(m.distance(10, 0), 0);
}

TEST(LocalCostmap, StaticMapCellsAreObstacles) {
  mrpt::maps::COccupancyGridMap2D grid(-5, 5, -5, 5, 0.05);
  grid.fill(0.9f);                                                   // free everywhere
  for (double y = -5; y < 5; y += 0.05) grid.setPos(1.5, y, 0.05f);  // a wall at x = 1.5
  LocalCostmap m(params(), walker());
  m.build({0, 0}, {}, &grid);
  EXPECT_GT(m.obstacleCells(), 50u);
  EXPECT_NEAR(m.check({0, 0, 0}).clearance, 1.25, 0.08);
}

TEST(ObstacleMemory, RemembersForTheirPersistenceThenForgets) {
  ObstacleMemory mem(0.05, 5.0, 3.0);
  mem.addPoints({{1, 0}, {1, 0.05}}, 10.0);
  EXPECT_EQ(mem.size(), 2u);
  mem.prune(14.9, {0, 0});
  EXPECT_EQ(mem.size(), 2u);  // still within 5 s
  mem.prune(15.1, {0, 0});
  EXPECT_EQ(mem.size(), 0u);
  // Farther than the radius: dropped at once.
  mem.addPoints({{4, 0}}, 20.0);
  mem.prune(20.0, {0, 0});
  EXPECT_EQ(mem.size(), 0u);
}

TEST(ObstacleMemory, ARayThroughARememberedCellClearsIt) {
  ObstacleMemory mem(0.05, 5.0, 5.0);
  mem.addPoints({{1.0, 0.0}}, 1.0);  // a person stood there
  WorldScan s;
  s.origin = {0, 0};
  s.ends = {{2.0, 0.0}, {0.0, 1.0}};
  s.hit = {1, 1};
  mem.add(s, 2.0);  // now the ray goes through to 2 m
  const auto pts = mem.points();
  ASSERT_EQ(pts.size(), 2u);  // the two new hits, not the old cell
  for (const auto& p : pts) EXPECT_GT(std::hypot(p.x - 1.0, p.y), 0.5);
  // A cell in the sensor's blind zone is kept (nothing is seen there).
  mem.addPoints({{0.2, 0.0}}, 2.0);
  s.range_min = 0.5;
  mem.add(s, 3.0);
  bool kept = false;
  for (const auto& p : mem.points()) kept |= std::hypot(p.x - 0.2, p.y) < 0.05;
  EXPECT_TRUE(kept);
}

TEST(ObstacleMemory, APostsFaceInOneCellKeepsTheCornerTheRobotPasses) {
  // A lidar at the origin sees the face y = 0.36 of a post, x 0.505..0.545,
  // hits every 5 mm and all in one 5 cm cell; the last hit lies 4 cm from
  // the corner at x 0.505. The walker's side is to pass 1 cm under that
  // corner: with the padding of 2 cm that is contact.
  ObstacleMemory mem(0.05, 5.0, 3.0);
  WorldScan s;
  s.origin = {0, 0};
  for (double x = 0.505; x < 0.548; x += 0.005) {
    s.ends.push_back({x, 0.36});
    s.hit.push_back(1);
  }
  mem.add(s, 1.0);
  ASSERT_EQ(mem.size(), 1u);
  LocalCostmap m(params(), walker());
  m.build({0, 0}, mem.points());
  // The walker's left side 1 cm under the face, its front 1 cm past the
  // post's corner.
  const TPose2D pose{0.505 - 0.25 + 0.01, 0.025, 0};
  EXPECT_TRUE(m.check(pose).collision) << "the corner hit, not just the last one";
  EXPECT_NEAR(m.outlineClearance(pose), 0.01, 0.002);
  // Past the face's other end, 2.4 cm from it: no larger than the hits
  // (the cell's square would be 1.7 cm away).
  EXPECT_FALSE(m.check({0.545 + 0.45 + 0.022, 0.025, 0}).collision);
}

TEST(ObstacleMemory, ANoisyFaceIsAveragedAcrossNotGrownToTheNoisesExtremes) {
  // A wall face x = 1.025 (mid-cell) seen head-on, range noise 7 mm (a
  // 0.25 deg lidar puts about 11 hits in a 5 cm cell at 1 m). The walker's
  // front stands 3.2 cm short of the true face: beyond the 2 cm padding.
  // The boxes of the hits reach about 2.5 standard deviations (1.8 cm)
  // towards it; the segments fitted along the bearings end within about
  // 7 mm of the face (4 mm standard error at a segment's end). (Noise much larger than the cell
  // spreads a face's hits over two cells, and the nearer cell then holds the near half of the noise
  // whatever a cell keeps.)
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0, 0.007);
  int contacts = 0;
  const int trials = 20;
  for (int trial = 0; trial < trials; ++trial) {
    ObstacleMemory mem(0.05, 5.0, 3.0);
    WorldScan s;
    s.origin = {0, 0};
    for (double a = -0.2; a <= 0.2; a += 0.25 * M_PI / 180) {
      const double r = 1.025 / std::cos(a) + noise(rng);
      s.ends.push_back({r * std::cos(a), r * std::sin(a)});
      s.hit.push_back(1);
    }
    mem.add(s, 1.0);
    LocalCostmap m(params(), walker());
    m.build({0.7, 0}, mem.points());
    contacts += m.check({1.025 - 0.25 - 0.032, 0, 0}).collision;
  }
  EXPECT_LE(contacts, 2) << "of " << trials;
}

TEST(ObstacleMemory, WhatNoSensorCanSeeIsNotForgottenByTime) {
  // A post passed 10 s ago lies behind the robot, outside its lidar's
  // 270 deg; another lies ahead, hidden behind a box the lidar now hits.
  ObstacleMemory mem(0.05, 5.0, 3.0);
  mem.addPoints({{-0.5, 0.0}, {1.6, 0.0}}, 0.0);
  WorldScan s;
  s.origin = {0, 0};
  for (double a = -0.75 * M_PI; a <= 0.75 * M_PI; a += M_PI / 360) {
    const double r = std::abs(a) < 0.05 ? 1.0 : 2.5;  // the box straight ahead
    s.ends.push_back({r * std::cos(a), r * std::sin(a)});
    s.hit.push_back(1);
  }
  mem.add(s, 10.0);
  mem.prune(10.1, {0, 0});
  bool behind = false, hidden = false;
  for (const auto& p : mem.points()) {
    behind |= std::hypot(p.x + 0.5, p.y) < 0.05;
    hidden |= std::hypot(p.x - 1.6, p.y) < 0.05;
  }
  EXPECT_TRUE(behind) << "out of every sensor's view: kept";
  EXPECT_FALSE(hidden) << "where the lidar looks, 5 s as before";
  // A cycle without a new scan keeps the last view; a scan that looks
  // back lets time count there again.
  mem.prune(10.2, {0, 0});
  behind = false;
  for (const auto& p : mem.points()) behind |= std::hypot(p.x + 0.5, p.y) < 0.05;
  EXPECT_TRUE(behind);
  WorldScan back;  // something right behind the robot now hides the post
  back.origin = {0, 0};
  for (double a = M_PI - 0.2; a <= M_PI + 0.2; a += M_PI / 360) {
    back.ends.push_back({0.3 * std::cos(a), 0.3 * std::sin(a)});
    back.hit.push_back(1);
  }
  mem.add(back, 10.3);
  mem.prune(10.4, {0, 0});
  behind = false;
  for (const auto& p : mem.points()) behind |= std::hypot(p.x + 0.5, p.y) < 0.05;
  EXPECT_FALSE(behind);
}

/** The obstacle memory as first written: every ray walked to its end in
 *  half-cell steps, every hit kept until the next prune. */
std::set<std::pair<int, int>> referenceMemory(
    const std::vector<std::pair<WorldScan, double>>& scans, const TPoint2D& robot, double res,
    double radius) {
  std::map<std::pair<int, int>, double> cells;
  auto cell = [&](double x, double y) {
    return std::make_pair(static_cast<int>(std::floor(x / res)),
                          static_cast<int>(std::floor(y / res)));
  };
  for (const auto& [s, t] : scans) {
    for (size_t i = 0; i < s.ends.size(); ++i) {
      const double dx = s.ends[i].x - s.origin.x, dy = s.ends[i].y - s.origin.y;
      const double len = std::hypot(dx, dy);
      const double stop = s.hit[i] ? len - res : len;
      for (double d = 0; d < stop; d += res * 0.5) {
        auto it = cells.find(cell(s.origin.x + dx * d / len, s.origin.y + dy * d / len));
        if (it != cells.end() && it->second < t) cells.erase(it);
      }
    }
    for (size_t i = 0; i < s.ends.size(); ++i)
      if (s.hit[i]) cells[cell(s.ends[i].x, s.ends[i].y)] = t;
  }
  std::set<std::pair<int, int>> out;
  for (const auto& [c, t] : cells) {
    (void)t;
    if (std::hypot((c.first + 0.5) * res - robot.x, (c.second + 0.5) * res - robot.y) <= radius)
      out.insert(c);
  }
  return out;
}

TEST(ObstacleMemory, BoundedRaysAndOnceACellGiveTheSameMemoryAsWalkingEveryRay) {
  // Several scans between two prunes (a 40 Hz lidar, a 10 Hz control loop)
  // in rooms whose walls lie far beyond the memory's radius: the memory
  // walks each ray only as far as a remembered cell can be, and each cell
  // once per scan, and keeps no hit beyond the radius; after the prune it
  // holds what walking every ray to its end would have left.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  const double res = 0.05, radius = 3.0;
  for (int trial = 0; trial < 30; ++trial) {
    ObstacleMemory mem(res, 100.0, radius);
    const TPoint2D robot{u(rng) * 4 - 2, u(rng) * 4 - 2};
    std::vector<std::pair<WorldScan, double>> scans;
    for (int k = 0; k < 4; ++k) {
      WorldScan s;
      s.origin = {robot.x + 0.2, robot.y};
      s.robot = robot;
      const int beams = 200 + static_cast<int>(rng() % 400);
      for (int b = 0; b < beams; ++b) {
        const double a = -2.3 + 4.6 * b / beams;
        // a far wall, or a near person or box (some rays see nothing)
        const double r = u(rng) < 0.3 ? 0.5 + 3 * u(rng) : 6 + 14 * u(rng);
        s.ends.push_back({s.origin.x + r * std::cos(a), s.origin.y + r * std::sin(a)});
        s.hit.push_back(u(rng) < 0.9 ? 1 : 0);
      }
      scans.emplace_back(s, 1.0 + 0.025 * k);
      mem.add(s, 1.0 + 0.025 * k);
    }
    mem.prune(1.1, robot);
    std::set<std::pair<int, int>> got;
    for (const auto& p : mem.points())
      got.insert(
          {static_cast<int>(std::floor(p.x / res)), static_cast<int>(std::floor(p.y / res))});
    EXPECT_EQ(got, referenceMemory(scans, robot, res, radius)) << "trial " << trial;
  }
}

TEST(ObstacleMemory, HitsBeyondTheRadiusOfTheRobotAreNotKept) {
  ObstacleMemory mem(0.05, 5.0, 3.0);
  WorldScan s;
  s.origin = {0.3, 0};
  s.robot = TPoint2D{0, 0};
  s.ends = {{3.2, 0.0}, {2.9, 0.0}, {0.3, -3.1}};
  s.hit = {1, 1, 1};
  mem.add(s, 1.0);
  EXPECT_EQ(mem.size(), 1u)
      << "(2.9, 0) only: (3.2, 0) and (0.3, -3.1) are beyond 3 m of the robot";
}

}  // namespace
}  // namespace carenav::navigation
