// Bags as input: MRPT's SENA rawlog written as a bag through rosbag storage
// (odometry as nav_msgs/Odometry or tf) reads back through the rawlog reader
// as the same scans and odometry; a truncated or damaged bag stops with
// RawlogError naming the file and the byte, after what was before it.
#include <carenav/io/rawlog_reader.h>
#include <carenav/ros/bag.h>
#include <carenav/ros/nodes.h>

#include <mrpt/obs/CObservation2DRangeScan.h>

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace {

namespace fs = std::filesystem;
using carenav::io::RawlogEntry;
using carenav::io::RawlogError;
using carenav::io::RawlogReader;
using mrpt::obs::CObservation2DRangeScan;

const std::string kSena =
    std::string(CARENAV_MRPT_DATASETS) + "/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog";

fs::path scratch() {
  auto d = fs::temp_directory_path() / ("carenav_ros_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

/** The 2D scans of a log and the odometry summed up to each. */
struct Stream {
  std::vector<CObservation2DRangeScan::Ptr> scans;
  std::vector<mrpt::poses::CPose2D> odo;
  std::optional<std::string> error;
};

Stream readAll(const std::string& path) {
  carenav::ros::registerBagFormat();
  Stream s;
  RawlogReader r(path);
  RawlogEntry e;
  mrpt::poses::CPose2D odo;
  try {
    while (r.next(e)) {
      if (e.odometry_increment) odo = odo + *e.odometry_increment;
      for (const auto& o : e.observations())
        if (auto sc = std::dynamic_pointer_cast<CObservation2DRangeScan>(o)) {
          s.scans.push_back(sc);
          s.odo.push_back(odo);
        }
    }
  } catch (const RawlogError& err) {
    s.error = err.what();
  }
  return s;
}

std::string slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

void expectSame(const Stream& a, const Stream& b) {
  ASSERT_EQ(a.scans.size(), b.scans.size());
  for (size_t i = 0; i < a.scans.size(); ++i) {
    const auto &x = *a.scans[i], &y = *b.scans[i];
    ASSERT_EQ(x.getScanSize(), y.getScanSize()) << "scan " << i;
    // (a scan without a label gets the bag writer's frame "laser")
    EXPECT_EQ(x.sensorLabel.empty() ? "laser" : x.sensorLabel, y.sensorLabel);
    EXPECT_NEAR(x.aperture, y.aperture, 1e-5);
    EXPECT_EQ(x.rightToLeft, y.rightToLeft);
    EXPECT_NEAR(mrpt::Clock::toDouble(x.timestamp), mrpt::Clock::toDouble(y.timestamp), 1e-5);
    EXPECT_NEAR((x.sensorPose - y.sensorPose).norm(), 0, 1e-6);
    for (size_t k = 0; k < x.getScanSize(); ++k) {
      ASSERT_EQ(x.getScanRangeValidity(k), y.getScanRangeValidity(k)) << i << " " << k;
      if (x.getScanRangeValidity(k)) ASSERT_FLOAT_EQ(x.getScanRange(k), y.getScanRange(k));
    }
    EXPECT_NEAR(a.odo[i].distanceTo(b.odo[i]), 0, 1e-6) << "odometry at scan " << i;
    EXPECT_NEAR(std::remainder(a.odo[i].phi() - b.odo[i].phi(), 2 * M_PI), 0, 1e-6);
  }
}

TEST(RosBag, SenaAsBagReadsAsTheRawlog) {
  const auto bag = scratch() / "sena.bag";
  const size_t written = carenav::ros::writeBagFromRawlog(kSena, bag.string());
  const Stream ref = readAll(kSena), got = readAll(bag.string());
  EXPECT_FALSE(ref.error.has_value());
  EXPECT_FALSE(got.error.has_value()) << *got.error;
  EXPECT_EQ(written, ref.scans.size());
  EXPECT_GT(ref.scans.size(), 100u);
  expectSame(ref, got);
}

std::shared_ptr<carenav::ros::BagReadNotes> readNotes(const fs::path& bag,
                                                      const carenav::ros::BagReadOptions& o) {
  auto notes = std::make_shared<carenav::ros::BagReadNotes>();
  auto src = carenav::ros::openBag(bag.string(), o, notes);
  mrpt::obs::CObservation::Ptr obs;
  while (src->next(obs)) {
  }
  return notes;
}

TEST(RosBag, OdometryFromTf) {
  const auto bag = scratch() / "sena_tf.bag";
  carenav::ros::BagWriteOptions w;
  w.odom_topic = "/wheel_odom";
  w.tf_odometry = true;
  carenav::ros::writeBagFromRawlog(kSena, bag.string(), w);
  carenav::ros::BagReadOptions o;
  o.odom = "tf";
  const auto tf = readNotes(bag, o);
  o.odom = "/wheel_odom";
  const auto topic = readNotes(bag, o);
  const Stream ref = readAll(kSena);
  EXPECT_EQ(tf->scans, ref.scans.size());
  EXPECT_GT(tf->odometry, ref.scans.size() / 2);
  EXPECT_EQ(tf->odometry, topic->odometry);
  EXPECT_EQ(tf->topics.at("/wheel_odom"), "nav_msgs/Odometry");
  EXPECT_EQ(tf->scans_no_tf, 0u);
}

TEST(RosBag, TruncatedBagKeepsWhatWasRead) {
  const auto dir = scratch();
  const auto bag = dir / "whole.bag";
  carenav::ros::BagWriteOptions w;
  w.chunk_bytes = 64 * 1024;  // several chunks: the cut falls after some
  carenav::ros::writeBagFromRawlog(kSena, bag.string(), w);
  const std::string bytes = slurp(bag);
  const auto cut = dir / "cut.bag";
  std::ofstream(cut, std::ios::binary) << bytes.substr(0, bytes.size() * 6 / 10);
  const Stream s = readAll(cut.string());
  ASSERT_TRUE(s.error.has_value()) << "a truncated bag must not read as complete";
  EXPECT_NE(s.error->find(cut.string()), std::string::npos) << *s.error;
  EXPECT_NE(s.error->find("byte "), std::string::npos) << *s.error;
  EXPECT_NE(s.error->find("truncated"), std::string::npos) << *s.error;
  EXPECT_GT(s.scans.size(), 0u) << "the chunks before the cut are read";
}

TEST(RosBag, DamagedBagsAreRawlogErrors) {
  const auto dir = scratch();
  const auto bag = dir / "whole.bag";
  carenav::ros::writeBagFromRawlog(kSena, bag.string());
  const std::string bytes = slurp(bag);
  // A message record's header field length garbled in the middle of the
  // file, and a bag that is not one.
  std::string bad = bytes;
  const size_t op = bad.find(std::string("op=\x02", 4), bad.size() / 2);
  ASSERT_NE(op, std::string::npos);
  for (size_t i = op - 4; i < op; ++i) bad[i] = static_cast<char>(0xff);
  const auto damaged = dir / "damaged.bag";
  std::ofstream(damaged, std::ios::binary) << bad;
  const Stream s = readAll(damaged.string());
  ASSERT_TRUE(s.error.has_value());
  EXPECT_NE(s.error->find(damaged.string()), std::string::npos) << *s.error;
  EXPECT_NE(s.error->find("corrupt"), std::string::npos) << *s.error;
  EXPECT_GT(s.scans.size(), 0u);
  const auto notbag = dir / "not.bag";
  std::ofstream(notbag, std::ios::binary) << "#ROSBAG V1.2\nhello";
  carenav::ros::registerBagFormat();
  try {
    RawlogReader r(notbag.string());
    FAIL() << "not a bag of format 2.0 was opened";
  } catch (const carenav::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not a ROS bag of format 2.0"), std::string::npos)
        << e.what();
  }
}

}  // namespace

namespace {
// ~ parameters as profile keys (nodes.h): every '/' but the last is a '.'.
TEST(RosParams, PrivateParametersBecomeProfileOverrides) {
  using carenav::ros::overrideFromParam;
  EXPECT_EQ(overrideFromParam("navigation/v_max", "0.3"), "navigation.v_max=0.3");
  EXPECT_EQ(overrideFromParam("sensor/laser/x", "0.1"), "sensor.laser.x=0.1");
  EXPECT_EQ(overrideFromParam("nav/recovery/enabled", "false"), "nav.recovery.enabled=false");
  EXPECT_EQ(overrideFromParam("v_max", "1"), "");
}
}  // namespace
