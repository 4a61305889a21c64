// Suites: the scenario files of a folder, RunMetrics through JSON, and runs in
// child processes whose metrics come back whole.
#include <carenav/common/json.h>
#include <carenav/localization/localization_params.h>
#include <carenav/navigation/navigation_params.h>
#include <carenav/perception/perception_params.h>
#include <carenav/runtime/suite.h>
#include <carenav/sim/sim_params.h>
#include <carenav/slam/slam_params.h>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include <unistd.h>

namespace nav = carenav::navigation;
namespace fs = std::filesystem;

namespace {

const std::string kScenarios = std::string(CARENAV_SOURCE_DIR) + "/maps/scenarios/";

nav::RunMetrics sample() {
  nav::RunMetrics m;
  m.scenario = "s\xc3\xa9";
  m.plugin = "goal-dwa";
  m.goal_name = "kitchen/table";
  m.success = true;
  m.outcome = "goal reached";
  m.collisions = 3;
  m.min_clearance_m = std::numeric_limits<double>::infinity();
  m.mean_clearance_m = 0.1;
  m.duration_s = 1137834225.973759;
  m.intent_fidelity = std::nan("");
  m.cycles = 1u << 20;
  m.entered_forbidden = true;
  m.left_map = true;
  m.recoveries = 2;
  m.outputs = {"a/run.png", "a/summary.json"};
  return m;
}

/** The profile sections a scenario's profile holds (main() registers them in
 *  the binary). */
void registerSections() {
  static const bool once = [] {
    carenav::slam::registerProfileSections();
    carenav::localization::registerProfileSections();
    nav::registerProfileSections();
    carenav::perception::registerProfileSections();
    carenav::sim::registerProfileSections();
    return true;
  }();
  (void)once;
}

}  // namespace

TEST(RunMetricsJson, CompleteRecordReadsBackWhole) {
  const nav::RunMetrics m = sample();
  const nav::RunMetrics b = nav::RunMetrics::fromJson(
      carenav::parseJson(carenav::dumpJson(m.toJsonValue(true), false), "test"));
  EXPECT_EQ(b.scenario, m.scenario);
  EXPECT_EQ(b.goal_name, m.goal_name);
  EXPECT_TRUE(b.success);
  EXPECT_EQ(b.outcome, m.outcome);
  EXPECT_EQ(b.collisions, 3u);
  EXPECT_TRUE(std::isinf(b.min_clearance_m));
  EXPECT_EQ(b.mean_clearance_m, 0.1);
  EXPECT_EQ(b.duration_s, m.duration_s);
  EXPECT_TRUE(std::isnan(b.intent_fidelity));
  EXPECT_EQ(b.cycles, m.cycles);
  EXPECT_TRUE(b.entered_forbidden);
  EXPECT_TRUE(b.left_map);
  EXPECT_EQ(b.recoveries, 2u);
  EXPECT_EQ(b.outputs, m.outputs);
}

// Every key the record writes is read back: each value is replaced by one
// no default has, and must come back as it went (a field added to toJson but
// not to fromJson fails here).
TEST(RunMetricsJson, EveryKeyWrittenIsReadBack) {
  carenav::Json j = sample().toJsonValue(true);
  for (auto& [key, v] : j.items()) {
    if (v.is_boolean())
      v = !v.get<bool>();
    else if (v.is_number_unsigned() || v.is_number_integer())
      v = 7u;
    else if (v.is_number() || v.is_null())
      v = 7.25;
    else if (v.is_string())
      v = "s-" + key;
    else if (v.is_array() && !v.empty() && v[0].is_string())
      v = carenav::Json::array({"a", "b"});
    else if (v.is_array())
      v = carenav::Json::array({1.5, 2.5});
    else
      ADD_FAILURE() << key << ": " << v;
  }
  EXPECT_EQ(nav::RunMetrics::fromJson(j).toJsonValue(true), j);
}

TEST(RunMetricsJson, SummaryKeepsItsKeysAndTypes) {
  const carenav::Json j = sample().toJsonValue();
  EXPECT_FALSE(j.contains("outputs"));
  EXPECT_FALSE(j.contains("entered_forbidden"));
  EXPECT_EQ(j.at("min_clearance_m"), 0.0);         // no obstacle seen: 0, as always
  EXPECT_TRUE(j.at("intent_fidelity").is_null());  // NaN: null
  EXPECT_TRUE(j.at("collisions").is_number_unsigned());
  EXPECT_TRUE(j.at("success").is_boolean());
  EXPECT_EQ(j.begin().key(), "scenario");
  const std::string text = sample().toJson();
  EXPECT_NE(text.find("\"collisions\": 3,"), std::string::npos) << text;
  EXPECT_NE(text.find("\"success\": true,"), std::string::npos) << text;
}

TEST(RunMetricsJson, AValueOfTheWrongTypeIsBadInput) {
  EXPECT_THROW(nav::RunMetrics::fromJson(carenav::Json{{"collisions", "three"}}),
               carenav::InputError);
  EXPECT_THROW(nav::RunMetrics::fromJson(carenav::Json::array()), carenav::InputError);
}

TEST(Suite, FilesAreTheSortedScenariosWithoutPlacesOrWorldFiles) {
  const fs::path d = fs::temp_directory_path() / ("carenav_suite_" + std::to_string(getpid()));
  fs::create_directories(d);
  for (const char* f : {"b.yaml", "a.yaml", "w.places.yaml", "notes.txt"}) std::ofstream(d / f);
  // A world beside its scenarios is not one of them.
  std::ofstream(d / "w.yaml") << "# carenav world\nformat: 1\nmap: w.png\nresolution: 0.05\n";
  std::ofstream(d / "c.yaml") << "format: 1\nworld: w.yaml\nstart: [1, 1, 0]\nend: true\n";
  const auto files = nav::suiteFiles(d.string());
  ASSERT_EQ(files.size(), 3u);
  EXPECT_EQ(fs::path(files[0]).filename(), "a.yaml");
  EXPECT_EQ(fs::path(files[1]).filename(), "b.yaml");
  EXPECT_EQ(fs::path(files[2]).filename(), "c.yaml");
  for (const char* f : {"a.yaml", "b.yaml", "c.yaml"}) fs::remove(d / f);
  EXPECT_THROW(nav::suiteFiles(d.string()), carenav::InputError);
  EXPECT_THROW(nav::suiteFiles((d / "w.places.yaml").string()), carenav::InputError);
  fs::remove_all(d);
}

// Two plugins side by side: each run in a child, the walker's metrics come
// back through JSON, the goal plugin that does not fit the walker scenario is
// skipped, not an error.
TEST(Suite, SideBySideRunsInChildrenAndSkipsAPluginThatDoesNotFit) {
  registerSections();
  const std::vector<nav::Scenario> scenarios = {
      nav::readScenario(kScenarios + "walker-wall-push.yaml")};
  nav::RunOptions base;
  base.duration = 3.0;
  const auto runs = nav::runSuite(scenarios, {"user-intent-dwa", "goal-dwa"}, base);
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0].scenario, "walker-wall-push");
  EXPECT_EQ(runs[0].plugin, "user-intent-dwa");
  EXPECT_GT(runs[0].cycles, 20u);  // 3 s at 10 Hz
  EXPECT_GT(runs[0].path_length_m, 0.3);
  EXPECT_EQ(runs[0].collisions, 0u);
  // Alone, the plugin that does not fit is the user's error.
  EXPECT_THROW(nav::runSuite(scenarios, {"goal-dwa"}, base), nav::PluginMismatchError);
  // A suite runs as fast as it can.
  base.speed = 1;
  EXPECT_THROW(nav::runSuite(scenarios, {"user-intent-dwa", "goal-dwa"}, base),
               carenav::InputError);
}
