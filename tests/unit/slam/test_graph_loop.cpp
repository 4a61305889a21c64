// icp-graph on simulated runs with exact ground truth (the simulator of `carenav simulate`:
// the INTERBOT's laser alone, driven on the real SENA map with the
// simulator's odometry noise): a loop closes when the robot comes back to its
// start from another heading, and a run without any revisit is left as the
// scan-matching front end made it.
#include <carenav/common/profile.h>
#include <carenav/common/robot.h>
#include <carenav/io/evaluation.h>
#include <carenav/io/trajectory.h>
#include <carenav/sim/drive.h>
#include <carenav/sim/simulate_job.h>
#include <carenav/slam/slam_job.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>

using namespace carenav;
namespace fs = std::filesystem;

namespace {
const std::string kSrc = CARENAV_SOURCE_DIR;

fs::path scratch(const std::string& name) {
  auto d = fs::temp_directory_path() / ("carenav_graph_" + std::to_string(::getpid())) / name;
  fs::create_directories(d);
  return d;
}

/** Simulates a drive along `path` (x,y waypoints) round the SENA building and
 *  returns the rawlog; the ground truth is next to it (.gt.tum). What
 *  `carenav simulate` does with the INTERBOT's profile without its Kinect
 *  section, `--set sensor.laser.rate_hz=5 --seed 3 --start -8,4.5,0`. */
std::string simulate(const fs::path& dir, const std::string& path) {
  Profile p = Profile::load(kSrc + "/ini/interbot.ini");
  p.applyOverrides({"sensor.laser.rate_hz=5"});
  sim::SimulateOptions o;
  o.robot = p.section<RobotParams>("robot");
  o.sensors = loadSensors(p);
  o.sensors.erase(std::remove_if(o.sensors.begin(), o.sensors.end(),
                                 [](const SensorParams& s) { return s.label == "kinect"; }),
                  o.sensors.end());
  o.params = p.section<sim::SimParams>("sim");
  o.params.seed = 3;
  o.world = kSrc + "/maps/worlds/sena.yaml";
  o.path = sim::parsePath(path);
  o.start = sim::parseStart("-8,4.5,0");
  o.out = (dir / "run.rawlog").string();
  o.progress = false;
  return sim::runSimulate(o).rawlog;
}

struct MapRun {
  slam::SlamJobResult result;
  double ate = 0;  // m, RMSE after SE(2) alignment
};

MapRun map(const std::string& rawlog, const std::string& method, const fs::path& out,
           double loop_search_radius = 4.0, bool loop_consistency = false,
           double loop_search_max = -1) {
  slam::SlamJobOptions o;
  o.rawlog = rawlog;
  o.out_dir = out.string();
  o.method = method;
  o.progress = false;
  o.mapper.slam.loop_search_radius = loop_search_radius;
  // The radius grows with the drift up to loop_search_max (default: no
  // growth, loop_search_radius is the reach).
  o.mapper.slam.loop_search_max = loop_search_max >= 0 ? loop_search_max : loop_search_radius;
  o.mapper.slam.loop_consistency = loop_consistency;
  MapRun r;
  r.result = slam::runSlam(o);
  const auto est = io::readTum((out / "trajectory.tum").string());
  const auto ref = io::readTum(rawlog.substr(0, rawlog.size() - 7) + ".gt.tum");
  r.ate = io::computeAte(io::associate(est, ref)).translation.rmse;
  return r;
}
}  // namespace

TEST(SlamGraphSimulated, ClosesALoopRevisitedFromAnotherHeading) {
  // Once round the building: the robot leaves its start heading east and
  // comes back heading north, so the keyframes at the two ends share only
  // part of their view (ICP goodness about 0.6: the visibility checks must
  // accept the closure).
  const auto dir = scratch("loop");
  const std::string rawlog = simulate(dir, "-8,4.5 3,4.5 3,-16 -8,-16 -8,4.5");
  const MapRun closed = map(rawlog, "icp-graph", dir / "closed");
  const MapRun open = map(rawlog, "icp-graph", dir / "open", 0.1);  // no candidate in reach
  EXPECT_EQ(open.result.stats.loop_closures, 0u);
  EXPECT_GE(closed.result.stats.loop_closures, 3u);
  EXPECT_GE(closed.result.stats.optimisations, 1u);
  // The front end (point-to-line ICP under the odometry's prior) keeps even
  // the open chain within a few mm of the truth on this loop, so there is
  // no drift left for the closures to pull back (with the point-to-point
  // front end there was: the open chain was then the worse by 30 %). The
  // closures must not make the map worse, and it stays within 5 cm.
  EXPECT_LE(closed.ate, open.ate + 0.002) << "closed " << closed.ate << " open " << open.ate;
  EXPECT_LT(closed.ate, 0.05);
  // The end of the loop is the start again.
  EXPECT_LT(closed.result.final_pose.norm(), 0.15);
  // With no reach of its own (0.1 m, as `open`) but allowed to grow with the
  // drift since the last closure (3 sigma of the chain, up to 15 m), the
  // search radius finds the loop.
  const MapRun grown = map(rawlog, "icp-graph", dir / "grown", 0.1, false, 15.0);
  EXPECT_GE(grown.result.stats.loop_closures, 3u);
  EXPECT_LT(grown.ate, 0.05);
  EXPECT_LT(grown.result.final_pose.norm(), 0.15);
  // With the pairwise consistency check (slam.loop_consistency) the
  // closures of the revisit support each other and still enter the graph.
  const MapRun checked = map(rawlog, "icp-graph", dir / "checked", 4.0, true);
  EXPECT_GE(checked.result.stats.loop_closures, 3u);
  EXPECT_LT(checked.ate, 0.05);
  EXPECT_LT(checked.result.final_pose.norm(), 0.15);
}

TEST(SlamGraphSimulated, StraightRunWithoutRevisitIsLeftAlone) {
  // East along a corridor then south: no place is seen twice. The graph
  // must not move anything (no closure, no optimisation) and be as accurate
  // as MRPT's ICP map builder on the same scans.
  const auto dir = scratch("straight");
  const std::string rawlog = simulate(dir, "-8,4.5 3,4.5 3,-2");
  const MapRun graph = map(rawlog, "icp-graph", dir / "graph");
  const MapRun icp = map(rawlog, "icp", dir / "icp");
  EXPECT_EQ(graph.result.stats.loop_closures, 0u);
  EXPECT_EQ(graph.result.stats.optimisations, 0u);
  EXPECT_GT(graph.result.stats.keyframes, 20u);
  EXPECT_LT(graph.ate, 1.25 * icp.ate + 0.01) << "graph " << graph.ate << " icp " << icp.ate;
  EXPECT_LT(graph.ate, 0.05);
}
