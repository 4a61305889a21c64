// Keys that moved from [navigation] to their class's [nav.*] section: a
// profile of the previous version still loads, and `profile check` names
// each old key with its new name.
#include "cli_helpers.h"

#include <gtest/gtest.h>

using namespace carenav_test;

TEST(CliProfileRenames, CheckReportsEachOldKeyWithItsNewName) {
  const auto file = scratch() / "old_walker.ini";
  std::ofstream(file) << "[profile]\nbase = " << kSrc << "/ini/isr-aiwalker.ini\n"
                      << "[navigation]\nk_heading = 1.5\npredict_horizon = 0\n"
                      << "[nav.people]\npredict_horizon = 1\n";
  const RunResult r = carenav({"profile", "check", file.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find(": OK ("), std::string::npos) << r.out;
  const std::string f = file.string();
  EXPECT_NE(r.err.find("warning: " + f +
                       ":4: [navigation] k_heading: navigation.k_heading is now "
                       "nav.goal_dwa.k_heading\n"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("warning: " + f +
                       ":5: [navigation] predict_horizon: navigation.predict_horizon is now "
                       "nav.people.predict_horizon; both are set, nav.people.predict_horizon (" +
                       f + ":7) wins: 1\n"),
            std::string::npos)
      << r.err;

  // The value the commands read: the new key's; an old key on the command line
  // overrides the file as before.
  const RunResult show = carenav({"profile", "show", f, "--set", "navigation.k_heading=2.5"});
  ASSERT_EQ(show.code, 0) << show.err;
  EXPECT_NE(show.out.find("\npredict_horizon = 1 "), std::string::npos) << show.out;
  EXPECT_NE(show.out.find("\nk_heading = 2.5 "), std::string::npos) << show.out;
  EXPECT_NE(show.err.find("warning: --set: [navigation] k_heading: navigation.k_heading is now "
                          "nav.goal_dwa.k_heading\n"),
            std::string::npos)
      << show.err;

  // The shipped profiles use the new sections only: no warning.
  const RunResult shipped = carenav({"profile", "check", kSrc + "/ini/isr-aiwalker.ini"});
  ASSERT_EQ(shipped.code, 0) << shipped.err;
  EXPECT_EQ(shipped.err, "");
}

TEST(CliProfileRenames, BothNamesWorkWithSet) {
  const std::string walker = kSrc + "/ini/isr-aiwalker.ini";
  for (const std::string set : {"navigation.k_heading=700", "nav.goal_dwa.k_heading=700"}) {
    const RunResult r = carenav({"profile", "check", walker, "--set", set});
    EXPECT_EQ(r.code, 2) << set;
    EXPECT_NE(r.err.find("k_heading: '700': out of range"), std::string::npos) << r.err;
  }
}
