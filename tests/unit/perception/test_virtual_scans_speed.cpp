// The fast FSPF+ and KOS (issue 17, docs/BENCHMARKS.md 'Virtual scans: speed') against the
// plain implementations they replaced (virtual_scans_baseline.h): the same planes, pixels, points
// and scan ranges, bit for bit, on frames of several scenes, poses and sizes, with invalid
// (NaN, zero) pixels, and on point sets built to hit the bin edges and band limits.
#include "scene.h"
#include "virtual_scans_baseline.h"

#include <carenav/perception/virtual_scans.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

using namespace carenav::perception;
using namespace carenav_test;

namespace {

Scene stairScene() {  // bench_perception's frame: a stair down, a gutter and a wall
  Scene s;
  s.floor(-10, 1.5).floor(1.6, 2.2).floor(1.5, 1.6, -0.1).floor(2.2, 10, -0.17);
  s.box({3.5, 3.7, -10, 10, -0.2, 2.5});
  return s;
}

Scene roomScene() {  // walls left, right and ahead, a box, a table top
  Scene s;
  s.floor(-10, 10)
      .box({2.5, 2.7, -10, 10, 0, 2.5})
      .box({-10, 10, 1.2, 1.4, 0, 2.5})
      .box({-10, 10, -1.6, -1.4, 0, 2.5})
      .box({1.2, 1.4, -0.1, 0.1, 0, 0.4})
      .box({1.6, 2.2, -1.0, -0.2, 0.7, 0.74});
  return s;
}

/** Some pixels NaN, some exactly zero (invalid in both ways). */
Cloud withHoles(Cloud c, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (auto& q : c.points) {
    const double r = u(rng);
    if (r < 0.05)
      q = {nan, nan, nan};
    else if (r < 0.08)
      q = {0.f, 0.f, 0.f};
  }
  return c;
}

struct Frame {
  Cloud cloud;
  Point3f origin;
};

std::vector<Frame> makeFrames() {
  const mrpt::poses::CPose3D low(0.1, 0, 0.6, 0.1, 20 * M_PI / 180, 3 * M_PI / 180);
  std::vector<Frame> f;
  f.push_back({renderDepth(stairScene(), walkerKinect()), {0.2f, 0.f, 0.9f}});
  f.push_back({renderDepth(roomScene(), walkerKinect(), 11), {0.2f, 0.f, 0.9f}});
  f.push_back({withHoles(renderDepth(roomScene(), low, 3), 5), {0.1f, 0.f, 0.6f}});
  f.push_back({renderDepth(stairScene(), low, 9, 2.0, nullptr, 320, 240), {0.1f, 0.f, 0.6f}});
  f.push_back({withHoles(renderDepth(roomScene(), walkerKinect(), 4, 1.0, nullptr, 128, 106), 8),
               {0.2f, 0.f, 0.9f}});
  f.push_back(
      {renderDepth(roomScene(), walkerKinect(), 2, 1.0, nullptr, 640, 480), {0.2f, 0.f, 0.9f}});
  return f;
}

/** Rendered once (several tests use them). */
const std::vector<Frame>& frames() {
  static const std::vector<Frame> f = makeFrames();
  return f;
}

void expectSameCloud(const Cloud& a, const Cloud& b) {
  ASSERT_EQ(a.points.size(), b.points.size());
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  for (size_t k = 0; k < a.points.size(); ++k) {
    ASSERT_EQ(a.points[k].x, b.points[k].x) << k;
    ASSERT_EQ(a.points[k].y, b.points[k].y) << k;
    ASSERT_EQ(a.points[k].z, b.points[k].z) << k;
  }
}

void expectSameFspf(const FspfResult& a, const FspfResult& b) {
  EXPECT_EQ(a.iterations, b.iterations);
  EXPECT_EQ(a.planes, b.planes);
  EXPECT_EQ(a.planes_dropped, b.planes_dropped);
  EXPECT_EQ(a.eligible, b.eligible);
  EXPECT_TRUE(a.pixel_class == b.pixel_class);
  expectSameCloud(a.filtered, b.filtered);
}

void expectSameScan(const mrpt::obs::CObservation2DRangeScan& a,
                    const mrpt::obs::CObservation2DRangeScan& b) {
  ASSERT_EQ(a.getScanSize(), b.getScanSize());
  EXPECT_EQ(a.sensorLabel, b.sensorLabel);
  EXPECT_EQ(a.aperture, b.aperture);
  for (size_t k = 0; k < a.getScanSize(); ++k) {
    ASSERT_EQ(a.getScanRangeValidity(k), b.getScanRangeValidity(k)) << "bin " << k;
    ASSERT_EQ(a.getScanRange(k), b.getScanRange(k)) << "bin " << k;
  }
}

}  // namespace

TEST(VirtualScansSpeed, FspfGivesTheBaselinesPlanesOnEveryFrame) {
  PerceptionParams p;
  for (const auto& f : frames()) {  // frames of other sizes one after the other: buffers reused
    SCOPED_TRACE(std::to_string(f.cloud.width) + " x " + std::to_string(f.cloud.height));
    const auto fast = fspfPlus(f.cloud, f.origin, p);
    const auto ref = fspfPlusBaseline(f.cloud, f.origin, p);
    EXPECT_GT(ref.planes + ref.planes_dropped, 0);
    expectSameFspf(fast, ref);
  }
}

TEST(VirtualScansSpeed, FspfMatchesWithOtherSeedsAndTheOfflineStop) {
  const auto& f = frames();
  PerceptionParams p;
  p.fspf_stop_fraction = 0.01;  // the offline setting: many more iterations
  p.seed = 42;
  expectSameFspf(fspfPlus(f[1].cloud, f[1].origin, p),
                 fspfPlusBaseline(f[1].cloud, f[1].origin, p));
  p.seed = 3;
  p.fspf_omega = 10;
  p.fspf_window = 0.2;
  p.fspf_epsilon = 0.005;
  expectSameFspf(fspfPlus(f[2].cloud, f[2].origin, p),
                 fspfPlusBaseline(f[2].cloud, f[2].origin, p));
}

TEST(VirtualScansSpeed, FspfDepthLimitsExactlyOnPixelDistances) {
  // depth_min and depth_max equal to two pixels' distances (float sqrt, as the plain dist()):
  // those pixels stay eligible, their neighbours just beyond the limits do not.
  const Frame& f = frames()[1];
  const auto distance = [&](size_t k) {
    const Point3f& q = f.cloud.points[k];
    const Point3f& o = f.origin;
    return static_cast<double>(std::sqrt((q.x - o.x) * (q.x - o.x) + (q.y - o.y) * (q.y - o.y) +
                                         (q.z - o.z) * (q.z - o.z)));
  };
  PerceptionParams p;
  const size_t W = f.cloud.width;
  for (size_t near : {300 * W + 100, 350 * W + 256})
    for (size_t far : {60 * W + 256, 100 * W + 400}) {
      p.depth_min = distance(near);
      p.depth_max = distance(far);
      ASSERT_LT(p.depth_min, p.depth_max);
      const auto ref = fspfPlusBaseline(f.cloud, f.origin, p);
      EXPECT_LT(ref.eligible, f.cloud.points.size() * 9 / 10);
      expectSameFspf(fspfPlus(f.cloud, f.origin, p), ref);
      p.depth_min = std::nextafter(p.depth_min, 10.0);  // just above: that pixel drops out
      p.depth_max = std::nextafter(p.depth_max, 0.0);
      const auto ref2 = fspfPlusBaseline(f.cloud, f.origin, p);
      EXPECT_LT(ref2.eligible, ref.eligible);
      expectSameFspf(fspfPlus(f.cloud, f.origin, p), ref2);
    }
}

TEST(VirtualScansSpeed, FspfOfAnUnorganisedOrEmptyFrameIsEmpty) {
  PerceptionParams p;
  Cloud c = frames()[4].cloud;
  c.height = 1;
  c.width = c.points.size();
  EXPECT_EQ(fspfPlus(c, {}, p).eligible, 0u);
  Cloud nan = frames()[4].cloud;
  for (auto& q : nan.points) q = {std::nanf(""), 0.f, 0.f};
  expectSameFspf(fspfPlus(nan, {}, p), fspfPlusBaseline(nan, {}, p));
}

TEST(VirtualScansSpeed, KosGivesTheBaselinesRangesOnFspfAndFullFrames) {
  PerceptionParams p;
  for (const auto& f : frames()) {
    SCOPED_TRACE(std::to_string(f.cloud.width) + " x " + std::to_string(f.cloud.height));
    const auto filtered = fspfPlus(f.cloud, f.origin, p).filtered;
    expectSameScan(kinectObstacleScan(filtered, p), kinectObstacleScanBaseline(filtered, p));
    expectSameScan(kinectObstacleScan(f.cloud, p), kinectObstacleScanBaseline(f.cloud, p));
  }
}

namespace {
Cloud unorganised(std::vector<Point3f> pts) {
  Cloud c;
  c.points = std::move(pts);
  c.width = c.points.size();
  return c;
}

/** Sparse clouds in which each point is alone in the bins it could fall in, so that a point
 *  put in the wrong bin (or kept or dropped wrongly) changes the scan: one point on every third
 *  bin edge, exactly (to float) or shifted by `shift` ulp of x and y, range varying with k. */
Cloud edgePoints(size_t n, size_t phase, int shift, float z) {
  std::vector<Point3f> pts;
  const double bin = 2 * M_PI / static_cast<double>(n);
  for (size_t k = phase; k < n; k += 3) {
    const double a = -M_PI + static_cast<double>(k) * bin,
                 r = 0.6 + 0.01 * static_cast<double>(k % 300);
    float x = static_cast<float>(r * std::cos(a)), y = static_cast<float>(r * std::sin(a));
    for (int s = 0; s < std::abs(shift); ++s) {
      x = std::nextafter(x, shift > 0 ? 10.f : -10.f);
      y = std::nextafter(y, shift > 0 ? -10.f : 10.f);
    }
    pts.push_back({x, y, z});
  }
  return unorganised(pts);
}

/** Heights on, just inside and just outside each band limit, each point alone in its bin. */
Cloud bandLimitPoints(const PerceptionParams& p, size_t n) {
  std::vector<float> zs;
  for (double h : p.kosHeights())
    for (double e : {h - p.kos_band, h + p.kos_band}) {
      const float inf = std::numeric_limits<float>::infinity();
      float f = static_cast<float>(e);
      for (int k = 0; k < 3; ++k) f = std::nextafter(f, -inf);
      for (int k = 0; k < 7; ++k, f = std::nextafter(f, inf)) zs.push_back(f);
    }
  for (float f : {0.f, -0.f, -1e-30f, -1e-17f, -2e-17f, 1e-45f, -1e-45f, 1e6f, -1e6f,
                  std::nextafter(1e6f, 0.f), std::nextafter(-1e6f, 0.f)})
    zs.push_back(f);
  std::vector<Point3f> pts;
  const double bin = 2 * M_PI / static_cast<double>(n);
  for (size_t i = 0; i < zs.size(); ++i) {
    const double a = -M_PI + (3.0 * static_cast<double>(i % (n / 3)) + 1.5) * bin;
    pts.push_back(
        {static_cast<float>(2 * std::cos(a)), static_cast<float>(2 * std::sin(a)), zs[i]});
  }
  return unorganised(pts);
}
}  // namespace

TEST(VirtualScansSpeed, KosBinsEveryEdgeAsAtan2fDoes) {
  for (double res : {0.5, 1.0, 0.25, 0.7, 3.0, 1.6, 0.05}) {  // 720 ... 7200 bins, odd 225
    PerceptionParams p;
    p.scan_resolution = res;
    const size_t n = static_cast<size_t>(std::lround(360.0 / res));
    for (size_t phase = 0; phase < 3; ++phase)
      for (int shift : {0, 1, -1, 3, -3}) {
        SCOPED_TRACE(std::to_string(n) + " bins, phase " + std::to_string(phase) + ", shift " +
                     std::to_string(shift));
        const Cloud c = edgePoints(n, phase, shift, 0.1f);
        expectSameScan(kinectObstacleScan(c, p), kinectObstacleScanBaseline(c, p));
      }
  }
}

TEST(VirtualScansSpeed, KosBinsTheAxesAndRandomPointsAsBefore) {
  PerceptionParams p;
  std::vector<Point3f> axes;
  for (float v : {1.f, -1.f, 2.5f, -3.f})
    for (float zero : {0.f, -0.f}) axes.insert(axes.end(), {{v, zero, 0.3f}, {zero, v, 0.6f}});
  for (double res : {0.5, 1.6, 0.7}) {
    p.scan_resolution = res;
    for (size_t i = 0; i < axes.size(); ++i) {  // one at a time: each alone in its bin
      const Cloud c = unorganised({axes[i]});
      expectSameScan(kinectObstacleScan(c, p), kinectObstacleScanBaseline(c, p));
    }
  }
  p.scan_resolution = 0.5;
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> u(-4, 4), zu(-0.5f, 1.5f);
  std::vector<Point3f> pts;
  for (int i = 0; i < 50000; ++i) pts.push_back({u(rng), u(rng), zu(rng)});
  const float nan = std::numeric_limits<float>::quiet_NaN(),
              inf = std::numeric_limits<float>::infinity();
  pts.insert(pts.end(), {{nan, 1.f, 0.1f},
                         {1.f, 1.f, nan},
                         {0.f, 0.f, 0.f},
                         {inf, 0.f, 0.1f},
                         {1.f, -inf, 0.1f},
                         {2e6f, 1.f, 0.1f},
                         {1.f, 1.f, 2e6f}});
  const Cloud c = unorganised(pts);
  expectSameScan(kinectObstacleScan(c, p), kinectObstacleScanBaseline(c, p));
}

TEST(VirtualScansSpeed, KosKeepsExactlyThePointsOfTheBands) {
  for (const char* heights : {"0.1 0.3 0.6 0.9", "0.25 0.05", "0.0 1.7", "1e6 -999999.95"}) {
    PerceptionParams p;
    p.kos_heights = heights;  // overlapping slabs, in any order; centred on 0; at |z| = 1e6
    for (double band : {0.1, 0.13, 0.001}) {
      SCOPED_TRACE(std::string(heights) + " +- " + std::to_string(band));
      p.kos_band = band;
      const Cloud c = bandLimitPoints(p, 720);
      ASSERT_LT(c.points.size(), 240u);  // each point alone in its bin
      expectSameScan(kinectObstacleScan(c, p), kinectObstacleScanBaseline(c, p));
    }
  }
}

TEST(VirtualScansSpeed, KosPointAboveTheRobotBlocksItsBinInItsLevelAsBefore) {
  // x = y = 0 in a band: range 0 in that level's bin (atan2 of signed zeros: 0, pi, -0, -pi),
  // which the per-level rule leaves invalid unless another level sees something there. With 225
  // bins (odd) the bin of bearing 0 has no edge at 0.
  for (double res : {0.5, 1.6}) {
    PerceptionParams p;
    p.scan_resolution = res;
    for (float sx : {0.f, -0.f})
      for (float sy : {0.f, -0.f})
        for (float z : {0.1f, 0.6f, 0.f}) {
          const Cloud c = unorganised({{sx, sy, z},
                                       {1.f, 0.f, 0.6f},
                                       {-1.f, sy, 0.1f},
                                       {-2.f, sy, 0.3f},
                                       {1.f, 1e-7f, 0.9f},
                                       {2.f, -1e-7f, 0.6f}});
          expectSameScan(kinectObstacleScan(c, p), kinectObstacleScanBaseline(c, p));
        }
  }
}

TEST(VirtualScansSpeed, KosOfEmptyAndAllInvalidCloudsHasNoValidBin) {
  PerceptionParams p;
  Cloud empty;
  expectSameScan(kinectObstacleScan(empty, p), kinectObstacleScanBaseline(empty, p));
  Cloud nan;
  nan.points.assign(100, {std::nanf(""), std::nanf(""), std::nanf("")});
  nan.width = 100;
  const auto s = kinectObstacleScan(nan, p);
  expectSameScan(s, kinectObstacleScanBaseline(nan, p));
  for (size_t k = 0; k < s.getScanSize(); ++k) EXPECT_FALSE(s.getScanRangeValidity(k));
}
