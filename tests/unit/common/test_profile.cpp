#include <carenav/common/data_dir.h>
#include <carenav/common/profile.h>
#include <carenav/common/robot.h>

#include <gtest/gtest.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <filesystem>
#include <fstream>

using namespace carenav;
namespace fs = std::filesystem;

namespace {
const std::string kIni = std::string(CARENAV_SOURCE_DIR) + "/ini/";

/** A scratch folder with a defaults.ini, for hand-made profiles. */
class ProfileFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("carenav_profile_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    // A base of common sections only (the shipped defaults.ini also holds
    // module sections, which test_common does not link).
    write("defaults.ini", "[profile]\nname = defaults\n[robot]\nv_max = 0.3\nw_max = 0.75\n");
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) {
    const auto p = (dir_ / name).string();
    std::ofstream(p) << text;
    return p;
  }
  /** The message of the InputError `f` throws (fails the test if none). */
  template <class F>
  static std::string errorOf(F&& f) {
    try {
      f();
    } catch (const InputError& e) {
      return e.what();
    }
    ADD_FAILURE() << "no InputError thrown";
    return "";
  }
  fs::path dir_;
};

const char* kWalkerish = R"([profile]
name = test
base = defaults.ini
[robot]
v_max = 0.4
)";
}  // namespace

TEST(Profile, EveryShippedProfileLoadsAndValidates) {
  for (const char* name : {"isr-aiwalker", "interbot", "hobbit"}) {
    SCOPED_TRACE(name);
    const Profile p = Profile::load(kIni + name + ".ini");
    // Module sections ([slam], ...) are checked where their modules are
    // linked (the CLI tests); here every common section must be clean.
    for (const auto& issue : p.check())
      EXPECT_TRUE(issue.message.rfind("unknown section", 0) == 0) << issue.text();
    EXPECT_EQ(p.files().size(), 2u);  // defaults.ini, then the robot
    const auto robot = p.section<RobotParams>("robot");
    EXPECT_GT(robot.v_max, 0);
    EXPECT_GE(robot.footprint.size(), 3u);
    const auto sensors = loadSensors(p);
    EXPECT_GE(sensors.size(), 2u);
    EXPECT_EQ(p.section<ProfileInfo>("profile").name, name);
  }
}

TEST(Profile, WalkerValuesFromTheThesis) {
  const Profile p = Profile::load(kIni + "isr-aiwalker.ini");
  const auto r = p.section<RobotParams>("robot");
  // [Rosa17, Table 5.1]
  EXPECT_DOUBLE_EQ(r.v_max, 0.3);
  EXPECT_DOUBLE_EQ(r.w_max, 0.75);
  EXPECT_DOUBLE_EQ(r.acc_v, 0.5);
  EXPECT_DOUBLE_EQ(r.acc_w, 1.0);
  EXPECT_DOUBLE_EQ(r.safe_distance, 0.325);
  EXPECT_EQ(r.control, "user-intent");
  // about 0.7 x 0.65 m (docs/design.md, 'Robot profiles')
  double minx = 1e9, maxx = -1e9, miny = 1e9, maxy = -1e9;
  for (const auto& q : r.footprint) {
    minx = std::min(minx, q.x), maxx = std::max(maxx, q.x);
    miny = std::min(miny, q.y), maxy = std::max(maxy, q.y);
  }
  EXPECT_NEAR(maxx - minx, 0.7, 1e-9);
  EXPECT_NEAR(maxy - miny, 0.65, 1e-9);
  const auto sensors = loadSensors(p);
  const auto kinect = std::find_if(sensors.begin(), sensors.end(),
                                   [](const SensorParams& s) { return s.label == "kinect"; });
  ASSERT_NE(kinect, sensors.end());
  EXPECT_EQ(kinect->type, "depth-camera");
  EXPECT_EQ(kinect->width, 512);
  EXPECT_EQ(kinect->height, 424);
  EXPECT_DOUBLE_EQ(kinect->range_min, 0.5);
  EXPECT_DOUBLE_EQ(kinect->range_max, 4.5);
}

TEST_F(ProfileFiles, BaseGivesDefaultsAndTheProfileOverrides) {
  const Profile p = Profile::load(write("r.ini", kWalkerish));
  const auto r = p.section<RobotParams>("robot");
  EXPECT_DOUBLE_EQ(r.v_max, 0.4);   // from r.ini
  EXPECT_DOUBLE_EQ(r.w_max, 0.75);  // from defaults.ini
  EXPECT_TRUE(p.check().empty());
}

TEST_F(ProfileFiles, OverridesWinAndAreValidated) {
  Profile p = Profile::load(write("r.ini", kWalkerish));
  p.applyOverride("robot.v_max=0.2");
  p.applyOverride("sensor.front.laser.type = lidar2d");  // dotted section name
  EXPECT_DOUBLE_EQ(p.section<RobotParams>("robot").v_max, 0.2);
  EXPECT_EQ(p.value("sensor.front.laser", "type"), "lidar2d");
  EXPECT_THROW(p.applyOverride("robot.v_max"), InputError);
  EXPECT_THROW(p.applyOverride("v_max=1"), InputError);
  EXPECT_THROW(p.applyOverride(".v_max=1"), InputError);
  p.applyOverride("robot.v_max=7");
  const auto issues = p.check();
  ASSERT_EQ(issues.size(), 1u);
  EXPECT_EQ(issues[0].origin.file, "--set");
  EXPECT_NE(issues[0].text().find("[0, 3] m/s"), std::string::npos) << issues[0].text();
}

TEST_F(ProfileFiles, MisspeltKeyIsNamedWithFileLineAndSuggestion) {
  const auto f = write("r.ini", std::string(kWalkerish) + "w_mx = 0.5\n");
  const Profile p = Profile::load(f);
  const auto issues = p.check();
  ASSERT_EQ(issues.size(), 1u);
  const std::string t = issues[0].text();
  EXPECT_NE(t.find(f + ":6"), std::string::npos) << t;
  EXPECT_NE(t.find("[robot] w_mx"), std::string::npos) << t;
  EXPECT_NE(t.find("did you mean 'w_max'"), std::string::npos) << t;
  const std::string msg = errorOf([&] { p.validate(); });
  EXPECT_NE(msg.find("w_mx"), std::string::npos);
}

TEST_F(ProfileFiles, WrongTypeAndOutOfRangeNameKeyAndRange) {
  const Profile p = Profile::load(
      write("r.ini", std::string(kWalkerish) + "w_max = fast\nacc_v = -1\ncontrol = joystick\n"));
  const auto issues = p.check();
  ASSERT_EQ(issues.size(), 3u);
  std::string all;
  for (const auto& i : issues) all += i.text() + "\n";
  EXPECT_NE(
      all.find("[robot] w_max: 'fast': not a number; allowed: a real number in [0, 10] rad/s"),
      std::string::npos)
      << all;
  EXPECT_NE(all.find("[robot] acc_v: '-1': out of range; allowed: a real number in [0.01, 10]"),
            std::string::npos)
      << all;
  EXPECT_NE(all.find("one of autonomous, user-intent"), std::string::npos) << all;
  // Reading the section into its struct fails the same way.
  const std::string msg = errorOf([&] { p.section<RobotParams>("robot"); });
  EXPECT_NE(msg.find("w_max"), std::string::npos) << msg;
}

TEST_F(ProfileFiles, UnknownSectionsAndBadSensorsAreErrors) {
  const Profile p = Profile::load(write("r.ini", std::string(kWalkerish) +
                                                     "[robott]\nx = 1\n"
                                                     "[sensor.a]\nx = 0.1\n"
                                                     "[sensor.b]\ntype = sonar\n"
                                                     "[sensor.c]\ntype = lidar2d\nwidth = 3\n"
                                                     "[sensor.d]\ntype = lidar2d\nrange_min = 5\n"
                                                     "range_max = 4\n"));
  const auto issues = p.check();
  std::string all;
  for (const auto& i : issues) all += i.text() + "\n";
  EXPECT_EQ(issues.size(), 5u) << all;
  EXPECT_NE(all.find("[robott]: unknown section"), std::string::npos) << all;
  EXPECT_NE(all.find("[sensor.a] type: missing"), std::string::npos) << all;
  EXPECT_NE(all.find("[sensor.b] type: 'sonar' is not one of"), std::string::npos) << all;
  EXPECT_NE(all.find("[sensor.c] width: unknown key"), std::string::npos) << all;
  EXPECT_NE(all.find("range_min (5) must be below range_max (4)"), std::string::npos) << all;
  EXPECT_THROW(loadSensors(p), InputError);
}

TEST_F(ProfileFiles, MissingEmptyAndMalformedFiles) {
  EXPECT_NE(errorOf([&] { Profile::load((dir_ / "none.ini").string()); }).find("not found"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { Profile::load(write("e.ini", "")); }).find("empty profile"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { Profile::load(write("c.ini", "; only a comment\n")); }).find("empty"),
            std::string::npos);
  const std::string noeq = errorOf([&] { Profile::load(write("m.ini", "[robot]\nv_max 3\n")); });
  EXPECT_NE(noeq.find("m.ini:2:"), std::string::npos) << noeq;
  const std::string hdr = errorOf([&] { Profile::load(write("h.ini", "[robot\nv_max=1\n")); });
  EXPECT_NE(hdr.find("h.ini:1:"), std::string::npos) << hdr;
  EXPECT_NE(errorOf([&] {
              Profile::load(write("k.ini", "v_max = 1\n[robot]\n"));
            }).find("before any [section]"),
            std::string::npos);
  const std::string dup =
      errorOf([&] { Profile::load(write("d.ini", "[robot]\nv_max=1\nv_max=2\n")); });
  EXPECT_NE(dup.find("d.ini:3:"), std::string::npos) << dup;
  EXPECT_NE(dup.find("first at line 2"), std::string::npos) << dup;
  const std::string bin =
      errorOf([&] { Profile::load(write("b.ini", std::string("[robot]\nv\0x=1\n", 13))); });
  EXPECT_NE(bin.find("not a text file"), std::string::npos) << bin;
  // Truncated in the middle of a header.
  EXPECT_NE(
      errorOf([&] { Profile::load(write("t.ini", "[profile]\nname = x\n[rob")); }).find("t.ini:3:"),
      std::string::npos);
  EXPECT_THROW(Profile::load(dir_.string()), InputError);  // a directory
}

TEST_F(ProfileFiles, BaseChainErrors) {
  const std::string missing =
      errorOf([&] { Profile::load(write("r.ini", "[profile]\nbase = nothere.ini\n[robot]\n")); });
  EXPECT_NE(missing.find("r.ini:2: [profile] base"), std::string::npos) << missing;
  EXPECT_NE(missing.find("nothere.ini"), std::string::npos) << missing;
  write("a.ini", "[profile]\nbase = b.ini\n[robot]\nv_max=1\n");
  write("b.ini", "[profile]\nbase = a.ini\n[robot]\nv_max=1\n");
  EXPECT_NE(errorOf([&] { Profile::load((dir_ / "a.ini").string()); }).find("circular"),
            std::string::npos);
}

TEST(Profile, RobotSectionIsRequired) {
  const Profile p = Profile::fromText("[profile]\nname = x\n", "mem.ini");
  const auto issues = p.check();
  ASSERT_EQ(issues.size(), 1u);
  EXPECT_EQ(issues[0].section, "robot");
}

TEST(Profile, FootprintMustHoldTheOrigin) {
  const Profile p = Profile::fromText("[robot]\nfootprint = 1,1 2,1 2,2 1,2\n", "mem.ini");
  ASSERT_EQ(p.check().size(), 1u);
  EXPECT_NE(p.check()[0].message.find("origin"), std::string::npos);
}

TEST(Profile, ResolvedTextShowsEveryKeyAndItsOrigin) {
  Profile p = Profile::load(kIni + "hobbit.ini");
  p.applyOverride("robot.w_max=0.5");
  const std::string t = p.resolvedText();
  EXPECT_NE(t.find("w_max = 0.5"), std::string::npos);
  EXPECT_NE(t.find("from --set"), std::string::npos);
  EXPECT_NE(t.find("from " + kIni + "defaults.ini:"), std::string::npos) << t;
  EXPECT_NE(t.find("[sensor.top]"), std::string::npos);
  // Every declared key of [robot] is listed, even those left at defaults.
  for (const auto& spec : RobotParams::table().specs())
    EXPECT_NE(t.find("\n" + spec.key + " = "), std::string::npos) << spec.key;
}

TEST(Profile, MrptConfigSeesTheResolvedValues) {
  Profile p = Profile::load(kIni + "interbot.ini");
  p.applyOverride("robot.v_max=0.1");
  mrpt::config::CConfigFileMemory cfg;
  p.toMrptConfig(cfg);
  EXPECT_DOUBLE_EQ(cfg.read_double("robot", "v_max", -1), 0.1);
  EXPECT_DOUBLE_EQ(cfg.read_double("robot", "w_max", -1), 1.0);
  EXPECT_EQ(cfg.read_string("sensor.laser", "type", ""), "lidar2d");
}

TEST(Profile, EditDistance) {
  EXPECT_EQ(editDistance("v_max", "v_max"), 0u);
  EXPECT_EQ(editDistance("w_mx", "w_max"), 1u);
  EXPECT_EQ(editDistance("", "abc"), 3u);
}

// ------------------------------------------------- the shipped data folder

TEST_F(ProfileFiles, ACopiedProfileFindsItsBaseInTheDataFolder) {
  // dir_ plays the installed data folder (its ini/defaults.ini); the profile
  // is a copy elsewhere that names `base = defaults.ini`.
  fs::create_directories(dir_ / "ini");
  fs::rename(dir_ / "defaults.ini", dir_ / "ini" / "defaults.ini");
  const fs::path elsewhere = dir_ / "copies";
  fs::create_directories(elsewhere);
  std::ofstream(elsewhere / "mine.ini") << kWalkerish;
  ::setenv("CARENAV_DATA_DIR", dir_.c_str(), 1);
  EXPECT_EQ(fs::path(dataDir()), dir_);
  const Profile p = Profile::load((elsewhere / "mine.ini").string());
  ::unsetenv("CARENAV_DATA_DIR");
  EXPECT_DOUBLE_EQ(p.section<RobotParams>("robot").w_max, 0.75) << "the base's value";
  // A base beside the copy wins over the shipped one.
  std::ofstream(elsewhere / "defaults.ini") << "[profile]\nname = d\n[robot]\nw_max = 0.5\n";
  ::setenv("CARENAV_DATA_DIR", dir_.c_str(), 1);
  const Profile q = Profile::load((elsewhere / "mine.ini").string());
  ::unsetenv("CARENAV_DATA_DIR");
  EXPECT_DOUBLE_EQ(q.section<RobotParams>("robot").w_max, 0.5);
}

TEST_F(ProfileFiles, AMissingDataFolderIsNamedWithWhereItWasLookedFor) {
  ::setenv("CARENAV_DATA_DIR", (dir_ / "nothing-here").c_str(), 1);
  const std::string msg = errorOf([] { dataFile("ini/isr-aiwalker.ini", "the default profile"); });
  ::unsetenv("CARENAV_DATA_DIR");
  EXPECT_NE(msg.find("the default profile"), std::string::npos) << msg;
  EXPECT_NE(msg.find("nothing-here"), std::string::npos) << msg;
  EXPECT_NE(msg.find("CARENAV_DATA_DIR"), std::string::npos) << msg;
}
