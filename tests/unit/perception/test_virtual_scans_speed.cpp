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

std::vector<Frame> frames() {
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
  const auto f = frames();
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
/** Points on and next to every bin edge (and the axes), at heights on and next to the band
 *  limits, plus random points, NaN and zero points. */
Cloud edgeCloud(size_t n, const std::vector<float>& heights, unsigned seed) {
  Cloud c;
  const double bin = 2 * M_PI / static_cast<double>(n);
  for (size_t k = 0; k <= n; ++k) {
    const double a = -M_PI + static_cast<double>(k) * bin;
    const double r = 0.5 + 3.0 * static_cast<double>(k % 7) / 7.0;
    const float x = static_cast<float>(r * std::cos(a)), y = static_cast<float>(r * std::sin(a));
    for (float z : heights)
      for (float dx : {-1.f, 0.f, 1.f}) {
        c.points.push_back({x, y, z});
        c.points.push_back({std::nextafter(x, dx * 10), std::nextafter(y, -dx * 10), z});
      }
  }
  for (float z : heights)
    for (float v : {1.f, -1.f, 0.f, -0.f, 2.5f})
      for (float w : {0.f, -0.f}) {
        c.points.push_back({v, w, z});  // on the x axis, signed zeros
        c.points.push_back({w, v, z});  // on the y axis
      }
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-4, 4), zu(-0.5f, 1.5f);
  for (int i = 0; i < 20000; ++i) c.points.push_back({u(rng), u(rng), zu(rng)});
  const float nan = std::numeric_limits<float>::quiet_NaN();
  c.points.push_back({nan, 1.f, 0.1f});
  c.points.push_back({1.f, 1.f, nan});
  c.points.push_back({0.f, 0.f, 0.f});
  c.points.push_back({std::numeric_limits<float>::infinity(), 0.f, 0.1f});
  c.width = c.points.size();
  return c;
}

std::vector<float> bandEdges(const PerceptionParams& p) {
  std::vector<float> z;
  for (double h : p.kosHeights())
    for (double e : {h - p.kos_band, h + p.kos_band, h}) {
      const float f = static_cast<float>(e);
      z.insert(z.end(), {f, std::nextafter(f, -10.f), std::nextafter(f, 10.f)});
    }
  return z;
}
}  // namespace

TEST(VirtualScansSpeed, KosMatchesOnBinEdgesBandLimitsAndOtherResolutions) {
  for (double res : {0.5, 1.0, 0.25, 0.7, 3.0}) {  // 720, 360, 1440 bins; 514 and 120
    SCOPED_TRACE(res);
    PerceptionParams p;
    p.scan_resolution = res;
    const size_t n = static_cast<size_t>(std::lround(360.0 / res));
    const Cloud c = edgeCloud(n, bandEdges(p), 17);
    expectSameScan(kinectObstacleScan(c, p), kinectObstacleScanBaseline(c, p));
  }
  PerceptionParams p;
  p.kos_heights = "0.25 0.05";  // overlapping slabs, in any order
  p.kos_band = 0.13;
  const Cloud c = edgeCloud(720, bandEdges(p), 5);
  expectSameScan(kinectObstacleScan(c, p), kinectObstacleScanBaseline(c, p));
}

TEST(VirtualScansSpeed, KosPointAboveTheRobotBlocksItsBinInItsLevelAsBefore) {
  // x = y = 0 in a band: range 0 in that level's bin (atan2 of zeros), which the per-level rule
  // leaves invalid unless another level sees something there.
  PerceptionParams p;
  for (float z : {0.1f, 0.6f}) {
    Cloud c;
    c.points = {{0.f, 0.f, z},    {0.f, -0.f, 0.3f},  {-1.f, 0.f, 0.1f},  {-1.f, -0.f, 0.1f},
                {1.f, 0.f, 0.6f}, {1.f, 1e-7f, 0.9f}, {2.f, -1e-7f, 0.6f}};
    c.width = c.points.size();
    expectSameScan(kinectObstacleScan(c, p), kinectObstacleScanBaseline(c, p));
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
