// Where a rawlog ends (pose_at_end.h), on MRPT's localization_demo data.
#include <carenav/common/errors.h>
#include <carenav/localization/pose_at_end.h>

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace carenav::localization {
namespace {

namespace fs = std::filesystem;

const std::string kDatasets = CARENAV_MRPT_DATASETS;
const std::string kRawlog = kDatasets + "/localization_demo.rawlog";
const std::string kSimplemap = kDatasets + "/localization_demo.simplemap.gz";
// Where MRPT's pf-localization ends on this log, and the tolerances, as in
// test_localizer.cpp.
constexpr double kMrptX = 15.91, kMrptY = -10.01, kMrptYawDeg = 4.93;
constexpr double kTolPos = 0.25, kTolYawDeg = 3.0;

LocalizeJobOptions tracking() {
  LocalizeJobOptions o;
  o.map = kSimplemap;
  o.rawlog = kRawlog;
  o.progress = false;
  o.init = parseInitialPose("3.7,-10.1,-40,0.2,0.2,5");
  return o;
}

template <class E, class F>
std::string errorOf(F f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(PoseAtEnd, TheRawlogEndsWhereMrptPfLocalizationEnds) {
  const EndPose e = poseAtEnd(tracking());
  EXPECT_NEAR(e.x, kMrptX, kTolPos);
  EXPECT_NEAR(e.y, kMrptY, kTolPos);
  EXPECT_NEAR(e.yaw * 180 / M_PI, kMrptYawDeg, kTolYawDeg);
  EXPECT_GT(e.scans, 30u);
  EXPECT_GT(e.spread, 0);
}

TEST(PoseAtEnd, NotConvergedOrABrokenRawlogIsRefused) {
  LocalizeJobOptions o = tracking();
  o.params.converged_spread = 0.001;
  EXPECT_NE(errorOf<std::runtime_error>([&] { poseAtEnd(o); }).find("has not converged at its end"),
            std::string::npos);

  const auto dir =
      fs::temp_directory_path() / ("carenav_pose_at_end_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ostringstream raw;
  raw << std::ifstream(kRawlog, std::ios::binary).rdbuf();
  const std::string cut = (dir / "cut.rawlog").string();
  std::ofstream(cut, std::ios::binary) << raw.str().substr(0, raw.str().size() / 3);
  o = tracking();
  o.rawlog = cut;
  const std::string m = errorOf<InputError>([&] { poseAtEnd(o); });
  EXPECT_NE(m.find("cut.rawlog"), std::string::npos) << m;
  EXPECT_NE(m.find("(add-place --here needs the whole log)"), std::string::npos) << m;
  fs::remove_all(dir);
}

TEST(PoseAtEnd, ParamsFromAProfileOrTheDefaultsWithOverrides) {
  EXPECT_EQ(localizationParamsOf("", {}).particles_max, LocalizationParams{}.particles_max);
  EXPECT_EQ(localizationParamsOf("", {"localization.particles_max=500"}).particles_max, 500);
  EXPECT_EQ(errorOf<InputError>([] { localizationParamsOf("", {"robot.v_max=1"}); }),
            "--set 'robot.v_max=1': without --profile only localization.* values can be set");

  registerProfileSections();  // a profile is validated against every known section
  const auto dir =
      fs::temp_directory_path() / ("carenav_pose_at_end_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string ini = (dir / "t.ini").string();
  std::ofstream(ini) << "[profile]\nname = t\n[robot]\n"
                        "footprint = 0.2,0.2 -0.2,0.2 -0.2,-0.2 0.2,-0.2\n"
                        "[localization]\nparticles_max = 600\n";
  EXPECT_EQ(localizationParamsOf(ini, {}).particles_max, 600);
  EXPECT_EQ(localizationParamsOf(ini, {"localization.particles_max=700"}).particles_max, 700);
  EXPECT_NE(errorOf<InputError>([&] {
              localizationParamsOf(ini, {"robot.nokey=1"});
            }).find("unknown key"),
            std::string::npos);
  fs::remove_all(dir);
}

}  // namespace carenav::localization
