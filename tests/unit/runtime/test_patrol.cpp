// Patrol scenarios (goals visited in turn) and the run-health metrics of
// runScenario: the soak runs of tests/bench/soak rely on both.
#include <carenav/common/errors.h>
#include <carenav/localization/localization_params.h>
#include <carenav/navigation/navigation_params.h>
#include <carenav/perception/perception_params.h>
#include <carenav/runtime/scenario.h>
#include <carenav/sim/sim_params.h>
#include <carenav/slam/slam_params.h>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

using namespace carenav::navigation;

namespace {

const std::string kSrc = CARENAV_SOURCE_DIR;

/** Every section of the shipped profiles, as the binary registers them. */
class ProfileSections : public ::testing::Environment {
 public:
  void SetUp() override {
    carenav::slam::registerProfileSections();
    carenav::localization::registerProfileSections();
    carenav::navigation::registerProfileSections();
    carenav::perception::registerProfileSections();
    carenav::sim::registerProfileSections();
  }
};
const auto* const kSections = ::testing::AddGlobalTestEnvironment(new ProfileSections);

std::string patrolText(const std::string& goals, const std::string& extra = "") {
  return "format: 1\nworld: " + kSrc + "/maps/worlds/empty_room.yaml\nprofile: " + kSrc +
         "/ini/interbot.ini\nstart: [3, 3, 0]\npatrol:\n" + goals + extra + "end: true\n";
}

}  // namespace

TEST(PatrolScenario, ReadsPosesAndNamesInOrder) {
  const auto s = parseScenario(
      patrolText("  - [6, 3, 0]\n  - \"kitchen/table\"\n  - [3, 6, 90]\n", "leg_timeout: 40\n"),
      "p.yaml", ".");
  ASSERT_EQ(s.patrol.size(), 3u);
  ASSERT_TRUE(s.patrol[0].pose);
  EXPECT_DOUBLE_EQ(s.patrol[0].pose->x, 6);
  EXPECT_EQ(s.patrol[1].name, "kitchen/table");
  EXPECT_NEAR(s.patrol[2].pose->phi, M_PI / 2, 1e-12);
  EXPECT_DOUBLE_EQ(s.leg_timeout, 40);
  ASSERT_TRUE(s.goal) << "the first goal is the run's goal";
  EXPECT_DOUBLE_EQ(s.goal->x, 6);
}

TEST(PatrolScenario, MalformedPatrolsNameTheLine) {
  auto refused = [](const std::string& text, const std::string& what) {
    try {
      parseScenario(text, "p.yaml", ".");
      ADD_FAILURE() << "accepted: " << text;
    } catch (const carenav::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("p.yaml:"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  refused(patrolText("  - [6, 3, 0]\n"), "2 to 1000 goals");
  refused(patrolText("  - [6]\n  - [3, 6, 0]\n"), "[x, y, heading_deg]");
  // [x, y]: a goal any heading will do
  const Scenario any = parseScenario(patrolText("  - [6, 3]\n  - [3, 6, 0]\n"), "p.yaml", ".");
  EXPECT_TRUE(std::isnan(any.patrol.front().pose->phi));
  refused(patrolText("  - [6, 3, 0]\n  - [3, 6, 0]\n", "goal: [1, 1, 0]\n"), "not both");
  refused(patrolText("  - [6, 3, 0]\n  - [3, 6, 0]\n", "leg_timeout: -1\n"), "leg_timeout");
}

TEST(PatrolRun, VisitsTheGoalsInTurnAndReportsItsHealth) {
  auto s = parseScenario(patrolText("  - [7, 3, 0]\n  - [3, 3, 180]\n", "duration: 150\n"),
                         "p.yaml", ".");
  RunOptions o;
  const RunMetrics m = runScenario(s, o);
  // Interbot stops once its estimate is within goal_tolerance (0.5 m): with
  // a few cm of localisation error the truth may be just outside, a leg
  // "reported reached" but counted as missed; never given up.
  EXPECT_EQ(m.legs_failed, 0u) << m.outcome;
  EXPECT_GE(m.legs_completed + m.legs_missed, 4u) << "4 m legs at 0.25 m/s in 150 s";
  EXPECT_GE(m.legs_completed, 1u) << m.outcome;
  EXPECT_LT(m.leg_miss_max_m, 0.6) << "localisation within 10 cm";
  EXPECT_EQ(m.success, m.legs_missed == 0) << m.outcome;
  EXPECT_EQ(m.collisions, 0u);
  EXPECT_NEAR(m.duration_s, 150, 0.2) << "a patrol runs its whole duration";
  EXPECT_NE(m.outcome.find("patrol"), std::string::npos) << m.outcome;
  // Resident memory at the start, at each simulated minute (60 and 120 s), and at the end.
  ASSERT_EQ(m.rss_mb.size(), 4u);
  for (double v : m.rss_mb) EXPECT_GT(v, 1.0);
  EXPECT_GT(m.work_ms_p99, 0.0);
  EXPECT_GE(m.work_ms_max, m.work_ms_p99);
  ASSERT_EQ(m.work_ms_p99_windows.size(), 1u) << "one (partial) 10-minute window";
  const std::string js = m.toJson();
  for (const char* key : {"\"legs_completed\"", "\"work_ms_p99\"", "\"rss_mb_per_minute\"",
                          "\"work_ms_p99_per_10min\""})
    EXPECT_NE(js.find(key), std::string::npos) << key;
}

namespace {

/** A 6 m x 6 m room (0.05 m cells) with a closed 1 m box inside: its
 *  centre is free space that no route reaches. Returns the world file. */
std::string roomWithClosedBox() {
  const std::string dir = ::testing::TempDir() + "/patrol_box";
  std::filesystem::create_directories(dir);
  const int n = 120;
  std::string px(static_cast<size_t>(n) * n, static_cast<char>(255));
  auto wall = [&](int x, int y) { px[static_cast<size_t>(n - 1 - y) * n + x] = 0; };
  for (int i = 0; i < n; ++i) wall(i, 0), wall(i, n - 1), wall(0, i), wall(n - 1, i);
  for (int i = 80; i <= 100; ++i) wall(i, 80), wall(i, 100), wall(80, i), wall(100, i);
  std::ofstream(dir + "/box.pgm", std::ios::binary) << "P5\n" << n << " " << n << "\n255\n" << px;
  std::ofstream(dir + "/box.yaml") << "format: 1\nmap: box.pgm\nresolution: 0.05\norigin: [0, 0]\n";
  return dir + "/box.yaml";
}

}  // namespace

TEST(PatrolRun, AGoalThatCannotBeReachedFailsItsLegAndThePatrolGoesOn) {
  // The box's inside has no route: that leg times out; the patrol goes on
  // to the reachable goal, and the run fails on the leg it could not do.
  const std::string text = "format: 1\nworld: " + roomWithClosedBox() + "\nprofile: " + kSrc +
                           "/ini/interbot.ini\nstart: [1, 1, 0]\npatrol:\n  - [3, 1, 0]\n"
                           "  - [4.5, 4.5, 0]\n  - [1, 1, 180]\nduration: 120\nleg_timeout: 20\n"
                           "end: true\n";
  const RunMetrics m = runScenario(parseScenario(text, "p.yaml", "."), RunOptions{});
  EXPECT_GE(m.legs_failed, 1u);
  EXPECT_GE(m.legs_completed, 2u) << "the reachable goals before and after it";
  EXPECT_FALSE(m.success);
  EXPECT_NE(m.outcome.find("patrol legs failed"), std::string::npos) << m.outcome;
  EXPECT_EQ(m.collisions, 0u);
}

// Issue 18: with nothing in the lidar's range (the middle of a 20 m room, the
// range cut to 3 m), the localiser weighs no scan and the estimate follows
// odometry; the run counts those scans and still gets where it was sent.
TEST(NothingInView, LocalisationFollowsOdometryAndTheRunSaysSo) {
  const std::string text =
      "format: 1\nworld: " + kSrc + "/maps/worlds/empty_room.yaml\nprofile: " + kSrc +
      "/ini/interbot.ini\nstart: [10, 10, 0]\ngoal: [12, 10, 0]\n" + "duration: 40\nend: true\n";
  RunOptions o;
  o.sets = {"sensor.laser.range_max=3"};
  const RunMetrics m = runScenario(parseScenario(text, "g.yaml", "."), o);
  EXPECT_GT(m.dead_reckoning_scans, 50u) << "10 scans a second, none with a return";
  EXPECT_EQ(m.collisions, 0u);
  // Interbot stops once its estimate is within goal_tolerance (0.5 m) of the
  // goal; dead reckoning over 2 m adds a few centimetres to that.
  EXPECT_LT(m.final_goal_error_m, 0.6) << m.outcome;
  o.sets = {};  // the full range sees the walls: every scan is weighed
  EXPECT_EQ(runScenario(parseScenario(text, "g.yaml", "."), o).dead_reckoning_scans, 0u);
}

// `goal: [x, y]` and `--goal x,y`: any heading will do. The robot stops at
// the goal as it stands instead of turning to a heading nobody asked for.
TEST(GoalWithoutHeading, IsReadAndReachedWithoutTurningAtTheGoal) {
  EXPECT_TRUE(std::isnan(parseGoalText("12,10")->phi));
  EXPECT_NEAR(parseGoalText("12,10,90")->phi, M_PI / 2, 1e-12);
  for (const char* bad : {"12,10,", "12;10", "12,10,90,1", "12", "12,nan"})
    EXPECT_FALSE(parseGoalText(bad)) << bad;
  EXPECT_FALSE(parsePoseText("12,10")) << "a start needs its heading";
  EXPECT_NEAR(parsePoseText("12,10,90")->phi, M_PI / 2, 1e-12);
  auto text = [](const std::string& goal) {
    return "format: 1\nworld: " + kSrc + "/maps/worlds/empty_room.yaml\nprofile: " + kSrc +
           "/ini/interbot.ini\nstart: [10, 10, 0]\ngoal: " + goal + "\nduration: 40\nend: true\n";
  };
  const Scenario any = parseScenario(text("[10, 13]"), "g.yaml", ".");
  ASSERT_TRUE(any.goal);
  EXPECT_TRUE(std::isnan(any.goal->phi));
  EXPECT_THROW(parseScenario(text("[13]"), "g.yaml", "."), carenav::InputError);
  // The robot starts facing +x and arrives facing +y: as fast as a goal
  // asking for +y, a turn faster than one asking for -y (or for +x, the
  // heading a missing one used to become).
  const RunMetrics m_any = runScenario(any, {});
  auto run = [&](const char* goal) {
    const RunMetrics m = runScenario(parseScenario(text(goal), "g.yaml", "."), {});
    EXPECT_TRUE(m.success) << goal << ": " << m.outcome;
    return m.duration_s;
  };
  EXPECT_TRUE(m_any.success) << m_any.outcome;
  EXPECT_LT(m_any.final_goal_error_m, 0.5);
  EXPECT_NEAR(m_any.duration_s, run("[10, 13, 90]"), 0.35);
  EXPECT_LT(m_any.duration_s + 0.5, run("[10, 13, 0]")) << "no turn at the goal";
  EXPECT_LT(m_any.duration_s + 1.0, run("[10, 13, 270]"));
}
