// The navigation sections: each class's keys in its own [nav.*] section, and
// the keys of the previous version's [navigation] still read the same.
#include <carenav/common/errors.h>
#include <carenav/common/profile.h>
#include <carenav/navigation/navigation_params.h>

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include <unistd.h>

namespace carenav::navigation {
namespace {

namespace fs = std::filesystem;

const char* kRobot = "[robot]\nv_max = 0.3\n";

/** The [nav.*] sections and the renamed keys, for every test (ctest runs
 *  each in its own process). */
const bool kRegistered = (registerProfileSections(), true);

/** A valid value other than the default, for every key of the tables. */
std::string otherValue(const ParamSpec& s) {
  const double x = s.min + 0.37 * (s.max - s.min);
  char buf[64];
  if (s.type == ParamType::Integer)
    std::snprintf(buf, sizeof buf, "%d", static_cast<int>(x));
  else
    std::snprintf(buf, sizeof buf, "%.4f", x);
  return buf;
}

/** Every renamed key, by new section: key = otherValue. */
std::map<std::string, std::string> renamedKeyLines() {
  std::map<std::string, std::string> by_section;
  for (const auto& r : ProfileSchemas::instance().renames()) {
    if (r.old_section != "navigation") continue;
    for (const auto* schema : ProfileSchemas::instance().candidates(r.new_section))
      for (const auto& s : schema->specs)
        if (s.key == r.new_key) by_section[r.new_section] += s.key + " = " + otherValue(s) + "\n";
  }
  return by_section;
}

template <class T>
void expectSameFields(const NavigationParams& a, const NavigationParams& b) {
  for (const auto& s : T::table().specs())
    EXPECT_EQ(T::table().get(a, s.key), T::table().get(b, s.key)) << s.key;
}

void expectSameParams(const NavigationParams& a, const NavigationParams& b) {
  expectSameFields<NavigationParams>(a, b);
  expectSameFields<UserIntentDwaParams>(a, b);
  expectSameFields<GoalDwaParams>(a, b);
  expectSameFields<LocalMapParams>(a, b);
  expectSameFields<PeopleParams>(a, b);
  expectSameFields<SafetyParams>(a, b);
}

TEST(NavigationParams, EveryKeyHasOneSectionAndTheOldOnesAreRenamed) {
  ASSERT_TRUE(kRegistered);
  std::set<std::string> keys;
  size_t n = 0;
  auto add = [&](const std::vector<ParamSpec>& specs) {
    for (const auto& s : specs) keys.insert(s.key), ++n;
  };
  add(NavigationParams::table().specs());
  add(UserIntentDwaParams::table().specs());
  add(GoalDwaParams::table().specs());
  add(LocalMapParams::table().specs());
  add(PeopleParams::table().specs());
  add(SafetyParams::table().specs());
  EXPECT_EQ(n, 53u);  // the 46 keys of the previous [navigation], static_memory, align_deg,
                      // track_min_cells, route_footprint(_margin, _nodes), replan_new_only
  EXPECT_EQ(keys.size(), n) << "a key in two sections";
  size_t renamed = 0;
  for (const auto& r : ProfileSchemas::instance().renames())
    if (r.old_section == "navigation") {
      ++renamed;
      EXPECT_FALSE(NavigationParams::table().find(r.old_key)) << r.old_key;
    }
  EXPECT_EQ(renamed, n - 1 - NavigationParams::table().specs().size());
  EXPECT_FALSE(ProfileSchemas::instance().renames().empty());
}

TEST(NavigationParams, OldKeysGiveExactlyTheParamsOfTheNewSections) {
  const auto lines = renamedKeyLines();
  std::string old_text = std::string(kRobot) + "[navigation]\nplugin = user-intent-dwa\n";
  std::string new_text = std::string(kRobot) + "[navigation]\nplugin = user-intent-dwa\n";
  for (const auto& [section, kv] : lines) {
    old_text += kv;
    new_text += "[" + section + "]\n" + kv;
  }
  const Profile old_p = Profile::fromText(old_text, "old.ini");
  const Profile new_p = Profile::fromText(new_text, "new.ini");
  EXPECT_TRUE(old_p.check().empty()) << old_p.check().front().text();
  EXPECT_TRUE(new_p.check().empty()) << new_p.check().front().text();
  const auto a = NavigationParams::fromProfile(old_p);
  const auto b = NavigationParams::fromProfile(new_p);
  expectSameParams(a, b);
  // Every renamed field was read (none is left at its default).
  const NavigationParams d;
  EXPECT_NE(a.k_heading, d.k_heading);
  EXPECT_NE(a.k_s, d.k_s);
  EXPECT_NE(a.obstacle_persistence, d.obstacle_persistence);
  EXPECT_NE(a.track_depth_min_cells, d.track_depth_min_cells);
  EXPECT_NE(a.intent_timeout, d.intent_timeout);
  EXPECT_EQ(old_p.renamedKeys().size(), 34u);
  EXPECT_TRUE(new_p.renamedKeys().empty());
}

// The walker's [navigation] as shipped before the sections were split.
const char* kOldWalkerNavigation = R"([navigation]
plugin = user-intent-dwa
sim_time = 7.0
sim_step = 0.1
window_time = 0.5
v_samples = 12
k_s = 0.01
k_0 = 1.0
k_1 = 0.5
k_2 = 0.05
)";

TEST(NavigationParams, TheShippedWalkerReadsAsItsPreviousForm) {
  const Profile shipped = Profile::load(std::string(CARENAV_SOURCE_DIR) + "/ini/isr-aiwalker.ini");
  const Profile old_p = Profile::fromText(std::string(kRobot) + kOldWalkerNavigation, "old.ini");
  expectSameParams(NavigationParams::fromProfile(shipped), NavigationParams::fromProfile(old_p));
  EXPECT_TRUE(shipped.renamedKeys().empty());
}

TEST(NavigationParams, NewKeyWinsOverOldAndCheckSaysSo) {
  const Profile p = Profile::fromText(std::string(kRobot) +
                                          "[navigation]\nk_heading = 2\n"
                                          "[nav.goal_dwa]\nk_heading = 3\n",
                                      "t.ini");
  EXPECT_EQ(NavigationParams::fromProfile(p).k_heading, 3.0);
  EXPECT_TRUE(p.check().empty());
  const auto notes = p.renamedKeys();
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_EQ(notes[0].text(),
            "t.ini:4: [navigation] k_heading: navigation.k_heading is now nav.goal_dwa.k_heading; "
            "both are set, nav.goal_dwa.k_heading (t.ini:6) wins: 3");
  const Profile only_old =
      Profile::fromText(std::string(kRobot) + "[navigation]\nk_heading = 2\n", "t.ini");
  ASSERT_EQ(only_old.renamedKeys().size(), 1u);
  EXPECT_EQ(only_old.renamedKeys()[0].text(),
            "t.ini:4: [navigation] k_heading: navigation.k_heading is now nav.goal_dwa.k_heading");
}

TEST(NavigationParams, OldAndNewKeysOnTheCommandLine) {
  Profile p = Profile::fromText(std::string(kRobot) + "[nav.goal_dwa]\nk_heading = 3\n", "t.ini");
  p.applyOverride("navigation.predict_horizon=0");
  EXPECT_EQ(NavigationParams::fromProfile(p).predict_horizon, 0.0);
  // --set overrides the file, under either name ...
  p.applyOverride("navigation.k_heading=4");
  EXPECT_EQ(NavigationParams::fromProfile(p).k_heading, 4.0);
  // ... and of two --set, the new name wins.
  p.applyOverride("nav.goal_dwa.k_heading=5");
  EXPECT_EQ(NavigationParams::fromProfile(p).k_heading, 5.0);
  EXPECT_TRUE(p.check().empty());
}

TEST(NavigationParams, AnOldKeyInARobotProfileOverridesANewOneInItsBase) {
  const fs::path dir =
      fs::temp_directory_path() / ("carenav_navparams_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "base.ini") << "[robot]\nv_max = 0.3\n[nav.people]\npredict_speed = 0.7\n";
  std::ofstream(dir / "robot.ini")
      << "[profile]\nbase = base.ini\n[navigation]\npredict_speed = 0.2\n";
  const Profile p = Profile::load((dir / "robot.ini").string());
  EXPECT_EQ(NavigationParams::fromProfile(p).predict_speed, 0.2);
  ASSERT_EQ(p.renamedKeys().size(), 1u);
  EXPECT_NE(p.renamedKeys()[0].text().find("navigation.predict_speed ("), std::string::npos)
      << p.renamedKeys()[0].text();
  fs::remove_all(dir);
}

TEST(NavigationParams, BadOldValuesAreReportedAtTheirLine) {
  const Profile p =
      Profile::fromText(std::string(kRobot) + "[navigation]\nk_heading = 500\n", "t.ini");
  const auto issues = p.check();
  ASSERT_EQ(issues.size(), 1u);
  EXPECT_EQ(issues[0].origin.where(), "t.ini:4");
  EXPECT_EQ(issues[0].key, "k_heading");
  EXPECT_THROW(NavigationParams::fromProfile(p), InputError);
}

TEST(NavigationParams, AMisspeltOldKeyIsToldItsNewPlace) {
  const Profile p =
      Profile::fromText(std::string(kRobot) + "[navigation]\nk_headng = 1\n", "t.ini");
  const auto issues = p.check();
  ASSERT_EQ(issues.size(), 1u);
  EXPECT_NE(issues[0].text().find("t.ini:4: [navigation] k_headng: unknown key (did you mean "
                                  "'k_heading' (now nav.goal_dwa.k_heading)?); keys of "
                                  "[navigation]: plugin, "),
            std::string::npos)
      << issues[0].text();
}

}  // namespace
}  // namespace carenav::navigation
