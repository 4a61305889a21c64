// Simulator throughput: simulated seconds per wall second for the
// ISR-AIWALKER walker (its Kinect One depth camera at 10 Hz, 512 x 424, and
// its Leddar range array) plus a 2D lidar at 10 Hz, driving a circle in the
// apartment world (walls, a table, a gutter) and the SENA corridors.
// Argument: the depth decimation (1 = full resolution).
//   build-sim/tests/bench/bench_sim --benchmark_counters_tabular=true
#include <carenav/common/profile.h>
#include <carenav/sim/simulator.h>

#include <benchmark/benchmark.h>

#include <memory>

using namespace carenav;
using namespace carenav::sim;

namespace {

const std::string kSrc = CARENAV_SOURCE_DIR;

std::vector<SensorParams> walkerSensors() {
  const Profile p = Profile::load(kSrc + "/ini/isr-aiwalker.ini");
  auto sensors = loadSensors(p);
  SensorParams lidar;  // the walker has no lidar: a 270 deg one low on the front
  lidar.label = "lidar";
  lidar.type = "lidar2d";
  lidar.x = 0.25;
  lidar.z = 0.3;
  lidar.rate_hz = 10;
  lidar.fov = 270;
  lidar.beams = 541;
  lidar.range_min = 0.1;
  lidar.range_max = 20;
  lidar.noise_std = 0.02;
  sensors.push_back(lidar);
  return sensors;
}

void run(benchmark::State& state, const std::string& world_file, Pose2 start, double radius) {
  static std::map<std::string, std::shared_ptr<const World>> worlds;
  auto& world = worlds[world_file];
  if (!world) world = std::make_shared<const World>(loadWorld(kSrc + "/maps/worlds/" + world_file));
  const Profile p = Profile::load(kSrc + "/ini/isr-aiwalker.ini");
  const auto robot = p.section<RobotParams>("robot");
  SimParams params = p.section<SimParams>("sim");
  params.depth_decimation = static_cast<int>(state.range(0));
  Simulator sim(world, robot, walkerSensors(), params);
  sim.reset(start);
  const double v = 0.25, w = v / radius;  // a circle
  size_t frames = 0;
  double simulated = 0;
  for (auto _ : state) {
    for (int i = 0; i < 20; ++i) {  // 1 s of simulated time per iteration
      sim.setCommand(v, w);
      frames += sim.step(0.05).size();
    }
    simulated += 1.0;
  }
  if (sim.collisions() > 0) state.SkipWithError("the walker hit something");
  state.counters["sim_s_per_wall_s"] = benchmark::Counter(simulated, benchmark::Counter::kIsRate);
  state.counters["frames"] = static_cast<double>(frames);
  const auto& cam = walkerSensors().front();
  state.counters["depth_px"] = static_cast<double>((cam.width / params.depth_decimation) *
                                                   (cam.height / params.depth_decimation));
}

void BM_SimWalkerApartment(benchmark::State& state) {
  run(state, "apartment.yaml", {3.0, 1.4, 0}, 1.2);
}
void BM_SimWalkerSena(benchmark::State& state) { run(state, "sena.yaml", {-6.0, 4.4, 0}, 1.0); }

}  // namespace

BENCHMARK(BM_SimWalkerApartment)->Arg(1)->Arg(2)->Arg(4)->Arg(8)->Unit(benchmark::kMillisecond)->UseRealTime();
void BM_SimWalkerEmptyRoom(benchmark::State& state) {
  run(state, "empty_room.yaml", {10, 9, 0}, 1.0);
}
BENCHMARK(BM_SimWalkerEmptyRoom)->Arg(1)->Arg(4)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SimWalkerSena)->Arg(1)->Arg(2)->Arg(4)->Arg(8)->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_MAIN();
