// Perception per stage and per frame on a 512x424 walker frame (analytic scene
// with a downward stair, a gutter and a wall), rrt-gpd against the baselines.
#include "../unit/perception/scene.h"
#include "../unit/perception/virtual_scans_baseline.h"

#include <carenav/perception/pipeline.h>

#include <benchmark/benchmark.h>

using namespace carenav::perception;
using namespace carenav_test;

namespace {
const Cloud& frame() {
  static const Cloud c = [] {
    Scene s;
    s.floor(-10, 1.5).floor(1.6, 2.2).floor(1.5, 1.6, -0.1).floor(2.2, 10, -0.17);
    s.box({3.5, 3.7, -10, 10, -0.2, 2.5});
    return renderDepth(s, walkerKinect());
  }();
  return c;
}

void runMethod(benchmark::State& st, Method m, bool scans, double noise = 0) {
  PerceptionParams p;
  p.depth_noise_std = noise;  // > 0: the noise-aware voxel rules (same work, other thresholds)
  Pipeline pipe(p, m);
  FrameInput in;
  in.cloud = &frame();
  in.sensor_origin = {0.2f, 0.f, 0.9f};
  for (auto _ : st) benchmark::DoNotOptimize(pipe.process(in, scans));
}
}  // namespace

static void BM_Frame_RrtGpd(benchmark::State& s) { runMethod(s, Method::RrtGpd, false); }
static void BM_Frame_Ransac(benchmark::State& s) { runMethod(s, Method::Ransac, false); }
static void BM_Frame_HeightBand(benchmark::State& s) { runMethod(s, Method::HeightBand, false); }
static void BM_Frame_RrtGpdNoiseModel(benchmark::State& s) {
  runMethod(s, Method::RrtGpd, false, 0.005);  // ini/isr-aiwalker.ini's depth_noise_std
}
static void BM_Frame_RrtGpdWithScans(benchmark::State& s) { runMethod(s, Method::RrtGpd, true); }

static void BM_ElevationGrid(benchmark::State& st) {
  ElevationGrid g(200, 0.05);
  for (auto _ : st) benchmark::DoNotOptimize(g.build(frame(), -1, 2, 3));
}
static void BM_GroundPlane_RrtGpd(benchmark::State& st) {
  ElevationGrid g(200, 0.05);
  g.build(frame(), -1, 2, 3);
  for (auto _ : st) benchmark::DoNotOptimize(detectGroundRrt(g, PerceptionParams{}));
}
static void BM_GroundPlane_RansacOnly(benchmark::State& st) {
  for (auto _ : st) benchmark::DoNotOptimize(detectGroundRansac(frame(), PerceptionParams{}));
}
static void BM_Ism(benchmark::State& st) {
  ElevationGrid g(200, 0.05);
  g.build(frame(), -1, 2, 3);
  const auto plane = *detectGroundRrt(g, PerceptionParams{}).plane;
  LocalOccupancy grid(200, 0.05, 4.6);
  for (auto _ : st) {
    grid.beginFrame();
    benchmark::DoNotOptimize(integrateIsm(g, plane, PerceptionParams{}, grid));
    grid.endFrame();
  }
}
static void BM_FspfPlus(benchmark::State& st) {
  for (auto _ : st)
    benchmark::DoNotOptimize(fspfPlus(frame(), {0.2f, 0.f, 0.9f}, PerceptionParams{}));
}
static void BM_Kos(benchmark::State& st) {
  const auto f = fspfPlus(frame(), {0.2f, 0.f, 0.9f}, PerceptionParams{});
  for (auto _ : st) benchmark::DoNotOptimize(kinectObstacleScan(f.filtered, PerceptionParams{}));
}
// Before the speed work of issue 17 (tests/unit/perception/virtual_scans_baseline.h), measured in
// the same run: docs/BENCHMARKS.md, 'Virtual scans: speed (issue 17)'.
static void BM_FspfPlusBaseline(benchmark::State& st) {
  for (auto _ : st)
    benchmark::DoNotOptimize(fspfPlusBaseline(frame(), {0.2f, 0.f, 0.9f}, PerceptionParams{}));
}
static void BM_KosBaseline(benchmark::State& st) {
  const auto f = fspfPlus(frame(), {0.2f, 0.f, 0.9f}, PerceptionParams{});
  for (auto _ : st)
    benchmark::DoNotOptimize(kinectObstacleScanBaseline(f.filtered, PerceptionParams{}));
}
static void BM_MaxRule(benchmark::State& st) {
  for (auto _ : st) benchmark::DoNotOptimize(maxRuleScan(frame(), PerceptionParams{}));
}

BENCHMARK(BM_Frame_RrtGpd)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Frame_Ransac)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Frame_HeightBand)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Frame_RrtGpdNoiseModel)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Frame_RrtGpdWithScans)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ElevationGrid)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GroundPlane_RrtGpd)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GroundPlane_RansacOnly)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Ism)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FspfPlus)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Kos)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FspfPlusBaseline)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_KosBaseline)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MaxRule)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
