// Time of one control cycle of each local planner, with the walker's
// settings of [Rosa17, Table 5.1] (7 s horizon at 0.1 s steps, 12 + 12 speed
// samples): a 3 m corridor with a box ahead, the walker moving at 0.3 m/s.
// Also the local cost map rebuild (distance transform) and the safety
// supervisor, which run every cycle as well.
#include <carenav/navigation/local_planner.h>
#include <carenav/navigation/safety.h>

#include <benchmark/benchmark.h>

namespace carenav::navigation {
namespace {

RobotParams walker() {
  RobotParams r;
  r.footprint = {{0.25, 0.325}, {-0.45, 0.325}, {-0.45, -0.325}, {0.25, -0.325}};
  r.v_max = 0.3;
  r.v_min = -0.15;
  r.w_max = 0.75;
  r.acc_v = 0.5;
  r.acc_w = 1.0;
  r.safe_distance = 0.325;
  return r;
}

NavigationParams walkerNav() {
  NavigationParams p;
  p.sim_time = 7.0;
  p.sim_step = 0.1;
  p.window_time = 0.5;
  p.v_samples = 12;
  p.w_samples = 11;
  return p;
}

std::vector<TPoint2D> corridorWithBox() {
  std::vector<TPoint2D> pts;
  for (double x = -4; x <= 4; x += 0.05) {
    pts.push_back({x, -1.5});
    pts.push_back({x, 1.5});
  }
  for (double x = 2.4; x <= 2.8; x += 0.05)
    for (double y = 0.15; y <= 0.6; y += 0.05) pts.push_back({x, y});
  return pts;
}

void BM_CostmapBuild(benchmark::State& state) {
  const auto nav = walkerNav();
  LocalCostmap map(nav, Footprint(walker().footprint, nav.resolution));
  const auto obs = corridorWithBox();
  for (auto _ : state) map.build({0, 0}, obs);
  state.counters["cells"] = map.size() * map.size();
}
BENCHMARK(BM_CostmapBuild)->Unit(benchmark::kMillisecond);

void BM_PlannerCycle(benchmark::State& state, const char* plugin) {
  auto nav = walkerNav();
  nav.plugin = plugin;
  const auto robot = walker();
  LocalCostmap map(nav, Footprint(robot.footprint, nav.resolution));
  map.build({0, 0}, corridorWithBox());
  auto planner = PlannerRegistry::instance().create(plugin, nav, robot);
  PlannerInput in;
  in.pose = {0, 0, 0};
  in.current = {0.3, 0};
  in.map = &map;
  in.user = Twist{0.3, 0};
  in.path = {{0, 0}, {3.5, -0.6}, {6, 0}};
  in.goal = TPose2D{6, 0, 0};
  size_t evaluated = 0;
  for (auto _ : state) {
    const auto out = planner->plan(in);
    evaluated = out.evaluated;
    benchmark::DoNotOptimize(out.cmd);
  }
  state.counters["trajectories"] = static_cast<double>(evaluated);
}
BENCHMARK_CAPTURE(BM_PlannerCycle, user_intent_dwa, "user-intent-dwa")
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_PlannerCycle, goal_dwa, "goal-dwa")->Unit(benchmark::kMillisecond);
// MRPT's TP-space navigation (default [nav.mrpt_ptg]: C and alpha PTGs of
// 121 paths, 3 m reference distance, CHolonomicFullEval with clearance).
BENCHMARK_CAPTURE(BM_PlannerCycle, mrpt_ptg, "mrpt-ptg")->Unit(benchmark::kMillisecond);

void BM_Supervisor(benchmark::State& state) {
  const auto nav = walkerNav();
  const auto robot = walker();
  LocalCostmap map(nav, Footprint(robot.footprint, nav.resolution));
  map.build({0, 0}, corridorWithBox());
  const SafetySupervisor sup(nav, robot);
  SafetyInput in;
  in.now = 1;
  in.last_scan_time = 1;
  in.last_odom_time = 1;
  in.plan.ok = true;
  in.plan.cmd = {0.3, 0};
  in.map = &map;
  for (auto _ : state) benchmark::DoNotOptimize(sup.apply(in));
}
BENCHMARK(BM_Supervisor)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace carenav::navigation

BENCHMARK_MAIN();
