// Moving-obstacle tracks: velocity from the centroids over a window, the lane
// a tracked person walks in, and the Navigator using it (lidar and depth).
#include <carenav/navigation/moving_tracker.h>
#include <carenav/navigation/navigator.h>

#include <mrpt/obs/CObservation2DRangeScan.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fixtures.h"

using namespace carenav;
using namespace carenav::navigation;

namespace {

/** The half of a 0.25 m person facing -x at (cx, cy), every 5 cm, with
 *  jitter: what a lidar in front of it sees. */
std::vector<TPoint2D> personFront(double cx, double cy, std::mt19937& rng) {
  std::normal_distribution<double> n(0, 0.02);
  std::vector<TPoint2D> pts;
  for (double a = M_PI / 2; a <= 3 * M_PI / 2 + 1e-9; a += 0.2)
    pts.push_back({cx + 0.25 * std::cos(a) + n(rng), cy + 0.25 * std::sin(a) + n(rng)});
  return pts;
}

}  // namespace

TEST(MovingTracker, ClustersApartPointsSeparately) {
  const std::vector<TPoint2D> pts{{0, 0}, {0.1, 0}, {0.2, 0.05}, {2, 2}, {2.1, 2}, {5, 5}};
  const auto c = clusterPoints(pts, 0.3);
  ASSERT_EQ(c.size(), 3u);
  EXPECT_EQ(c[0].size(), 3u);
  EXPECT_EQ(c[1].size(), 2u);
  EXPECT_EQ(c[2].size(), 1u);
}

TEST(MovingTracker, EstimatesAWalkersVelocityAndSweepsItsLaneAhead) {
  std::mt19937 rng(3);
  MovingTracker tr;
  for (int k = 0; k <= 15; ++k) {
    const double t = 0.1 * k;
    tr.update(personFront(6.0 - 0.5 * t, 1.2, rng), t);
  }
  ASSERT_EQ(tr.tracks().size(), 1u);
  const auto& k = tr.tracks()[0];
  EXPECT_NEAR(k.velocity.x, -0.5, 0.08);
  EXPECT_NEAR(k.velocity.y, 0.0, 0.08);
  EXPECT_EQ(k.sightings, 16);
  const auto lane = tr.predictedPath(2.0, 0.05);
  ASSERT_FALSE(lane.empty());
  double xmin = 1e9, xmax = -1e9;
  for (const auto& p : lane) {
    xmin = std::min(xmin, p.x);
    xmax = std::max(xmax, p.x);
    EXPECT_NEAR(p.y, 1.2, k.radius + 0.06) << "the lane is as wide as the body";
  }
  EXPECT_LT(xmax, k.centroid.x) << "only ahead of the person";
  EXPECT_NEAR(k.centroid.x - xmin, 1.0, 0.2) << "0.5 m/s for 2 s";
  // wider lanes for the route
  const auto wide = tr.predictedPath(2.0, 0.05, 0.5);
  double ymax = -1e9;
  for (const auto& p : wide) ymax = std::max(ymax, p.y);
  EXPECT_GT(ymax, 1.2 + 0.45);
}

TEST(MovingTracker, StandingClusterHasNoLaneAndOldTracksAreDropped) {
  std::mt19937 rng(5);
  MovingTracker tr;
  for (int k = 0; k <= 10; ++k) tr.update(personFront(3.0, 0.0, rng), 0.1 * k);
  ASSERT_EQ(tr.tracks().size(), 1u);
  EXPECT_LT(std::hypot(tr.tracks()[0].velocity.x, tr.tracks()[0].velocity.y), 0.15);
  EXPECT_TRUE(tr.predictedPath(2.0, 0.05).empty()) << "jitter is not walking";
  tr.update({}, 1.3);
  EXPECT_EQ(tr.tracks().size(), 1u) << "hidden for a moment: kept";
  EXPECT_TRUE(tr.hiddenRegions(2.0, 0.05).empty()) << "it never walked: no hidden person";
  tr.update({}, 4.1);
  EXPECT_TRUE(tr.tracks().empty()) << "unseen for longer than keep";
}

TEST(MovingTracker, AClusterWiderThanAPersonIsNotTracked) {
  // A wall's face flickering under grazing rays: moved-in cells every 5 cm
  // along 3 m, sliding along the wall as the robot drives (it "walks").
  MovingTracker tr;
  for (int k = 0; k <= 20; ++k) {
    std::vector<TPoint2D> face;
    for (double x = 0; x <= 3.0; x += 0.05) face.push_back({x + 0.05 * k, 0.1});
    tr.update(face, 0.1 * k);
  }
  EXPECT_TRUE(tr.tracks().empty());
  tr.update({}, 3.0);
  EXPECT_TRUE(tr.hiddenRegions(3.0, 0.05).empty()) << "no hidden region of the wall's size";
  // A person beside it is tracked.
  std::mt19937 rng(2);
  for (int k = 0; k <= 10; ++k) tr.update(personFront(3.0, 1.0 - 0.05 * k, rng), 3.1 + 0.1 * k);
  EXPECT_EQ(tr.tracks().size(), 1u);
}

TEST(MovingTracker, APostsFlickeringEdgeCellStartsNoTrackAPersonDoes) {
  // The edge cells of 30 random posts (0.15 m): one or two moved-in cells a
  // cycle, sliding around the post as the robot passes (their centroid
  // "walks" at up to 1 m/s). None may start a track, sweep a lane or count
  // as a moving obstacle; a person's body beside each post is tracked, and
  // a sighting of one cell of it (partly hidden) continues its track.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-5, 5), ang(-M_PI, M_PI);
  for (int post = 0; post < 30; ++post) {
    const TPoint2D c{u(rng), u(rng)};
    const double a0 = ang(rng);
    MovingTracker tr;
    for (int k = 0; k <= 15; ++k) {
      std::vector<TPoint2D> edge;
      const int cells = 1 + (k + post) % 2;
      for (int i = 0; i < cells; ++i) {
        const double a = a0 + 0.3 * k + 0.4 * i;
        edge.push_back({c.x + 0.075 * std::cos(a), c.y + 0.075 * std::sin(a)});
      }
      tr.update(edge, 0.1 * k);
      EXPECT_TRUE(tr.bodies().empty()) << "post " << post << " cycle " << k;
    }
    EXPECT_TRUE(tr.tracks().empty()) << "post " << post;
    EXPECT_TRUE(tr.predictedPath(2.0, 0.05).empty()) << "post " << post;
    for (int k = 0; k <= 10; ++k) {
      const double t = 2.0 + 0.1 * k;
      auto body = personFront(c.x + 1.0, c.y + 1.0 - 0.5 * (t - 2.0), rng);
      if (k == 8) body.resize(1);  // partly hidden
      tr.update(body, t);
      EXPECT_EQ(tr.bodies().size(), body.size()) << "post " << post << " cycle " << k;
    }
    ASSERT_EQ(tr.tracks().size(), 1u) << "post " << post;
    EXPECT_EQ(tr.tracks()[0].sightings, 11) << "post " << post;
    EXPECT_FALSE(tr.predictedPath(2.0, 0.05).empty()) << "post " << post;
  }
}

TEST(MovingTracker, AClusterThatSlidesAFewCentimetresSweepsNoLaneAPersonSoon) {
  // The moved-in cells of a post's face as the robot passes: a body-sized
  // cluster (4 cells) whose centroid slides 5-15 cm at 0.2-1 m/s, then
  // stays. Its velocity is a person's; its travel is not: no lane, and no
  // hidden person where it was. A person walking at 0.5 m/s gets a lane
  // within 0.5 s of the first sighting.
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-5, 5), ang(-M_PI, M_PI), slide(0.05, 0.15),
      speed(0.2, 1.0);
  for (int post = 0; post < 30; ++post) {
    const TPoint2D c{u(rng), u(rng)};
    const double a = ang(rng), len = slide(rng), v = speed(rng);
    MovingTracker tr;
    for (int k = 0; k <= 15; ++k) {
      const double t = 0.1 * k, d = std::min(len, v * t);
      std::vector<TPoint2D> face;
      for (int i = 0; i < 4; ++i)
        face.push_back({c.x + d * std::cos(a) + 0.06 * i, c.y + d * std::sin(a)});
      tr.update(face, t);
      EXPECT_TRUE(tr.predictedPath(2.0, 0.05).empty()) << "post " << post << " cycle " << k;
    }
    EXPECT_FALSE(tr.tracks().empty()) << "post " << post << ": a body, tracked";
    tr.update({}, 2.5);
    EXPECT_TRUE(tr.hiddenRegions(2.5, 0.05).empty()) << "post " << post;
  }
  MovingTracker tr;
  double lane_at = -1;
  for (int k = 0; k <= 15 && lane_at < 0; ++k) {
    const double t = 0.1 * k;
    tr.update(personFront(6.0 - 0.5 * t, 1.2, rng), t);
    if (!tr.predictedPath(2.0, 0.05).empty()) lane_at = t;
  }
  EXPECT_GE(lane_at, 0.2);
  EXPECT_LE(lane_at, 0.5);
}

TEST(MovingTracker, APersonWhoWalkedOutOfSightMayBeNearWhereSeenLast) {
  std::mt19937 rng(9);
  MovingTracker tr;
  for (int k = 0; k <= 10; ++k) tr.update(personFront(3.0, 1.0 - 0.5 * 0.1 * k, rng), 0.1 * k);
  ASSERT_EQ(tr.tracks().size(), 1u);
  const TPoint2D last = tr.tracks()[0].centroid;
  EXPECT_TRUE(tr.hiddenRegions(1.0, 0.05).empty()) << "still in sight";
  EXPECT_FALSE(tr.predictedPath(2.0, 0.05).empty());
  // Out of sight: no lane any more (its walk is not known), a disc growing
  // with the time unseen around where it was last seen.
  tr.update({}, 2.0);
  EXPECT_TRUE(tr.predictedPath(2.0, 0.05).empty());
  auto extent = [&](double now) {
    double r = 0;
    for (const auto& p : tr.hiddenRegions(now, 0.05))
      r = std::max(r, std::hypot(p.x - last.x, p.y - last.y));
    return r;
  };
  const double r2 = extent(2.0), r3 = extent(3.0);
  EXPECT_GT(r2, 0.2);
  EXPECT_GT(r3, r2 + 0.2) << "0.5 m/s unseen";
  EXPECT_LT(extent(3.5), tr.tracks()[0].radius + 0.5 + 0.06) << "at most hidden_growth";
  // Back in sight near there: the same track, a fresh velocity.
  tr.update(personFront(last.x + 0.4, last.y, rng), 3.0);
  ASSERT_EQ(tr.tracks().size(), 1u);
  EXPECT_EQ(tr.tracks()[0].history.size(), 1u);
  EXPECT_TRUE(tr.hiddenRegions(3.0, 0.05).empty());
}

TEST(MovingTracker, TwoPeopleKeepTheirOwnTracks) {
  std::mt19937 rng(7);
  MovingTracker tr;
  for (int k = 0; k <= 12; ++k) {
    const double t = 0.1 * k;
    auto a = personFront(5.0 - 0.5 * t, 1.0, rng);
    const auto b = personFront(3.0, -1.0 + 0.6 * t, rng);
    a.insert(a.end(), b.begin(), b.end());
    tr.update(a, t);
  }
  ASSERT_EQ(tr.tracks().size(), 2u);
  bool towards = false, crossing = false;
  for (const auto& k : tr.tracks()) {
    if (std::abs(k.velocity.x + 0.5) < 0.1 && std::abs(k.velocity.y) < 0.1) towards = true;
    if (std::abs(k.velocity.x) < 0.1 && std::abs(k.velocity.y - 0.6) < 0.1) crossing = true;
  }
  EXPECT_TRUE(towards);
  EXPECT_TRUE(crossing);
}

namespace {

/** A lidar at the origin looking along +x (721 beams over 180 deg) in a
 *  corridor |y| < 1.5, with a 0.25 m person at (px, py). */
mrpt::obs::CObservation2DRangeScan corridorScan(double px, double py) {
  mrpt::obs::CObservation2DRangeScan s;
  s.aperture = static_cast<float>(M_PI);
  s.rightToLeft = true;
  s.maxRange = 20;
  s.resizeScan(721);
  for (size_t i = 0; i < 721; ++i) {
    const double a = -M_PI / 2 + M_PI * static_cast<double>(i) / 720;
    const double dx = std::cos(a), dy = std::sin(a);
    double r = std::abs(dy) > 1e-6 ? 1.5 / std::abs(dy) : 19.0;
    // ray - circle
    const double b = dx * px + dy * py, c = px * px + py * py - 0.25 * 0.25;
    const double disc = b * b - c;
    if (disc >= 0 && b - std::sqrt(disc) > 0) r = std::min(r, b - std::sqrt(disc));
    s.setScanRange(i, static_cast<float>(std::min(r, 19.0)));
    s.setScanRangeValidity(i, true);
  }
  return s;
}

/** The robot stands at the origin while a person walks from x = 6 towards
 *  it along y = py for 2 s; the remembered obstacles for the route. */
std::pair<std::vector<TPoint2D>, size_t> walkTowards(const NavigationParams& p, double py) {
  Navigator n(p, test::walkerRobot());
  for (int k = 0; k <= 20; ++k) {
    const double t = 0.1 * k;
    n.setOdometry({0, 0, 0}, {0, 0}, t);
    n.addObservation(corridorScan(6.0 - 0.5 * t, py), {0, 0, 0}, t);
    n.cycle(t);
  }
  return {n.obstaclesInMap(), n.predicted().size()};
}

bool anyNear(const std::vector<TPoint2D>& pts, double x, double y, double r) {
  for (const auto& p : pts)
    if (std::hypot(p.x - x, p.y - y) < r) return true;
  return false;
}

}  // namespace

TEST(Navigator, APersonWalkingTowardsTheRobotBlocksItsLaneForTheRoute) {
  NavigationParams p;
  p.plugin = "goal-dwa";
  // At t = 2 the person is at x = 5 (front at 4.75): its lane towards the
  // robot (x = 2.5, 8 s at 0.5 m/s reaches past it) is blocked for the route,
  // the other side of the corridor is not.
  const auto [on, lane] = walkTowards(p, 0.0);
  EXPECT_GT(lane, 0u) << "a walking person is swept ahead on the local map";
  EXPECT_TRUE(anyNear(on, 2.5, 0.0, 0.06));
  EXPECT_TRUE(anyNear(on, 2.5, 0.5, 0.06)) << "the lane is widened like the cost map";
  EXPECT_FALSE(anyNear(on, 2.5, -1.0, 0.2)) << "room to pass beside it";
  // Without tracking only the person's own cells (grown) are there.
  p.predict_horizon = 0;
  const auto [off, none] = walkTowards(p, 0.0);
  EXPECT_EQ(none, 0u);
  EXPECT_FALSE(anyNear(off, 2.5, 0.0, 0.5));
}

TEST(Navigator, DepthFramesTellAPersonFromABox) {
  // The floor in front is seen free for 1 s; then obstacle cells appear on
  // it (a person stepping in) or on cells never seen free (a box's top).
  auto run = [](bool onFloor) {
    NavigationParams p;
    p.plugin = "goal-dwa";
    Navigator n(p, test::walkerRobot());
    std::vector<TPoint2D> floor, hits;
    for (double x = 1.0; x <= 3.0; x += 0.05)
      for (double y = -1.0; y <= 1.0; y += 0.05) {
        const bool body = std::hypot(x - 2.0, y) < 0.25;
        if (!body || onFloor) floor.push_back({x, y});
        if (body) hits.push_back({x, y});
      }
    for (int k = 0; k < 10; ++k) {
      const double t = 0.1 * k;
      n.setOdometry({0, 0, 0}, {0, 0}, t);
      std::vector<TPoint2D> f;
      for (const auto& c : floor)
        if (onFloor || std::hypot(c.x - 2.0, c.y) >= 0.25) f.push_back(c);
      n.addPerceivedFrame(f, onFloor ? std::vector<TPoint2D>{} : hits, t);
      n.setPerceivedObstacles(onFloor ? std::vector<TPoint2D>{} : hits, t);
      n.cycle(t);
    }
    n.setOdometry({0, 0, 0}, {0, 0}, 1.0);
    n.addPerceivedFrame({}, hits, 1.0);
    n.setPerceivedObstacles(hits, 1.0);
    n.cycle(1.0);
    return n.moving().size();
  };
  EXPECT_GE(run(true), 5u) << "obstacle on floor seen a moment before: moving";
  EXPECT_EQ(run(false), 0u) << "a box that was always there";
}
