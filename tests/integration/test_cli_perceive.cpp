// carenav perceive on real data (MRPT's tests_rgbd.rawlog, the office1.pcd
// Kinect frame) and its input errors.
#include "cli_helpers.h"

#include <fstream>

using namespace carenav_test;

namespace {
const std::string kProfile = kSrc + "/ini/isr-aiwalker.ini";
const std::string kOffice = kTestData + "/pcd/office1.pcd";
const std::string kRgbd = kDatasets + "/tests_rgbd.rawlog";

double jsonReal(const std::string& json, const std::string& key) {
  std::smatch m;
  if (!std::regex_search(json, m, std::regex("\"" + key + "\": (-?[0-9.eE+-]+)"))) {
    ADD_FAILURE() << "no key " << key;
    return 0;
  }
  return std::stod(m[1]);
}
}  // namespace

TEST(CliPerceive, Office1KinectFrameFindsTheFloorPlane) {
  const auto out = scratch() / "perceive_office1";
  // office1.pcd: Kinect held level 1.4 m above the floor (the floor rows are
  // at y = 1.40 m in the camera frame from 3 to 5 m).
  const auto r = carenav({"-q", "perceive", "--profile", kProfile, "--cloud", kOffice, "--out",
                          out.string(), "--sensor-pose", "0,0,1.4,0,0,0"});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string s = slurp(out / "summary.json");
  EXPECT_NE(s.find("\"plane_source\": \"rrt-gpd\""), std::string::npos) << s;
  EXPECT_LT(jsonReal(s, "plane_tilt_deg"), 6.0);
  EXPECT_GT(jsonReal(s, "c"), 0.99);
  EXPECT_LT(std::abs(jsonReal(s, "d")), 0.15);
  EXPECT_GE(jsonNumber(s, "rrt_nodes"), 10u);
  const auto occ = jsonNumber(s, "occupied"), fr = jsonNumber(s, "free"),
             unk = jsonNumber(s, "unknown");
  EXPECT_EQ(occ + fr + unk, 40000u);
  EXPECT_GT(occ, 100u);
  EXPECT_GT(fr, 1000u);
  EXPECT_TRUE(fs::exists(out / "frame_0000.png"));
  EXPECT_TRUE(fs::exists(out / "frame_0000.gridmap.gz"));
  EXPECT_TRUE(fs::exists(out / "virtual_scans.rawlog"));
  // The RANSAC-only baseline on the same frame takes the back wall as ground.
  const auto out2 = scratch() / "perceive_office1_ransac";
  const auto r2 = carenav({"-q", "perceive", "--profile", kProfile, "--cloud", kOffice, "--out",
                           out2.string(), "--sensor-pose", "0,0,1.4,0,0,0", "--method", "ransac"});
  ASSERT_EQ(r2.code, 0) << r2.err;
  EXPECT_GT(jsonReal(slurp(out2 / "summary.json"), "plane_tilt_deg"), 45.0);
}

TEST(CliPerceive, TestsRgbdRawlogRunsEveryMethod) {
  for (const std::string m : {"rrt-gpd", "ransac", "height-band", "mrpt-2dscan"}) {
    const auto out = scratch() / ("perceive_rgbd_" + m);
    const auto r = carenav({"-q", "perceive", "--profile", kProfile, "--rawlog", kRgbd, "--out",
                            out.string(), "--method", m, "--set", "perception.sensor=OPENNI2"});
    ASSERT_EQ(r.code, 0) << m << ": " << r.err;
    const std::string s = slurp(out / "summary.json");
    EXPECT_EQ(jsonNumber(s, "frame_count"), 1u);
    EXPECT_GT(jsonNumber(s, "valid_points"), 200000u);
    EXPECT_GT(jsonNumber(s, "occupied"), 0u) << m;
    EXPECT_EQ(jsonNumber(s, "occupied") + jsonNumber(s, "free") + jsonNumber(s, "unknown"), 40000u);
    if (m == "mrpt-2dscan") EXPECT_GT(jsonNumber(s, "mrpt_2dscan_valid"), 100u);
    EXPECT_NE(s.find("\"timing_ms\""), std::string::npos);
  }
}

TEST(CliPerceive, BadInputsExitTwoNamingTheProblem) {
  const auto d = scratch();
  const auto trunc = (d / "trunc.pcd").string();
  {
    std::ofstream f(trunc);
    f << "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 10\nHEIGHT 1\n"
         "POINTS 10\nDATA binary\n0123";
  }
  auto r = carenav(
      {"perceive", "--profile", kProfile, "--cloud", trunc, "--out", (d / "p_bad").string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("trunc.pcd"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("truncated"), std::string::npos) << r.err;
  r = carenav({"perceive", "--profile", kProfile, "--cloud", kOffice, "--out",
               (d / "p_bad2").string(), "--method", "magic"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("magic"), std::string::npos) << r.err;
  r = carenav({"perceive", "--profile", kProfile, "--cloud", kOffice, "--out",
               (d / "p_bad3").string(), "--method", "mrpt-2dscan"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("depth images"), std::string::npos) << r.err;
  r = carenav({"perceive", "--profile", kProfile, "--cloud", kOffice, "--out",
               (d / "p_bad4").string(), "--sensor-pose", "1,2,3"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("six numbers"), std::string::npos) << r.err;
}
