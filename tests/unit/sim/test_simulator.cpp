// The robot: kinematics under the profile's limits and latency, waypoint
// following, odometry noise (systematic and random, reproducible under a
// seed), the bumper, sensor timing.
#include <carenav/sim/drive.h>
#include <carenav/sim/simulator.h>

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

using namespace carenav;
using namespace carenav::sim;
namespace fs = std::filesystem;

namespace {
const std::string kWorlds = std::string(CARENAV_SOURCE_DIR) + "/maps/worlds";

std::shared_ptr<const World> emptyRoom() {
  static auto w = std::make_shared<const World>(loadWorld(kWorlds + "/empty_room.yaml"));
  return w;
}

SimParams noiseless() {
  SimParams p;
  p.odom_scale_d = p.odom_scale_w = p.odom_bias_w = 0;
  p.odom_std_d = p.odom_std_w = p.odom_std_wd = 0;
  return p;
}

SensorParams laser(double rate = 10) {
  SensorParams s;
  s.label = "laser";
  s.type = "lidar2d";
  s.x = 0.2;
  s.z = 0.3;
  s.rate_hz = rate;
  s.fov = 180;
  s.beams = 181;
  s.range_min = 0.1;
  s.range_max = 30;
  s.noise_std = 0;
  return s;
}

void drive(Simulator& sim, double v, double w, double seconds) {
  for (int i = 0; i < static_cast<int>(std::lround(seconds / 0.05)); ++i) {
    sim.setCommand(v, w);
    sim.step(0.05);
  }
}
}  // namespace

TEST(SimRobot, StraightRunFollowsLatencyAndAccelerationRamp) {
  RobotParams robot;  // v_max 0.3, acc_v 0.5
  SimParams p = noiseless();
  p.latency = 0.2;
  Simulator sim(emptyRoom(), robot, {}, p);
  sim.reset({5, 10, 0});
  drive(sim, 0.3, 0, 10.0);
  // nothing moves for the latency, then v ramps at acc_v to v_max
  const double ramp = 0.3 / 0.5;
  const double expected = 0.5 * 0.5 * ramp * ramp + 0.3 * (10.0 - 0.2 - ramp);
  EXPECT_NEAR(sim.groundTruth().x - 5, expected, 0.3 * p.physics_dt);
  EXPECT_NEAR(sim.groundTruth().y, 10, 1e-9);
  EXPECT_NEAR(sim.v(), 0.3, 1e-9);
  EXPECT_NEAR(sim.time(), 10.0, 1e-9);
  // noiseless odometry equals the truth
  EXPECT_NEAR(sim.odometry().x, sim.groundTruth().x, 1e-9);
}

TEST(SimRobot, CommandsAreClampedToTheLimits) {
  RobotParams robot;
  robot.v_min = -0.1;
  Simulator sim(emptyRoom(), robot, {}, noiseless());
  sim.reset({10, 10, 0});
  drive(sim, 5.0, 9.0, 5.0);
  EXPECT_NEAR(sim.v(), robot.v_max, 1e-9);
  EXPECT_NEAR(sim.w(), robot.w_max, 1e-9);
  drive(sim, -5.0, 0, 5.0);
  EXPECT_NEAR(sim.v(), -0.1, 1e-9);
}

TEST(SimRobot, CircleReturnsToItsStart) {
  RobotParams robot;
  robot.acc_v = robot.acc_w = 1000;  // immediate: a clean circle
  SimParams p = noiseless();
  p.latency = 0;
  Simulator sim(emptyRoom(), robot, {}, p);
  sim.reset({10, 8, 0});
  const double w = 0.5, v = 0.25;  // radius 0.5 m
  drive(sim, v, w, 2 * M_PI / w);
  // exact arcs: back at the start up to the first step's ramp
  EXPECT_NEAR(sim.groundTruth().x, 10, 0.01);
  EXPECT_NEAR(sim.groundTruth().y, 8, 0.01);
  EXPECT_NEAR(sim.distance(), v * 2 * M_PI / w, 0.01);
}

TEST(SimRobot, KnownPathInAnEmptyWorldReturnsTheGroundTruth) {
  RobotParams robot;
  Simulator sim(emptyRoom(), robot, {laser()}, noiseless());
  const std::vector<Vec2> path = {{3, 3}, {12, 3}, {12, 12}, {4, 14}};
  sim.reset({3, 3, 0});
  WaypointFollower f(path, robot);
  std::vector<Pose2> truth;
  size_t frames = 0;
  for (int i = 0; i < 4000 && !f.done(); ++i) {
    double v, w;
    f.command(sim.groundTruth(), v, w);
    sim.setCommand(v, w);
    frames += sim.step(0.05).size();
    truth.push_back(sim.groundTruth());  // the pose the follower sees next
  }
  ASSERT_TRUE(f.done());
  drive(sim, 0, 0, 2.0);  // stop: latency and braking
  EXPECT_LT(std::hypot(sim.groundTruth().x - 4, sim.groundTruth().y - 14), 0.1);
  EXPECT_EQ(sim.collisions(), 0u);
  // every waypoint was passed within the follower's tolerance, the last within half
  for (size_t k = 0; k < path.size(); ++k) {
    double dmin = 1e9;
    for (const auto& q : truth) dmin = std::min(dmin, std::hypot(q.x - path[k].x, q.y - path[k].y));
    EXPECT_LT(dmin, k + 1 == path.size() ? 0.1 : 0.2) << "waypoint " << k;
  }
  // the track stays on the legs of the path (integration error of the controller)
  for (const auto& q : truth) {
    double dseg = 1e9;
    for (size_t k = 0; k + 1 < path.size(); ++k) {
      const double ex = path[k + 1].x - path[k].x, ey = path[k + 1].y - path[k].y;
      const double u = std::clamp(
          ((q.x - path[k].x) * ex + (q.y - path[k].y) * ey) / (ex * ex + ey * ey), 0.0, 1.0);
      dseg = std::min(dseg, std::hypot(path[k].x + u * ex - q.x, path[k].y + u * ey - q.y));
    }
    EXPECT_LT(dseg, 0.35);
  }
  // frames come at the lidar's 10 Hz
  EXPECT_NEAR(static_cast<double>(frames), (truth.size() + 1) / 2.0, 1.0);
}

TEST(SimRobot, OdometryNoiseIsReproducibleUnderASeed) {
  RobotParams robot;
  SimParams p;  // the defaults: systematic and random errors
  auto run = [&](int seed) {
    p.seed = seed;
    Simulator sim(emptyRoom(), robot, {}, p);
    sim.reset({5, 5, 0});
    drive(sim, 0.3, 0.2, 20);
    return std::make_pair(sim.odometry(), sim.groundTruth());
  };
  const auto a = run(7), b = run(7), c = run(8);
  EXPECT_EQ(a.first.x, b.first.x);
  EXPECT_EQ(a.first.y, b.first.y);
  EXPECT_EQ(a.first.yaw, b.first.yaw);
  EXPECT_EQ(a.second.x, c.second.x);  // the truth does not depend on the seed
  EXPECT_NE(a.first.x, c.first.x);    // the noise does
  // odometry drifts from the truth
  EXPECT_GT(std::hypot(a.first.x - a.second.x, a.first.y - a.second.y), 0.01);
}

TEST(SimRobot, SystematicOdometryErrorsAccumulate) {
  RobotParams robot;
  SimParams p = noiseless();
  p.odom_scale_d = 0.1;
  Simulator sim(emptyRoom(), robot, {}, p);
  sim.reset({2, 10, 0});
  drive(sim, 0.3, 0, 20);
  const double dt = sim.groundTruth().x - 2, dodo = sim.odometry().x - 2;
  EXPECT_NEAR(dodo, 1.1 * dt, 1e-6);
  // a heading drift per metre bends the odometry
  p = noiseless();
  p.odom_bias_w = 2.0;  // deg per metre
  Simulator s2(emptyRoom(), robot, {}, p);
  s2.reset({2, 10, 0});
  drive(s2, 0.3, 0, 20);
  EXPECT_NEAR(s2.odometry().yaw * 180 / M_PI, 2.0 * s2.distance(), 1e-6);
  EXPECT_NEAR(s2.groundTruth().yaw, 0, 1e-12);
}

TEST(SimRobot, RandomOdometryErrorGrowsWithDistance) {
  RobotParams robot;
  SimParams p = noiseless();
  p.odom_std_d = 0.05;
  p.odom_std_wd = 1.0;
  std::vector<double> err5, err20;
  for (int seed = 1; seed <= 30; ++seed) {
    p.seed = seed;
    Simulator sim(emptyRoom(), robot, {}, p);
    sim.reset({2, 10, 0});
    drive(sim, 0.3, 0, 5 / 0.3);
    err5.push_back(
        std::hypot(sim.odometry().x - sim.groundTruth().x, sim.odometry().y - sim.groundTruth().y));
    drive(sim, 0.3, 0, 15 / 0.3);
    err20.push_back(
        std::hypot(sim.odometry().x - sim.groundTruth().x, sim.odometry().y - sim.groundTruth().y));
  }
  double m5 = 0, m20 = 0;
  for (size_t i = 0; i < err5.size(); ++i)
    m5 += err5[i] / err5.size(), m20 += err20[i] / err20.size();
  EXPECT_GT(m5, 0.01);
  EXPECT_GT(m20, 1.5 * m5);
}

TEST(SimRobot, BumperStopsTheRobotAtAWallAndCountsOnce) {
  RobotParams robot;  // 0.5 m square footprint
  Simulator sim(emptyRoom(), robot, {}, noiseless());
  sim.reset({18.5, 10, 0});  // wall face at x = 19.9
  drive(sim, 0.3, 0, 15);
  EXPECT_TRUE(sim.collided());
  EXPECT_EQ(sim.collisions(), 1u);
  EXPECT_LE(sim.groundTruth().x + 0.25, 19.9 + 1e-9);
  EXPECT_GT(sim.groundTruth().x + 0.25, 19.9 - 0.1);
  EXPECT_EQ(sim.v(), 0.0);
  // backing away releases the bumper
  RobotParams r2 = robot;
  r2.v_min = -0.2;
  Simulator s2(emptyRoom(), r2, {}, noiseless());
  s2.reset({18.5, 10, 0});
  drive(s2, 0.3, 0, 15);
  drive(s2, -0.2, 0, 3);
  EXPECT_FALSE(s2.collided());
  EXPECT_EQ(s2.collisions(), 1u);
}

TEST(SimRobot, BumperMeetsPeople) {
  Person p;
  p.path = {{12, 10}};
  auto w = std::make_shared<World>(loadWorld(kWorlds + "/empty_room.yaml"));
  World with(w->grid(), {}, {p}, 2.5);
  Simulator sim(std::make_shared<World>(with), RobotParams{}, {}, noiseless());
  sim.reset({10, 10, 0});
  drive(sim, 0.3, 0, 10);
  EXPECT_EQ(sim.collisions(), 1u);
  EXPECT_NEAR(sim.groundTruth().x, 12 - 0.25 - 0.25, 0.02);
}

TEST(SimRobot, FramesComeAtTheSensorRatesWithOdometryFirst) {
  SensorParams fast = laser(20), slow = laser(5);
  slow.label = "slow";
  Simulator sim(emptyRoom(), RobotParams{}, {fast, slow}, SimParams{});
  sim.reset({10, 10, 0});
  size_t n_fast = 0, n_slow = 0, frames = 0;
  double last_t = -1;
  for (int i = 0; i < 20; ++i) {
    sim.setCommand(0.2, 0.1);
    for (const auto& f : sim.step(0.1)) {
      ++frames;
      EXPECT_GT(f.t, last_t);
      last_t = f.t;
      ASSERT_FALSE(f.observations.empty());
      auto odo = std::dynamic_pointer_cast<mrpt::obs::CObservationOdometry>(f.observations[0]);
      ASSERT_TRUE(odo);
      EXPECT_EQ(odo->timestamp, simStamp(f.t));
      for (const auto& o : f.observations) {
        EXPECT_EQ(o->timestamp, simStamp(f.t));
        if (o->sensorLabel == "laser") ++n_fast;
        if (o->sensorLabel == "slow") ++n_slow;
      }
    }
  }
  EXPECT_EQ(n_fast, 40u);  // 2 s at 20 Hz
  EXPECT_EQ(n_slow, 10u);  // 2 s at 5 Hz
  EXPECT_EQ(frames, 40u);
}

TEST(SimRobot, LidarMaxRangePolicy) {
  SensorParams s = laser();
  s.range_max = 5;
  SimParams p = noiseless();
  Simulator a(emptyRoom(), RobotParams{}, {s}, p);
  a.reset({10, 10, 0});
  auto scan = std::dynamic_pointer_cast<mrpt::obs::CObservation2DRangeScan>(a.observe(0));
  ASSERT_TRUE(scan);
  EXPECT_FALSE(scan->getScanRangeValidity(90));  // the wall ahead is 9.7 m away
  EXPECT_FLOAT_EQ(scan->getScanRange(90), 5.0f);
  p.lidar_max_range = "max";
  Simulator b(emptyRoom(), RobotParams{}, {s}, p);
  b.reset({10, 10, 0});
  scan = std::dynamic_pointer_cast<mrpt::obs::CObservation2DRangeScan>(b.observe(0));
  EXPECT_TRUE(scan->getScanRangeValidity(90));
  s.range_max = 30;
  Simulator c(emptyRoom(), RobotParams{}, {s}, p);
  c.reset({10, 10, 0});
  scan = std::dynamic_pointer_cast<mrpt::obs::CObservation2DRangeScan>(c.observe(0));
  EXPECT_NEAR(scan->getScanRange(90), 19.9 - 10.2, 0.05);  // sensor 0.2 m ahead of the axle
  EXPECT_TRUE(scan->getScanRangeValidity(90));
}

TEST(SimDrive, ParsesPathsAndStarts) {
  const auto p = parsePath("1,2 3.5,-4");
  ASSERT_EQ(p.size(), 2u);
  EXPECT_EQ(p[1].y, -4);
  EXPECT_NEAR(parseStart("1,2,90").yaw, M_PI / 2, 1e-12);
  EXPECT_THROW(parsePath(""), InputError);
  EXPECT_THROW(parsePath("1,2 3"), InputError);
  EXPECT_THROW(parsePath("1,x"), InputError);
  EXPECT_THROW(parseStart("1,2"), InputError);
  EXPECT_THROW(parseStart("1,2,3,"), InputError);
}

TEST(SimDrive, ScriptsAreReadStrictly) {
  const auto dir = fs::temp_directory_path() / ("carenav_sim_script_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name) << text;
    return (dir / name).string();
  };
  const auto good = readCommandScript(write("good.txt", "# t v w\n0 0.2 0\n\n2 0.2 0.5\n4 0 0\n"));
  ASSERT_EQ(good.rows.size(), 3u);
  double v, w;
  good.at(3, v, w);
  EXPECT_EQ(v, 0.2);
  EXPECT_EQ(w, 0.5);
  EXPECT_EQ(good.endTime(), 4);
  auto err = [&](const std::string& name, const std::string& text) -> std::string {
    try {
      readCommandScript(write(name, text));
    } catch (const InputError& e) {
      return e.what();
    }
    return "(no error)";
  };
  EXPECT_NE(err("empty.txt", "").find("empty.txt"), std::string::npos);
  EXPECT_NE(err("comments.txt", "# only\n").find("no command rows"), std::string::npos);
  EXPECT_NE(err("trunc.txt", "0 0.2 0\n1 0.2").find("trunc.txt:2"), std::string::npos)
      << err("trunc.txt", "0 0.2 0\n1 0.2");
  EXPECT_NE(err("bad.txt", "0 fast 0\n").find("bad.txt:1"), std::string::npos);
  EXPECT_NE(err("back.txt", "2 0 0\n1 0 0\n").find("goes back"), std::string::npos);
  EXPECT_THROW(readCommandScript((dir / "absent.txt").string()), InputError);
}

TEST(SimRobot, StepsStopTheRobotButSillsAndDropsDoNot) {
  auto make = [](double height) {
    Feature f;
    f.kind = Feature::Kind::Step;
    f.height = height;
    f.polygon = {{6, 0}, {6.5, 0}, {6.5, 10}, {6, 10}};
    auto g = loadWorld(kWorlds + "/empty_room.yaml").grid();
    return std::make_shared<World>(g, std::vector<Feature>{f}, std::vector<Person>{}, 2.5);
  };
  for (double h : {0.10, 0.03, -0.2}) {
    Simulator sim(make(h), RobotParams{}, {}, noiseless());
    sim.reset({4, 5, 0});
    drive(sim, 0.3, 0, 15);
    if (h > 0.05) {  // above bumper_step: stopped with the footprint at the step's edge
      EXPECT_EQ(sim.collisions(), 1u) << h;
      EXPECT_NEAR(sim.groundTruth().x + 0.25, 6.0, 0.06) << h;
    } else {
      EXPECT_EQ(sim.collisions(), 0u) << h;
      EXPECT_GT(sim.groundTruth().x, 7.5) << h;
    }
  }
}
