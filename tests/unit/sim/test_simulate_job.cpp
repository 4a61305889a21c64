// `carenav simulate`'s job: the rawlog it writes is read back by carenav's
// rawlog reader with its observations, odometry increments and timestamps
// matching the ground-truth TUM; the summary counts what was written.
#include <carenav/io/rawlog_reader.h>
#include <carenav/io/trajectory.h>
#include <carenav/sim/simulate_job.h>

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CObservationRange.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

using namespace carenav;
using namespace carenav::sim;
namespace fs = std::filesystem;

namespace {
const std::string kWorlds = std::string(CARENAV_SOURCE_DIR) + "/maps/worlds";

fs::path scratch() {
  auto d = fs::temp_directory_path() / ("carenav_sim_job_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

SimulateOptions walker() {
  SimulateOptions o;
  SensorParams lidar;
  lidar.label = "laser";
  lidar.type = "lidar2d";
  lidar.z = 0.3;
  lidar.beams = 271;
  lidar.fov = 270;
  lidar.range_max = 20;
  SensorParams cam;
  cam.label = "kinect";
  cam.type = "depth-camera";
  cam.x = 0.2;
  cam.z = 0.9;
  cam.pitch = 30;
  cam.width = 64;
  cam.height = 53;
  cam.fov = 70.6;
  cam.vfov = 60;
  cam.range_min = 0.5;
  cam.range_max = 4.5;
  cam.rate_hz = 5;
  SensorParams leddar;
  leddar.label = "leddar";
  leddar.type = "range-array";
  leddar.z = 0.3;
  leddar.segments = 16;
  leddar.fov = 45;
  leddar.range_min = 0;
  leddar.range_max = 50;
  o.sensors = {lidar, cam, leddar};
  o.world = kWorlds + "/apartment.yaml";
  o.path = {{1, 1}, {4, 1}, {6, 3.5}, {8.5, 3.5}};
  o.progress = false;
  return o;
}
}  // namespace

TEST(SimJob, RawlogIsReadBackWithGroundTruthTimestamps) {
  auto o = walker();
  o.out = (scratch() / "walk.rawlog").string();
  const auto r = runSimulate(o);
  EXPECT_TRUE(r.path_completed);
  EXPECT_EQ(r.collisions, 0u);
  EXPECT_EQ(r.ground_truth, (scratch() / "walk.gt.tum").string());
  ASSERT_TRUE(fs::exists(r.rawlog));
  ASSERT_TRUE(fs::exists(r.summary));
  const auto gt = io::readTum(r.ground_truth);
  ASSERT_EQ(gt.size(), r.frames);

  io::RawlogReader reader(r.rawlog);
  io::RawlogEntry e;
  std::map<std::string, size_t> counts;
  size_t increments = 0, frame = 0;
  double last_t = -1;
  while (reader.next(e)) {
    ASSERT_EQ(e.kind, io::EntryKind::Observation);
    const auto& obs = e.observation;
    ++counts[obs->sensorLabel];
    const double t = mrpt::Clock::toDouble(obs->timestamp);
    if (auto odo = std::dynamic_pointer_cast<mrpt::obs::CObservationOdometry>(obs)) {
      ASSERT_LT(frame, gt.size());
      EXPECT_NEAR(t, gt[frame].t, 1e-6);  // each frame starts with its odometry
      EXPECT_GT(t, last_t);
      last_t = t;
      ++frame;
      if (e.odometry_increment) ++increments;
    } else {
      EXPECT_NEAR(t, last_t, 1e-9);  // sensor observations share their frame's time
    }
    if (auto scan = std::dynamic_pointer_cast<mrpt::obs::CObservation2DRangeScan>(obs)) {
      EXPECT_EQ(scan->getScanSize(), 271u);
      EXPECT_NEAR(scan->sensorPose.z(), 0.3, 1e-9);
    }
    if (auto d = std::dynamic_pointer_cast<mrpt::obs::CObservation3DRangeScan>(obs)) {
      EXPECT_TRUE(d->hasRangeImage);
      EXPECT_EQ(d->rangeImage.cols(), 64);
      EXPECT_NEAR(d->sensorPose.pitch(), 30 * M_PI / 180, 1e-9);
    }
    if (auto a = std::dynamic_pointer_cast<mrpt::obs::CObservationRange>(obs))
      EXPECT_EQ(a->sensedData.size(), 16u);
  }
  EXPECT_EQ(frame, gt.size());
  EXPECT_GE(increments + 1, frame);
  EXPECT_EQ(counts, r.observations);
  EXPECT_EQ(counts["laser"], counts["odometry"]);  // the lidar is the fastest (10 Hz)
  EXPECT_NEAR(static_cast<double>(counts["kinect"]), counts["laser"] / 2.0, 1.0);

  std::stringstream ss;
  ss << std::ifstream(r.summary).rdbuf();
  EXPECT_NE(ss.str().find("\"collisions\": 0"), std::string::npos) << ss.str();
  EXPECT_NE(ss.str().find("\"kinect\": " + std::to_string(counts["kinect"])), std::string::npos);
}

TEST(SimJob, SameSeedSameFiles) {
  auto o = walker();
  o.sensors.resize(1);
  o.out = (scratch() / "a.rawlog").string();
  runSimulate(o);
  o.out = (scratch() / "b.rawlog").string();
  runSimulate(o);
  auto slurp = [](const fs::path& p) {
    std::stringstream ss;
    ss << std::ifstream(p, std::ios::binary).rdbuf();
    return ss.str();
  };
  EXPECT_EQ(slurp(scratch() / "a.rawlog"), slurp(scratch() / "b.rawlog"));
  EXPECT_EQ(slurp(scratch() / "a.gt.tum"), slurp(scratch() / "b.gt.tum"));
  o.params.seed = 99;
  o.out = (scratch() / "c.rawlog").string();
  runSimulate(o);
  EXPECT_NE(slurp(scratch() / "a.rawlog"), slurp(scratch() / "c.rawlog"));
  EXPECT_EQ(slurp(scratch() / "a.gt.tum"), slurp(scratch() / "c.gt.tum"));
}

TEST(SimJob, BadStartsAndOutputsAreInputErrors) {
  auto o = walker();
  o.out = (scratch() / "x.rawlog").string();
  o.start = Pose2{0.05, 4, 0};  // inside the west wall
  EXPECT_THROW(runSimulate(o), InputError);
  o.start = Pose2{100, 100, 0};
  EXPECT_THROW(runSimulate(o), InputError);
  o.start.reset();
  o.out = (scratch() / "x.txt").string();
  EXPECT_THROW(runSimulate(o), InputError);
  o.out = (scratch() / "no_such_dir" / "x.rawlog").string();
  EXPECT_THROW(runSimulate(o), InputError);
}

TEST(SimJob, ScriptTimesDurationAndOnePointPathsAreBounded) {
  const auto d = scratch();
  std::ofstream(d / "far.txt") << "0 0.2 0\n1e15 0 0\n";
  try {
    readCommandScript((d / "far.txt").string());
    ADD_FAILURE() << "a row at t = 1e15 was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("far.txt:2: time"), std::string::npos) << e.what();
  }
  auto o = walker();
  o.out = (d / "bounded.rawlog").string();
  o.duration = 1e12;
  EXPECT_THROW(runSimulate(o), InputError);
  o.duration = 0;
  o.path = {{1, 4}};
  EXPECT_THROW(runSimulate(o), InputError) << "one waypoint, no start: nothing to drive";
  EXPECT_FALSE(fs::exists(d / "bounded.rawlog.tmp"));
}
