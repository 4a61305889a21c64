// Bags as input through the binary: a bag written from MRPT's SENA rawlog
// (rosbag storage) imports to a rawlog with the same scans, and maps with
// `carenav slam --rawlog X.bag` to the same trajectory as the rawlog; a
// truncated bag gives exit 2 naming the file and the byte, keeping what was
// read. Without the ROS part these skip; a `.bag` then says so (exit 2).
#include "cli_helpers.h"

#ifdef CARENAV_TEST_WITH_ROS
#include <carenav/ros/bag.h>
#endif

namespace {

using namespace carenav_test;

#ifdef CARENAV_TEST_WITH_ROS
/** SENA as a bag, in several chunks (so a cut keeps the ones before it). */
fs::path senaBag() {
  const auto bag = scratch() / "sena_cli.bag";
  carenav::ros::BagWriteOptions w;
  w.chunk_bytes = 64 * 1024;
  carenav::ros::writeBagFromRawlog(kSena, bag.string(), w);
  return bag;
}
#define SKIP_WITHOUT_ROS()
#else
#define SKIP_WITHOUT_ROS() GTEST_SKIP() << "built without the ROS part (CARENAV_WITH_ROS=OFF)"
#endif

TEST(CliRosbag, BagWithoutRosPartIsExitTwo) {
#ifdef CARENAV_TEST_WITH_ROS
  GTEST_SKIP() << "built with the ROS part: bags are read (the other CliRosbag tests)";
#else
  const auto bag = scratch() / "any.bag";
  std::ofstream(bag) << "#ROSBAG V2.0\n";
  const auto r = carenav_test::carenav({"rawlog", "info", bag.string()});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("built without its ROS part"), std::string::npos) << r.err;
#endif
}

TEST(CliRosbag, ImportGivesTheRawlogsScans) {
  SKIP_WITHOUT_ROS();
#ifdef CARENAV_TEST_WITH_ROS
  const auto bag = senaBag();
  const auto out = scratch() / "sena_from_bag.rawlog";
  const auto r = carenav_test::carenav(
      {"-q", "import", "rosbag", bag.string(), "--out", out.string(), "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(jsonNumber(r.out, "scans"), 225u) << r.out;
  const auto ref = carenav_test::carenav({"rawlog", "info", "--json", kSena});
  const auto got = carenav_test::carenav({"rawlog", "info", "--json", out.string()});
  const auto direct = carenav_test::carenav({"rawlog", "info", "--json", bag.string()});
  ASSERT_EQ(got.code, 0) << got.err;
  ASSERT_EQ(direct.code, 0) << direct.err;
  EXPECT_NE(got.out.find("\"count\": 225"), std::string::npos) << got.out;
  EXPECT_NE(direct.out.find("\"count\": 225"), std::string::npos) << direct.out;
  EXPECT_NE(ref.out.find("\"count\": 225"), std::string::npos) << ref.out;
#endif
}

TEST(CliRosbag, SlamOnTheBagMapsAsOnTheRawlog) {
  SKIP_WITHOUT_ROS();
#ifdef CARENAV_TEST_WITH_ROS
  const auto bag = senaBag();
  const auto a = scratch() / "slam_rawlog", b = scratch() / "slam_bag";
  const std::string profile = kSrc + "/ini/defaults.ini";
  auto r = carenav_test::carenav(
      {"-q", "slam", "--profile", profile, "--rawlog", kSena, "--out", a.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  r = carenav_test::carenav(
      {"-q", "slam", "--profile", profile, "--rawlog", bag.string(), "--out", b.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto e = carenav_test::carenav({"-q", "eval", "--est", (b / "trajectory.tum").string(),
                                        "--ref", (a / "trajectory.tum").string(), "--out",
                                        (scratch() / "slam_eval").string()});
  ASSERT_EQ(e.code, 0) << e.err;
  const std::string ev = slurp(scratch() / "slam_eval" / "eval.json");
  EXPECT_NE(ev.find("\"matched\": 225"), std::string::npos) << ev;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(
      ev, m, std::regex("\"translation_m\": \\{\\s*\"n\": 225,\\s*\"rmse\": ([0-9.e-]+)")))
      << ev;
  EXPECT_LT(std::stod(m[1]), 0.01) << "the bag maps as the rawlog does";
#endif
}

TEST(CliRosbag, TruncatedBagIsExitTwoAndKeepsWhatWasRead) {
  SKIP_WITHOUT_ROS();
#ifdef CARENAV_TEST_WITH_ROS
  const std::string bytes = slurp(senaBag());
  const auto cut = scratch() / "sena_cut.bag";
  std::ofstream(cut, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  const auto info = carenav_test::carenav({"rawlog", "info", cut.string()});
  EXPECT_EQ(info.code, 2) << info.err;
  EXPECT_NE(info.err.find(cut.string()), std::string::npos) << info.err;
  EXPECT_NE(info.err.find("(byte "), std::string::npos) << info.err;
  EXPECT_NE(info.out.find("CObservation2DRangeScan"), std::string::npos) << info.out;
  const auto out = scratch() / "sena_cut.rawlog";
  const auto imp =
      carenav_test::carenav({"-q", "import", "rosbag", cut.string(), "--out", out.string()});
  EXPECT_EQ(imp.code, 2) << imp.err;
  EXPECT_NE(imp.err.find("truncated"), std::string::npos) << imp.err;
  EXPECT_TRUE(fs::exists(out)) << "what was read before the cut is written";
  const auto slam =
      carenav_test::carenav({"-q", "slam", "--profile", kSrc + "/ini/defaults.ini", "--rawlog",
                             cut.string(), "--out", (scratch() / "slam_cut").string()});
  EXPECT_EQ(slam.code, 2) << slam.err;
  EXPECT_TRUE(fs::exists(scratch() / "slam_cut" / "map.png")) << slam.err;
#endif
}

TEST(CliRosbag, LocalizeOnTheBagTracksAsOnTheRawlog) {
  SKIP_WITHOUT_ROS();
#ifdef CARENAV_TEST_WITH_ROS
  // MRPT's localization_demo as a bag: `carenav localize --rawlog X.bag`
  // gives the same track as on the rawlog (same scans, odometry, stamps).
  const std::string rawlog = kDatasets + "/localization_demo.rawlog";
  const std::string map = kDatasets + "/localization_demo.simplemap.gz";
  const auto bag = scratch() / "loc_demo.bag";
  carenav::ros::writeBagFromRawlog(rawlog, bag.string());
  const auto a = scratch() / "loc_rawlog", b = scratch() / "loc_bag";
  const std::string profile = kSrc + "/ini/defaults.ini";
  for (const auto& [log, out] : {std::pair{rawlog, a}, std::pair{bag.string(), b}}) {
    const auto r = carenav_test::carenav({"-q", "localize", "--profile", profile, "--map", map,
                                          "--rawlog", log, "--global", "--out", out.string()});
    ASSERT_EQ(r.code, 0) << r.err;
  }
  EXPECT_EQ(slurp(a / "track.tum"), slurp(b / "track.tum"));
#endif
}

}  // namespace
