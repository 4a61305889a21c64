// CARMEN log import: every message type from hand-written lines, bad input,
// and the real Intel and CSAIL logs read back through carenav's rawlog reader.
#include <carenav/io/carmen.h>
#include <carenav/io/rawlog_reader.h>
#include <carenav/io/trajectory.h>

#include <gtest/gtest.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

using namespace carenav;
using namespace carenav::io;
namespace fs = std::filesystem;
using mrpt::obs::CObservation2DRangeScan;
using mrpt::obs::CObservationOdometry;

namespace {
const std::string kTestData = CARENAV_TEST_DATA;
const double kDeg = M_PI / 180;

fs::path scratch() {
  auto d = fs::temp_directory_path() / ("carenav_carmen_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

std::string writeText(const std::string& name, const std::string& text) {
  const auto p = (scratch() / name).string();
  std::ofstream(p, std::ios::binary) << text;
  return p;
}

std::string writeGz(const std::string& name, const std::string& text) {
  const auto p = (scratch() / name).string();
  mrpt::io::CFileGZOutputStream f(p);
  f.Write(text.data(), text.size());
  return p;
}

/** "r r r ... r" (n times). */
std::string readings(size_t n, double r) {
  std::ostringstream o;
  for (size_t i = 0; i < n; ++i) o << (i ? " " : "") << r;
  return o.str();
}

std::string flaser(const std::string& ranges, size_t n, const std::string& pose,
                   const std::string& odom, const std::string& ts) {
  return "FLASER " + std::to_string(n) + " " + ranges + " " + pose + " " + odom + " " + ts +
         " host " + ts + "\n";
}

/** Runs the import into scratch()/name.rawlog. */
CarmenImportStats import(const std::string& input, const std::string& name,
                         CarmenOdometry odo = CarmenOdometry::Auto) {
  CarmenImportOptions o;
  o.input = input;
  o.output = (scratch() / (name + ".rawlog")).string();
  o.odometry = odo;
  return importCarmen(o);
}

std::vector<mrpt::obs::CObservation::Ptr> readBack(const std::string& rawlog) {
  std::vector<mrpt::obs::CObservation::Ptr> out;
  RawlogReader r(rawlog);
  RawlogEntry e;
  while (r.next(e)) {
    EXPECT_EQ(e.kind, EntryKind::Observation);
    out.push_back(e.observation);
  }
  return out;
}

/** UNIX seconds of a timestamp, exactly in 100 ns ticks. */
int64_t ticksSinceUnix(mrpt::Clock::time_point t) {
  return (t - mrpt::Clock::fromDouble(0)).count();
}

double sensorYaw(const CObservation2DRangeScan& s) { return s.sensorPose.yaw(); }

/** The message of the InputError thrown by importing `text`. */
std::string importError(const std::string& text, const std::string& name) {
  try {
    import(writeText(name + ".log", text), name);
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for " << name;
  return "";
}
}  // namespace

TEST(Carmen, OldFlaserFormat) {
  // 180 beams: CARMEN's readlog says 1 deg apart from -90 deg, so the last is
  // at +89 deg; the max range comes from PARAM robot_front_laser_max.
  std::string r = "0 1.5 50 60 -1 nan" + std::string(" ") + readings(174, 2.25);
  const std::string log =
      "# CARMEN Logfile\n"
      "PARAM robot_front_laser_max 50 1134863807.0 b21 1134863807.0\n" +
      flaser(r, 180, "1 2 0.5", "10 20 0.25", "1134863807.658747");
  const auto st = import(writeText("flaser.log", log), "flaser");
  EXPECT_EQ(st.totalScans(), 1u);
  EXPECT_EQ(st.scans.at("FLASER"), 1u);
  EXPECT_EQ(st.odometry, 1u);
  EXPECT_EQ(st.odometry_source, CarmenOdometry::Laser);
  EXPECT_EQ(st.lines, 3u);
  EXPECT_EQ(st.comments, 1u);
  EXPECT_EQ(st.params, 1u);
  const auto obs = readBack(st.output);
  ASSERT_EQ(obs.size(), 2u);
  // Odometry first, from the odom fields, at the scan's time.
  auto odo = std::dynamic_pointer_cast<CObservationOdometry>(obs[0]);
  ASSERT_TRUE(odo);
  EXPECT_EQ(odo->sensorLabel, "ODOMETRY");
  EXPECT_DOUBLE_EQ(odo->odometry.x(), 10);
  EXPECT_DOUBLE_EQ(odo->odometry.y(), 20);
  EXPECT_DOUBLE_EQ(odo->odometry.phi(), 0.25);
  EXPECT_FALSE(odo->hasVelocities);
  auto scan = std::dynamic_pointer_cast<CObservation2DRangeScan>(obs[1]);
  ASSERT_TRUE(scan);
  EXPECT_EQ(scan->sensorLabel, "FLASER");
  EXPECT_EQ(ticksSinceUnix(scan->timestamp), 11348638076587470);  // exact to 100 ns
  EXPECT_EQ(odo->timestamp, scan->timestamp);
  ASSERT_EQ(scan->getScanSize(), 180u);
  EXPECT_TRUE(scan->rightToLeft);
  EXPECT_NEAR(scan->aperture, 179 * kDeg, 1e-6);
  EXPECT_FLOAT_EQ(scan->maxRange, 50.f);
  EXPECT_NEAR(sensorYaw(*scan), -0.5 * kDeg, 1e-9);  // centre of [-90, +89] deg
  EXPECT_NEAR(scan->sensorPose.x(), 0, 1e-12);
  // First beam at -90 deg, last at +89 deg in the robot frame.
  EXPECT_NEAR(sensorYaw(*scan) + scan->getScanAngle(0), -90 * kDeg, 1e-6);
  EXPECT_NEAR(sensorYaw(*scan) + scan->getScanAngle(179), 89 * kDeg, 1e-6);
  EXPECT_FALSE(scan->getScanRangeValidity(0));  // 0
  EXPECT_TRUE(scan->getScanRangeValidity(1));
  EXPECT_FLOAT_EQ(scan->getScanRange(1), 1.5f);
  EXPECT_FALSE(scan->getScanRangeValidity(2));  // == max range
  EXPECT_FALSE(scan->getScanRangeValidity(3));  // beyond
  EXPECT_FALSE(scan->getScanRangeValidity(4));  // negative
  EXPECT_FALSE(scan->getScanRangeValidity(5));  // nan
  EXPECT_TRUE(scan->getScanRangeValidity(179));
  // TUM: the pose fields at the scan's time.
  const auto traj = readTum(st.tum);
  EXPECT_EQ(st.tum, (scratch() / "flaser.tum").string());
  ASSERT_EQ(traj.size(), 1u);
  EXPECT_NEAR(traj[0].t, 1134863807.658747, 1e-6);
  EXPECT_NEAR(traj[0].x, 1, 1e-6);
  EXPECT_NEAR(traj[0].y, 2, 1e-6);
  EXPECT_NEAR(traj[0].yaw, 0.5, 1e-6);
}

TEST(Carmen, OldLaserBeamCountsFollowCarmenReadlog) {
  struct Case {
    size_t n;
    double aperture_deg, yaw_deg;
  };
  for (const Case c : {Case{181, 180, 0}, Case{361, 180, 0}, Case{360, 179.5, -0.25},
                       Case{401, 100, -40}, Case{90, 180, 0}}) {
    SCOPED_TRACE(c.n);
    const auto st =
        import(writeText("n.log", flaser(readings(c.n, 3), c.n, "0 0 0", "0 0 0", "5.5")), "n");
    auto scan = std::dynamic_pointer_cast<CObservation2DRangeScan>(readBack(st.output).at(1));
    ASSERT_TRUE(scan);
    EXPECT_EQ(scan->getScanSize(), c.n);
    EXPECT_NEAR(scan->aperture, c.aperture_deg * kDeg, 1e-5);
    EXPECT_NEAR(sensorYaw(*scan), c.yaw_deg * kDeg, 1e-6);
    EXPECT_FLOAT_EQ(scan->maxRange, 80.f);  // CARMEN's default for old messages
  }
  // An unusual count takes PARAM laser_front_laser_resolution (deg).
  const auto st =
      import(writeText("res.log", "PARAM laser_front_laser_resolution 0.5 h 0\n" +
                                      flaser(readings(100, 3), 100, "0 0 0", "0 0 0", "5.5")),
             "res");
  auto scan = std::dynamic_pointer_cast<CObservation2DRangeScan>(readBack(st.output).at(1));
  EXPECT_NEAR(scan->aperture, 49.5 * kDeg, 1e-5);
}

TEST(Carmen, RearLaserFacesBackwardsAndAddsNoTumPose) {
  const std::string log =
      "PARAM robot_rearlaser_offset 0.3 h 0\nPARAM robot_rear_laser_max 20 h 0\n"
      "RLASER 181 " +
      readings(181, 4) + " 1 2 0.5 1 2 0.5 7.25 host 7.25\n" +
      flaser(readings(181, 4), 181, "1 2 0.5", "1 2 0.5", "7.5");
  const auto st = import(writeText("rlaser.log", log), "rlaser");
  EXPECT_EQ(st.scans.at("RLASER"), 1u);
  EXPECT_EQ(st.scans.at("FLASER"), 1u);
  EXPECT_EQ(st.odometry, 2u);
  const auto obs = readBack(st.output);
  ASSERT_EQ(obs.size(), 4u);
  auto rear = std::dynamic_pointer_cast<CObservation2DRangeScan>(obs[1]);
  ASSERT_TRUE(rear);
  EXPECT_EQ(rear->sensorLabel, "RLASER");
  EXPECT_NEAR(std::abs(sensorYaw(*rear)), M_PI, 1e-9);
  EXPECT_NEAR(rear->sensorPose.x(), -0.3, 1e-9);
  EXPECT_FLOAT_EQ(rear->maxRange, 20.f);
  EXPECT_EQ(readTum(st.tum).size(), 1u);  // the FLASER only
}

TEST(Carmen, RobotLaser1NewFormat) {
  // Robot at (1, 2) facing +y; the laser 0.2 m ahead of it, 5 beams from
  // -0.5 rad, 0.25 rad apart, 2 remissions.
  const std::string log =
      "ROBOTLASER1 0 -0.5 1.0 0.25 30 0.02 0 5 1 2 3 40 0 2 0.5 0.6 "
      "1 2.2 1.5707963267948966 1 2 1.5707963267948966 0.3 0.1 0.55 0.375 1000000 "
      "1234567890.1234567 host 1234567890.2\n";
  const auto st = import(writeText("robotlaser.log", log), "robotlaser");
  EXPECT_EQ(st.scans.at("ROBOTLASER1"), 1u);
  const auto obs = readBack(st.output);
  ASSERT_EQ(obs.size(), 2u);
  auto odo = std::dynamic_pointer_cast<CObservationOdometry>(obs[0]);
  ASSERT_TRUE(odo);
  EXPECT_NEAR(odo->odometry.x(), 1, 1e-12);
  EXPECT_NEAR(odo->odometry.phi(), M_PI / 2, 1e-12);
  EXPECT_TRUE(odo->hasVelocities);
  EXPECT_DOUBLE_EQ(odo->velocityLocal.vx, 0.3);
  EXPECT_DOUBLE_EQ(odo->velocityLocal.omega, 0.1);
  auto scan = std::dynamic_pointer_cast<CObservation2DRangeScan>(obs[1]);
  ASSERT_TRUE(scan);
  EXPECT_EQ(scan->sensorLabel, "ROBOTLASER1");
  EXPECT_EQ(ticksSinceUnix(scan->timestamp), 12345678901234567);
  EXPECT_NEAR(scan->aperture, 1.0, 1e-6);
  EXPECT_FLOAT_EQ(scan->maxRange, 30.f);
  EXPECT_FLOAT_EQ(scan->stdError, 0.02f);
  EXPECT_NEAR(scan->sensorPose.x(), 0.2, 1e-9);  // laser_pose relative to robot_pose
  EXPECT_NEAR(scan->sensorPose.y(), 0, 1e-9);
  EXPECT_NEAR(sensorYaw(*scan), 0.0, 1e-9);  // -0.5 + 1.0 / 2
  EXPECT_TRUE(scan->getScanRangeValidity(2));
  EXPECT_FALSE(scan->getScanRangeValidity(3));  // 40 >= 30
  EXPECT_FALSE(scan->getScanRangeValidity(4));  // 0
  const auto traj = readTum(st.tum);
  ASSERT_EQ(traj.size(), 1u);
  EXPECT_NEAR(traj[0].x, 1, 1e-6);
  EXPECT_NEAR(traj[0].y, 2, 1e-6);
  EXPECT_NEAR(traj[0].yaw, M_PI / 2, 1e-6);
}

TEST(Carmen, RawLaserAndOdomLines) {
  // RAWLASER carries no pose: auto takes the odometry from the ODOM lines.
  const std::string log =
      "ODOM 0 0 0 0 0 0 100.0 host 100.0\n"
      "RAWLASER1 0 -1.0 0.04 0.01 8 0.01 0 5 1 1 1 1 1 0 100.05 host 100.05\n"
      "RAWLASER2 0 -1.0 0.04 0.01 8 0.01 0 5 1 1 1 1 1 5 1 1 1 1 1 100.07 host 100.07\n"
      "ODOM 0.5 0.1 0.2 0.4 0.05 0 100.1 host 100.1\n";
  const auto st = import(writeText("raw.log", log), "raw");
  EXPECT_EQ(st.odometry_source, CarmenOdometry::Odom);
  EXPECT_EQ(st.scans.at("RAWLASER1"), 1u);
  EXPECT_EQ(st.scans.at("RAWLASER2"), 1u);
  EXPECT_EQ(st.odometry, 2u);
  EXPECT_TRUE(st.tum.empty());  // no pose to write
  EXPECT_FALSE(fs::exists(scratch() / "raw.tum"));
  const auto obs = readBack(st.output);
  ASSERT_EQ(obs.size(), 4u);
  auto scan = std::dynamic_pointer_cast<CObservation2DRangeScan>(obs[1]);
  ASSERT_TRUE(scan);
  EXPECT_EQ(scan->sensorLabel, "RAWLASER1");
  EXPECT_NEAR(scan->aperture, 0.04, 1e-6);
  EXPECT_NEAR(sensorYaw(*scan), -0.98, 1e-9);
  auto odo = std::dynamic_pointer_cast<CObservationOdometry>(obs[3]);
  ASSERT_TRUE(odo);
  EXPECT_NEAR(odo->odometry.x(), 0.5, 1e-12);
  EXPECT_TRUE(odo->hasVelocities);
  EXPECT_DOUBLE_EQ(odo->velocityLocal.vx, 0.4);
  EXPECT_DOUBLE_EQ(odo->velocityLocal.omega, 0.05);
  EXPECT_NEAR(mrpt::Clock::toDouble(odo->timestamp), 100.1, 1e-9);
}

TEST(Carmen, OdometrySourceChoices) {
  const std::string log = "ODOM 9 9 0 0 0 0 1.0 h 1.0\n" +
                          flaser(readings(180, 2), 180, "1 1 0", "2 2 0", "1.5") +
                          "ODOM 9 9 0 0 0 0 2.0 h 2.0\n";
  const auto in = writeText("choice.log", log);
  auto a = import(in, "auto");
  EXPECT_EQ(a.odometry_source, CarmenOdometry::Laser);
  EXPECT_EQ(a.odometry, 1u);
  EXPECT_EQ(a.unused.at("ODOM"), 2u);
  auto o = import(in, "odom", CarmenOdometry::Odom);
  EXPECT_EQ(o.odometry, 2u);
  EXPECT_TRUE(o.unused.empty());
  const auto obs = readBack(o.output);
  ASSERT_EQ(obs.size(), 3u);
  EXPECT_NEAR(std::dynamic_pointer_cast<CObservationOdometry>(obs[0])->odometry.x(), 9, 1e-12);
  auto n = import(in, "none", CarmenOdometry::None);
  EXPECT_EQ(n.odometry, 0u);
  EXPECT_EQ(readBack(n.output).size(), 1u);
  EXPECT_EQ(parseCarmenOdometry("odom"), CarmenOdometry::Odom);
  EXPECT_THROW(parseCarmenOdometry("wheels"), InputError);
}

TEST(Carmen, UnknownTypesCommentsBlankLinesAndCrlf) {
  const std::string log = "# comment\r\n\r\n   \nNEFF 15\r\nTRUEPOS 1 2 3 4 5 6 1.0 h 1.0\r\n" +
                          flaser(readings(180, 2), 180, "0 0 0", "0 0 0", "3.0") + "NEFF 16\n" +
                          "SYNC tag 4.0 h 4.0";  // a last line without '\n' is fine
  const auto st = import(writeText("unknown.log", log), "unknown");
  EXPECT_EQ(st.unknown.at("NEFF"), 2u);
  EXPECT_EQ(st.unknown.at("TRUEPOS"), 1u);
  EXPECT_EQ(st.unknown.at("SYNC"), 1u);
  EXPECT_EQ(st.totalUnknown(), 4u);
  EXPECT_EQ(st.comments, 1u);
  EXPECT_EQ(st.totalScans(), 1u);
  EXPECT_NE(st.notesText().find("skipped 2 NEFF lines"), std::string::npos) << st.notesText();
}

TEST(Carmen, TimestampsKeptExactlyAndDisorderCounted) {
  const std::string log = flaser(readings(180, 2), 180, "0 0 0", "0 0 0", "1134863807.000001") +
                          flaser(readings(180, 2), 180, "1 0 0", "1 0 0", "1134863806.5") +
                          flaser(readings(180, 2), 180, "2 0 0", "2 0 0", "1134863806.5") +
                          flaser(readings(180, 2), 180, "3 0 0", "3 0 0", "1.13487e+09");
  const auto st = import(writeText("times.log", log), "times", CarmenOdometry::None);
  EXPECT_EQ(st.scans_time_backwards, 1u);
  EXPECT_EQ(st.scans_time_repeated, 1u);
  const auto obs = readBack(st.output);
  ASSERT_EQ(obs.size(), 4u);
  EXPECT_EQ(ticksSinceUnix(obs[0]->timestamp), 11348638070000010);
  EXPECT_EQ(ticksSinceUnix(obs[1]->timestamp), 11348638065000000);
  EXPECT_NEAR(mrpt::Clock::toDouble(obs[3]->timestamp), 1134870000.0, 1e-6);
  EXPECT_DOUBLE_EQ(st.first_time, 1134863807.000001);
  EXPECT_DOUBLE_EQ(st.min_time, 1134863806.5);
  EXPECT_DOUBLE_EQ(st.max_time, 1134870000.0);
  // Rawlog in file order; TUM sorted by time (stable), so TUM readers take it.
  const auto traj = readTum(st.tum);
  ASSERT_EQ(traj.size(), 4u);
  EXPECT_NEAR(traj[0].x, 1, 1e-9);
  EXPECT_NEAR(traj[1].x, 2, 1e-9);
  EXPECT_NEAR(traj[2].x, 0, 1e-9);
  EXPECT_NEAR(traj[3].x, 3, 1e-9);
}

TEST(Carmen, MalformedLineStopsButKeepsWhatCameBefore) {
  const std::string good =
      flaser(readings(180, 2), 180, "1 2 3", "1 2 3", "10.0") + "ODOM 1 2 3 0 0 0 10.5 h 10.5\n";
  struct Case {
    std::string name, line, type, expect;
  };
  const std::vector<Case> cases = {
      {"few", "FLASER 180 1 2 3 4 5 6 7 8 9 10\n", "FLASER", "num_readings is 180 but"},
      {"count", flaser(readings(179, 2), 180, "0 0 0", "0 0 0", "11.0"), "FLASER",
       "expected 191 fields"},
      {"nonnum", flaser("abc " + readings(179, 2), 180, "0 0 0", "0 0 0", "11.0"), "FLASER",
       "reading 0 is not a number: 'abc'"},
      {"negative", "FLASER -3 1 2 3\n", "FLASER", "num_readings is negative"},
      {"fraction", "FLASER 1.5 1 2 3\n", "FLASER", "num_readings is not an integer"},
      {"pose", flaser(readings(180, 2), 180, "0 nan 0", "0 0 0", "11.0"), "FLASER",
       "y is not a finite number"},
      {"stamp", flaser(readings(180, 2), 180, "0 0 0", "0 0 0", "x11"), "FLASER",
       "ipc_timestamp is not a number"},
      {"odom", "ODOM 1 2 3 0 0 11.0 h 11.0\n", "ODOM", "expected 10 fields"},
      {"rawrem", "RAWLASER1 0 -1 0.04 0.01 8 0.01 0 2 1 1 3 1 1 11.0 h 11.0\n", "RAWLASER1",
       "expected 18 fields"},
      {"rawnocount", "RAWLASER1 0 -1 0.04 0.01 8\n", "RAWLASER1", "no num_readings"},
      {"robotold", "ROBOTLASER1 0 -1 0.04 0.01 8 0.01 0 2 1 1 0 0 0 0 0 0 0 0 0 0 0 11.0 h 11.0\n",
       "ROBOTLASER1", "expected 26 fields"},
      {"wide", "RAWLASER1 0 -1 7 1 8 0.01 0 8 1 1 1 1 1 1 1 1 0 11.0 h 11.0\n", "RAWLASER1",
       "span more than 360 deg"},
      {"param", "PARAM robot_front_laser_max lots 1 h 1\n", "PARAM",
       "robot_front_laser_max is not a number"},
      // Finite but absurd numbers (corrupt data): refused with the field named.
      {"hugex", flaser(readings(180, 2), 180, "1e300 0 0", "0 0 0", "11.0"), "FLASER",
       "x is 1e300 m, beyond +-1e+07 m"},
      {"hugeodomtheta", flaser(readings(180, 2), 180, "0 0 0", "0 0 -1e300", "11.0"), "FLASER",
       "odom_theta is -1e300 rad"},
      {"hugetime", flaser(readings(180, 2), 180, "0 0 0", "0 0 0", "1e300"), "FLASER",
       "ipc_timestamp is 1e300 s, beyond +-1e+10 s"},
      {"longtime", flaser(readings(180, 2), 180, "0 0 0", "0 0 0", "999999999999.5"), "FLASER",
       "ipc_timestamp is 999999999999.5 s"},
      {"hugeodom", "ODOM 1e300 2 3 0 0 0 11.0 h 11.0\n", "ODOM", "x is 1e300 m"},
      {"hugetv", "ODOM 1 2 3 1e300 0 0 11.0 h 11.0\n", "ODOM", "tv is 1e300"},
      {"hugemaxrange", "RAWLASER1 0 -1 0.04 0.01 1e300 0.01 0 2 1 1 0 11.0 h 11.0\n", "RAWLASER1",
       "maximum_range is 1e300 m"},
      {"hugestart", "RAWLASER1 0 1e300 0.04 0.01 8 0.01 0 2 1 1 0 11.0 h 11.0\n", "RAWLASER1",
       "start_angle is 1e300 rad"},
      {"hugerobot",
       "ROBOTLASER1 0 -1 0.04 0.01 8 0.01 0 2 1 1 0 0 0 0 1e300 0 0 0 0 0 0 0 11.0 h 11.0\n",
       "ROBOTLASER1", "robot_pose_x is 1e300 m"},
      {"hugeparam", "PARAM robot_front_laser_max 1e300 1 h 1\n", "PARAM",
       "robot_front_laser_max is 1e300"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string in = writeText("bad_" + c.name + ".log", good + c.line + good);
    CarmenImportOptions o;
    o.input = in;
    o.output = (scratch() / ("bad_" + c.name + ".rawlog")).string();
    try {
      importCarmen(o);
      ADD_FAILURE() << "no error";
    } catch (const CarmenImportError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(in + ":3: " + c.type + ": ", 0), 0u) << what;
      EXPECT_NE(what.find(c.expect), std::string::npos) << what;
      EXPECT_NE(what.find("the 2 lines before it were converted"), std::string::npos) << what;
      // Nothing lost: the good lines are in the rawlog and the TUM file.
      EXPECT_EQ(e.stats.observations, 2u);
      EXPECT_EQ(readBack(o.output).size(), 2u);
      EXPECT_EQ(readTum(defaultTumPath(o.output)).size(), 1u);
      EXPECT_FALSE(fs::exists(o.output + ".tmp"));
    }
  }
}

TEST(Carmen, NonFiniteReadingsAreInvalidBeamsCountedWithAWarning) {
  // nan, inf and negative readings: the scan is kept, those beams are
  // invalid, and the import says how many and where the first was. A 1e300
  // reading is beyond the maximum range: an ordinary invalid beam.
  std::string bad = "nan inf -1 1e300 " + readings(176, 2);
  const std::string text = flaser(readings(180, 2), 180, "0 0 0", "0 0 0", "10.0") +
                           flaser(bad, 180, "0 0 0", "0 0 0", "10.1") +
                           flaser("NaN " + readings(179, 2), 180, "0 0 0", "0 0 0", "10.2");
  const auto in = writeText("nanranges.log", text);
  const auto st = import(in, "nanranges");
  EXPECT_EQ(st.totalScans(), 3u);
  EXPECT_EQ(st.bad_readings, 4u);
  EXPECT_EQ(st.scans_with_bad_readings, 2u);
  EXPECT_EQ(st.first_bad_reading_line, 2u);
  EXPECT_NE(st.notesText().find("warning: 4 reading(s) in 2 scan(s) are nan, inf or negative "
                                "(first at line 2)"),
            std::string::npos)
      << st.notesText();
  EXPECT_NE(st.toJson().find("\"bad_readings\": 4"), std::string::npos);
  const auto obs = readBack((scratch() / "nanranges.rawlog").string());
  size_t scans = 0;
  for (const auto& o : obs) {
    const auto s = std::dynamic_pointer_cast<CObservation2DRangeScan>(o);
    if (!s) continue;
    ++scans;
    for (size_t i = 0; i < s->getScanSize(); ++i) {
      EXPECT_TRUE(std::isfinite(s->getScanRange(i))) << i;
      EXPECT_LE(s->getScanRange(i), s->maxRange);
    }
    if (scans == 2)
      for (size_t i = 0; i < 4; ++i) EXPECT_FALSE(s->getScanRangeValidity(i)) << i;
  }
  EXPECT_EQ(scans, 3u);
  // A clean log has no warning.
  const auto clean = import(
      writeText("clean.log", flaser(readings(180, 2), 180, "0 0 0", "0 0 0", "10.0")), "clean");
  EXPECT_EQ(clean.bad_readings, 0u);
  EXPECT_EQ(clean.notesText().find("warning"), std::string::npos);
}

TEST(Carmen, BadFirstLineWritesNothing) {
  const auto out = scratch() / "badfirst.rawlog";
  const std::string what = importError("FLASER 180 1 2\n", "badfirst");
  EXPECT_NE(what.find("badfirst.log:1: FLASER: "), std::string::npos) << what;
  EXPECT_NE(what.find("nothing was converted"), std::string::npos) << what;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_FALSE(fs::exists(scratch() / "badfirst.tum"));
}

TEST(Carmen, TruncatedLastLine) {
  std::string log = flaser(readings(180, 2), 180, "0 0 0", "0 0 0", "1.0") +
                    flaser(readings(180, 2), 180, "1 0 0", "1 0 0", "2.0");
  log = log.substr(0, log.size() - 200);  // a logger killed mid-line
  CarmenImportOptions o;
  o.input = writeText("cut.log", log);
  o.output = (scratch() / "cut.rawlog").string();
  try {
    importCarmen(o);
    ADD_FAILURE() << "no error";
  } catch (const CarmenImportError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("cut.log:2: FLASER: the file ends in the middle of this line"),
              std::string::npos)
        << what;
    EXPECT_EQ(e.stats.totalScans(), 1u);
    EXPECT_EQ(readBack(o.output).size(), 2u);
  }
}

TEST(Carmen, LogCutInsideTheLastMessageName) {
  const std::string good = flaser(readings(180, 2), 180, "0 0 0", "0 0 0", "1.0");
  const std::string what = importError(good + "FLAS", "cutname");
  EXPECT_NE(what.find("cutname.log:2: FLAS: the file ends in the middle of this line"),
            std::string::npos)
      << what;
  // A complete unknown last message without end of line is just skipped.
  EXPECT_EQ(import(writeText("lastneff.log", good + "NEFF 3"), "lastneff").unknown.at("NEFF"), 1u);
}

TEST(Carmen, MissingEmptyAndUselessInputs) {
  EXPECT_NE(importError("", "empty").find("empty file"), std::string::npos);
  EXPECT_FALSE(fs::exists(scratch() / "empty.rawlog"));
  const std::string useless = importError("# hello\nPARAM a b\nNEFF 3\n", "useless");
  EXPECT_NE(useless.find("nothing to convert"), std::string::npos) << useless;
  EXPECT_NE(useless.find("NEFF 1"), std::string::npos) << useless;
  EXPECT_FALSE(fs::exists(scratch() / "useless.rawlog"));
  CarmenImportOptions o;
  o.input = (scratch() / "no_such.log").string();
  o.output = (scratch() / "no_such.rawlog").string();
  try {
    importCarmen(o);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no_such.log: CARMEN log not found"), std::string::npos);
  }
  const std::string bin = importError(std::string("FLASER\0\0\0 1 2", 13) + "\n", "binary");
  EXPECT_NE(bin.find("binary data"), std::string::npos) << bin;
  // An output directory that does not exist is bad usage too.
  o.input = writeText("ok.log", flaser(readings(180, 2), 180, "0 0 0", "0 0 0", "1.0"));
  o.output = (scratch() / "no_dir" / "x.rawlog").string();
  EXPECT_THROW(importCarmen(o), InputError);
  // Writing over the input is refused, and so is a TUM path nobody can write.
  o.output = o.input;
  EXPECT_THROW(importCarmen(o), InputError);
  o.output = (scratch() / "ok.rawlog").string();
  o.tum = o.input;
  EXPECT_THROW(importCarmen(o), InputError);
  o.tum = (scratch() / "no_dir" / "x.tum").string();
  EXPECT_THROW(importCarmen(o), InputError);
  EXPECT_FALSE(fs::exists(o.output));
}

TEST(Carmen, GzipInputTruncatedAndCorrupt) {
  std::string log;
  for (int i = 0; i < 400; ++i)
    log += flaser(readings(180, 1 + i % 7), 180, std::to_string(i) + " 0 0", "0 0 0",
                  std::to_string(100 + i) + ".25");
  const auto gz = writeGz("log.gz", log);
  const auto st = import(gz, "gz");
  EXPECT_EQ(st.totalScans(), 400u);
  EXPECT_EQ(readTum(st.tum).size(), 400u);
  // Cut the compressed file: the conversion stops, naming the file.
  std::string bytes;
  {
    std::ifstream f(gz, std::ios::binary);
    std::stringstream ss;
    ss << f.rdbuf();
    bytes = ss.str();
  }
  const auto cut = writeText("cut.gz", bytes.substr(0, bytes.size() / 2));
  CarmenImportOptions o;
  o.input = cut;
  o.output = (scratch() / "cutgz.rawlog").string();
  try {
    importCarmen(o);
    ADD_FAILURE() << "no error";
  } catch (const CarmenImportError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(cut + ":", 0), 0u) << what;
    EXPECT_TRUE(what.find("truncated") != std::string::npos) << what;
    EXPECT_GT(e.stats.totalScans(), 10u);
    EXPECT_LT(e.stats.totalScans(), 400u);
    EXPECT_EQ(readBack(o.output).size(), e.stats.observations);
  }
  // A gzip header followed by garbage: an error, not a hang.
  const auto bad = writeText("bad.gz", std::string("\x1f\x8b\x08") + std::string(5000, 'x'));
  EXPECT_THROW(import(bad, "badgz"), InputError);
}

TEST(Carmen, DefaultTumPath) {
  EXPECT_EQ(defaultTumPath("a/x.rawlog"), "a/x.tum");
  EXPECT_EQ(defaultTumPath("x.rawlog.gz"), "x.tum");
  EXPECT_EQ(defaultTumPath("x.gz"), "x.tum");
  EXPECT_EQ(defaultTumPath("x"), "x.tum");
}

// ---------------------------------------------------------------------------
// The real logs: counted and parsed here independently of the importer.

namespace {
struct LaserLine {
  double t, x, y, theta;
};
std::vector<LaserLine> flaserLines(const std::string& gz) {
  mrpt::io::CFileGZInputStream in(gz);
  std::string text;
  char buf[65536];
  size_t n;
  while ((n = in.Read(buf, sizeof buf)) > 0 && n <= sizeof buf) text.append(buf, n);
  std::vector<LaserLine> out;
  std::istringstream is(text);
  std::string line;
  while (std::getline(is, line)) {
    if (line.rfind("FLASER ", 0) != 0) continue;
    std::istringstream ls(line);
    std::vector<std::string> f;
    std::string w;
    while (ls >> w) f.push_back(w);
    const size_t k = f.size();
    out.push_back(
        {std::stod(f[k - 3]), std::stod(f[k - 9]), std::stod(f[k - 8]), std::stod(f[k - 7])});
  }
  return out;
}

void checkRealLog(const std::string& name, size_t expected_scans, size_t beams) {
  const std::string path = kTestData + "/carmen/" + name;
  ASSERT_TRUE(fs::exists(path)) << path;
  const auto lines = flaserLines(path);
  ASSERT_EQ(lines.size(), expected_scans);
  const auto st = import(path, name);
  EXPECT_EQ(st.scans.at("FLASER"), lines.size());
  EXPECT_EQ(st.odometry, lines.size());
  size_t scans = 0;
  double first = -1, last = -1;
  RawlogReader r(st.output);
  RawlogEntry e;
  while (r.next(e)) {
    auto s = std::dynamic_pointer_cast<CObservation2DRangeScan>(e.observation);
    if (!s) continue;
    EXPECT_EQ(s->getScanSize(), beams);
    const double t = mrpt::Clock::toDouble(s->timestamp);
    if (first < 0) first = t;
    last = t;
    ++scans;
  }
  EXPECT_EQ(scans, lines.size());
  EXPECT_NEAR(first, lines.front().t, 1e-6);
  EXPECT_NEAR(last, lines.back().t, 1e-6);
  // TUM: one pose per laser line, the pose fields, sorted by time.
  const auto traj = readTum(st.tum);
  ASSERT_EQ(traj.size(), lines.size());
  auto sorted = lines;
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](const LaserLine& a, const LaserLine& b) { return a.t < b.t; });
  for (size_t i = 0; i < traj.size(); ++i) {
    EXPECT_NEAR(traj[i].t, sorted[i].t, 1e-6);
    EXPECT_NEAR(traj[i].x, sorted[i].x, 1e-6);
    EXPECT_NEAR(traj[i].y, sorted[i].y, 1e-6);
    EXPECT_NEAR(std::remainder(traj[i].yaw - sorted[i].theta, 2 * M_PI), 0, 1e-6);
  }
}
}  // namespace

TEST(CarmenReal, IntelCorrected) { checkRealLog("intel-corrected.log.gz", 910, 180); }

TEST(CarmenReal, CsailCorrected) { checkRealLog("csail-corrected.log.gz", 406, 361); }

namespace {
/** The odometry poses of the Intel log imported with noise `seed` (none: -1). */
std::vector<mrpt::poses::CPose2D> intelOdometry(int seed, CarmenImportStats* stats = nullptr) {
  CarmenImportOptions o;
  o.input = kTestData + "/carmen/intel-corrected.log.gz";
  o.output = (scratch() / ("intel_noise" + std::to_string(seed) + ".rawlog")).string();
  o.write_tum = false;
  if (seed >= 0) {
    OdometryNoiseParams n;
    n.seed = static_cast<uint64_t>(seed);
    o.odometry_noise = n;
  }
  const CarmenImportStats st = importCarmen(o);
  if (stats) *stats = st;
  std::vector<mrpt::poses::CPose2D> out;
  for (const auto& obs : readBack(o.output))
    if (auto odo = std::dynamic_pointer_cast<CObservationOdometry>(obs))
      out.push_back(odo->odometry);
  return out;
}
}  // namespace

TEST(Carmen, OdometryNoiseIsSeededAndFollowsItsModel) {
  CarmenImportStats st;
  const auto clean = intelOdometry(-1);
  const auto a = intelOdometry(1, &st);
  const auto again = intelOdometry(1);
  const auto b = intelOdometry(2);
  ASSERT_EQ(a.size(), clean.size());
  ASSERT_GT(a.size(), 900u);
  ASSERT_TRUE(st.odometry_noise.has_value());
  EXPECT_NE(st.toText().find("noise seed 1"), std::string::npos);
  EXPECT_NE(st.toJson().find("\"odometry_noise\""), std::string::npos);
  // Same seed, same noise; another seed, other noise; the first pose is the origin.
  for (size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i], again[i]) << i;
  EXPECT_EQ(a[0], clean[0]);
  EXPECT_GT((a.back() - b.back()).norm(), 0.05);
  // Each step's length error over the log: about 5 % of the step (its std
  // dev), unbiased; heading errors about 1 deg per m and 2 % of the turn.
  double sum = 0, sum2 = 0, heading2 = 0, model2 = 0;
  size_t n = 0;
  for (size_t i = 1; i < a.size(); ++i) {
    const auto ref = clean[i] - clean[i - 1], noisy = a[i] - a[i - 1];
    const double d = ref.norm();
    if (d < 0.05) continue;
    const double rel = noisy.norm() / d - 1;
    sum += rel, sum2 += rel * rel, ++n;
    const double dh = std::remainder(noisy.phi() - ref.phi(), 2 * M_PI);
    heading2 += dh * dh;
    model2 += std::pow(1.0 * kDeg * d, 2) + std::pow(0.02 * ref.phi(), 2);
  }
  ASSERT_GT(n, 500u);
  EXPECT_NEAR(sum / n, 0.0, 0.01);
  EXPECT_NEAR(std::sqrt(sum2 / n), 0.05, 0.008);
  EXPECT_NEAR(std::sqrt(heading2 / model2), 1.0, 0.15);
}

TEST(Carmen, OdometryNoiseNeedsOdometry) {
  CarmenImportOptions o;
  o.input = kTestData + "/carmen/intel-corrected.log.gz";
  o.output = (scratch() / "noise_none.rawlog").string();
  o.odometry = CarmenOdometry::None;
  o.odometry_noise = OdometryNoiseParams{};
  EXPECT_THROW(importCarmen(o), InputError);
  EXPECT_FALSE(fs::exists(o.output));
  o.odometry = CarmenOdometry::Auto;
  o.odometry_noise->dist_frac = -1;
  EXPECT_THROW(importCarmen(o), InputError);
}

namespace {
/** 40 FLASER scans of 180 beams: 150 walls 1-9.9 m away and 30 beams of
 *  `far(scan, beam)`. */
template <class Far>
std::string roomLog(const std::string& params, Far far) {
  std::string log = params;
  for (int s = 0; s < 40; ++s) {
    std::ostringstream r;
    for (int i = 0; i < 180; ++i)
      r << (i ? " " : "") << (i < 150 ? 1 + 0.1 * ((i + s) % 90) : far(s, i));
    log += flaser(r.str(), 180, "0 0 0", "0 0 0", std::to_string(10 + s) + ".5");
  }
  return log;
}

/** Beam validity of every scan of the rawlog, and the scans' maxRange. */
std::vector<CObservation2DRangeScan::Ptr> scansOf(const CarmenImportStats& st) {
  std::vector<CObservation2DRangeScan::Ptr> out;
  for (const auto& o : readBack(st.output))
    if (auto s = std::dynamic_pointer_cast<CObservation2DRangeScan>(o)) out.push_back(s);
  return out;
}
}  // namespace

TEST(Carmen, NoReturnValuePiledAtTheTopIsInvalid) {
  // The far beams hit nothing: the scanner writes 51.15 m (a few 51.14).
  const auto st = import(
      writeText("noret.log", roomLog("", [](int s, int i) { return (s + i) % 7 ? 51.15 : 51.14; })),
      "noret");
  ASSERT_EQ(st.no_return.count("FLASER"), 1u);
  const NoReturnLevel& l = st.no_return.at("FLASER");
  EXPECT_NEAR(l.level, 51.14, 0.011);
  EXPECT_NEAR(l.limit, 0.97 * l.level, 0.02);
  EXPECT_EQ(l.piled, 40u * 30u);
  const auto scans = scansOf(st);
  ASSERT_EQ(scans.size(), 40u);
  for (const auto& s : scans) {
    EXPECT_NEAR(s->maxRange, l.limit, 1e-4);
    EXPECT_TRUE(s->getScanRangeValidity(149));
    for (int i = 150; i < 180; ++i) EXPECT_FALSE(s->getScanRangeValidity(i)) << i;
  }
  const std::string json = st.toJson();
  EXPECT_NE(json.find("\"limit_m\""), std::string::npos) << json;
  EXPECT_LT(json.find("\"no_return\""), json.find("\"limit_m\""));
  EXPECT_NE(st.notesText().find("no-return value"), std::string::npos);
}

TEST(Carmen, RealFarReturnsAreNotANoReturnValue) {
  // Far walls thinning out with range (20-51.2 m, one beam per 4 cm): the
  // top of the readings is no pile, every reading below 80 m stays valid.
  const auto st = import(
      writeText("far.log",
                roomLog("", [](int s, int i) { return 20 + 0.04 * ((s * 30 + i - 150) % 780); })),
      "far");
  EXPECT_TRUE(st.no_return.empty());
  for (const auto& s : scansOf(st)) {
    EXPECT_FLOAT_EQ(s->maxRange, 80.f);
    for (int i = 0; i < 180; ++i) EXPECT_TRUE(s->getScanRangeValidity(i)) << i;
  }
  // A repeated value with many readings beyond it is a wall, not a pile.
  const auto wall = import(
      writeText("wall.log",
                roomLog("", [](int s, int i) { return i < 160 ? 12.0 : 13 + 0.1 * (s + i); })),
      "wall");
  EXPECT_TRUE(wall.no_return.empty());
  // A log of one value is no room at all: nothing is taken as no return.
  const std::string flat = flaser(readings(180, 2), 180, "0 0 0", "0 0 0", "10.0");
  EXPECT_TRUE(import(writeText("flat.log", flat + flat), "flat").no_return.empty());
}

TEST(Carmen, NoReturnValueWinsOverTheRobotModulesRange) {
  // PARAM robot_front_laser_max is the range CARMEN's robot module used; a
  // log may state 10 m while its scanner measured to 50 m (the walls here are
  // up to 9.9 m, the no-return value 51.15 m).
  auto far = [](int, int) { return 51.15; };
  const std::string param = "PARAM robot_front_laser_max 5 1.0 h 1.0\n";
  const auto p = import(writeText("noret_param.log", roomLog(param, far)), "noret_param");
  ASSERT_EQ(p.no_return.count("FLASER"), 1u);
  EXPECT_DOUBLE_EQ(p.no_return.at("FLASER").param_max, 5);
  EXPECT_NE(p.notesText().find("not PARAM's 5 m"), std::string::npos) << p.notesText();
  for (const auto& s : scansOf(p)) {
    EXPECT_NEAR(s->maxRange, p.no_return.at("FLASER").limit, 1e-4);
    EXPECT_TRUE(s->getScanRangeValidity(100));  // beyond PARAM's 5 m
    EXPECT_FALSE(s->getScanRangeValidity(170));
  }
  // Without a pile PARAM stays the maximum range.
  const auto wall = import(
      writeText(
          "wall_param.log",
          roomLog(param, [](int s, int i) { return 20 + 0.04 * ((s * 30 + i - 150) % 780); })),
      "wall_param");
  EXPECT_TRUE(wall.no_return.empty());
  for (const auto& s : scansOf(wall)) EXPECT_FLOAT_EQ(s->maxRange, 5.f);
  // --max-range wins over both.
  CarmenImportOptions o;
  o.input = writeText("noret_opt.log", roomLog("", far));
  o.output = (scratch() / "noret_opt.rawlog").string();
  o.max_range = 70;
  const auto m = importCarmen(o);
  EXPECT_TRUE(m.no_return.empty());
  for (const auto& s : scansOf(m)) EXPECT_TRUE(s->getScanRangeValidity(170));
}
