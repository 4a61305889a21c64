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
// Virtual scans against the implementations before the speed work of issue 17
// (tests/unit/perception/virtual_scans_baseline.h), measured in the same run: docs/BENCHMARKS.md,
// 'Virtual scans: speed (issue 17)'. Frames: bench frame above; the same scene at the profiles'
// [sim] depth_decimation 4 (128 x 106); a room (walls left, right and ahead, a box, a table top).
namespace {
enum class VsFrame { Stair, StairDecim4, Room };
const Cloud& vsFrame(VsFrame f) {
  static const Cloud decim4 = [] {
    Scene s;
    s.floor(-10, 1.5).floor(1.6, 2.2).floor(1.5, 1.6, -0.1).floor(2.2, 10, -0.17);
    s.box({3.5, 3.7, -10, 10, -0.2, 2.5});
    return renderDepth(s, walkerKinect(), 7, 1.0, nullptr, 128, 106);
  }();
  static const Cloud room = [] {
    Scene s;
    s.floor(-10, 10)
        .box({2.5, 2.7, -10, 10, 0, 2.5})
        .box({-10, 10, 1.2, 1.4, 0, 2.5})
        .box({-10, 10, -1.6, -1.4, 0, 2.5})
        .box({1.2, 1.4, -0.1, 0.1, 0, 0.4})
        .box({1.6, 2.2, -1.0, -0.2, 0.7, 0.74});
    return renderDepth(s, walkerKinect(), 11);
  }();
  return f == VsFrame::Stair ? frame() : (f == VsFrame::StairDecim4 ? decim4 : room);
}
template <bool kBaseline>
void runFspf(benchmark::State& st, VsFrame fr) {
  const Cloud& c = vsFrame(fr);
  const PerceptionParams p;
  for (auto _ : st)
    benchmark::DoNotOptimize(kBaseline ? fspfPlusBaseline(c, {0.2f, 0.f, 0.9f}, p)
                                       : fspfPlus(c, {0.2f, 0.f, 0.9f}, p));
  st.counters["px"] = static_cast<double>(c.points.size());
}
template <bool kBaseline>
void runKos(benchmark::State& st, VsFrame fr) {
  const PerceptionParams p;
  const Cloud filtered = fspfPlus(vsFrame(fr), {0.2f, 0.f, 0.9f}, p).filtered;
  for (auto _ : st)
    benchmark::DoNotOptimize(kBaseline ? kinectObstacleScanBaseline(filtered, p)
                                       : kinectObstacleScan(filtered, p));
  st.counters["points"] = static_cast<double>(filtered.points.size());
}
}  // namespace
// The whole rrt-gpd frame at the profiles' [sim] depth_decimation 4 (128 x 106 pixels).
static void BM_Frame_RrtGpd_Decim4(benchmark::State& st) {
  Pipeline pipe(PerceptionParams{}, Method::RrtGpd);
  FrameInput in;
  in.cloud = &vsFrame(VsFrame::StairDecim4);
  in.sensor_origin = {0.2f, 0.f, 0.9f};
  for (auto _ : st) benchmark::DoNotOptimize(pipe.process(in, false));
}
static void BM_FspfPlusBaseline(benchmark::State& s) { runFspf<true>(s, VsFrame::Stair); }
static void BM_KosBaseline(benchmark::State& s) { runKos<true>(s, VsFrame::Stair); }
static void BM_FspfPlus_Decim4(benchmark::State& s) { runFspf<false>(s, VsFrame::StairDecim4); }
static void BM_FspfPlusBaseline_Decim4(benchmark::State& s) {
  runFspf<true>(s, VsFrame::StairDecim4);
}
static void BM_Kos_Decim4(benchmark::State& s) { runKos<false>(s, VsFrame::StairDecim4); }
static void BM_KosBaseline_Decim4(benchmark::State& s) { runKos<true>(s, VsFrame::StairDecim4); }
static void BM_FspfPlus_Room(benchmark::State& s) { runFspf<false>(s, VsFrame::Room); }
static void BM_FspfPlusBaseline_Room(benchmark::State& s) { runFspf<true>(s, VsFrame::Room); }
static void BM_Kos_Room(benchmark::State& s) { runKos<false>(s, VsFrame::Room); }
static void BM_KosBaseline_Room(benchmark::State& s) { runKos<true>(s, VsFrame::Room); }
static void BM_MaxRule(benchmark::State& st) {
  for (auto _ : st) benchmark::DoNotOptimize(maxRuleScan(frame(), PerceptionParams{}));
}

BENCHMARK(BM_Frame_RrtGpd)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Frame_Ransac)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Frame_HeightBand)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Frame_RrtGpdNoiseModel)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Frame_RrtGpd_Decim4)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Frame_RrtGpdWithScans)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ElevationGrid)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GroundPlane_RrtGpd)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GroundPlane_RansacOnly)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Ism)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FspfPlus)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Kos)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FspfPlusBaseline)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_KosBaseline)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FspfPlus_Decim4)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FspfPlusBaseline_Decim4)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Kos_Decim4)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_KosBaseline_Decim4)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FspfPlus_Room)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FspfPlusBaseline_Room)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Kos_Room)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_KosBaseline_Room)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MaxRule)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
