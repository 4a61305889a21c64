// `carenav navigate` on the shipped scenarios, in the simulator: the
// walker's safety behaviours and goal navigation, measured from the
// simulator's ground truth.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <optional>
#include <regex>

#include "cli_helpers.h"

using namespace carenav_test;

namespace {

const std::string kScenarios = kSrc + "/maps/scenarios/";

std::optional<double> jsonReal(const std::string& json, const std::string& key) {
  std::smatch m;
  if (!std::regex_search(json, m, std::regex("\"" + key + "\": (-?[0-9.]+(?:[eE][-+]?[0-9]+)?)")))
    return std::nullopt;
  return std::stod(m[1]);
}

bool jsonTrue(const std::string& json, const std::string& key) {
  return json.find("\"" + key + "\": true") != std::string::npos;
}

struct NavRun {
  RunResult r;
  std::string json;
};

NavRun navigate(const std::string& scenario, const std::vector<std::string>& extra = {}) {
  std::vector<std::string> args = {"-q", "navigate", "--scenario", kScenarios + scenario, "--json"};
  args.insert(args.end(), extra.begin(), extra.end());
  NavRun run{carenav(args), ""};
  run.json = run.r.out;
  return run;
}

/** Last value of a column of navlog.csv. */
std::vector<std::vector<std::string>> readCsv(const fs::path& p) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(slurp(p));
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::string cell;
    bool quoted = false;
    for (char c : line) {
      if (c == '"')
        quoted = !quoted;
      else if (c == ',' && !quoted) {
        cells.push_back(cell);
        cell.clear();
      } else
        cell += c;
    }
    cells.push_back(cell);
    rows.push_back(cells);
  }
  return rows;
}

}  // namespace

TEST(CliNavigate, HelpListsThePlugins) {
  const RunResult r = carenav({"navigate", "--help"});
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("user-intent-dwa"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("goal-dwa"), std::string::npos);
  EXPECT_EQ(carenav({"navigate"}).code, 2);  // neither --scenario nor --suite
}

// The walker is pushed towards stairs going down: only the depth camera
// through the perception pipeline (RRT-GPD ground plane) sees the drop; the
// walker must stop before the edge without a collision.
TEST(CliNavigate, WalkerStopsBeforeStairsGoingDown) {
  const auto out = scratch() / "nav_stairs";
  fs::remove_all(out);
  const NavRun run = navigate("walker-stairs-down.yaml", {"--out", out.string()});
  ASSERT_EQ(run.r.code, 0) << run.r.err;
  EXPECT_TRUE(jsonTrue(run.json, "success")) << run.json;
  EXPECT_EQ(jsonReal(run.json, "collisions"), 0.0);
  EXPECT_GT(jsonReal(run.json, "depth_frames").value_or(0), 100.0);  // 10 Hz over 30 s
  // The walker went towards the stairs (start x = 2, edge x = 6) and stopped.
  const auto rows = readCsv(out / "walker-stairs-down" / "navlog.csv");
  ASSERT_GT(rows.size(), 250u);
  const double final_x = std::stod(rows.back()[1]);
  EXPECT_GT(final_x, 4.0);
  EXPECT_LT(final_x + 0.25, 6.0);                         // the walker's front is short of the edge
  EXPECT_LT(std::abs(std::stod(rows.back()[11])), 0.02);  // and commanded to stop
  // The picture of the run is a PNG.
  EXPECT_EQ(slurp(out / "walker-stairs-down" / "run.png").substr(1, 3), "PNG");
}

TEST(CliNavigate, StartMovesAScenarioAndIsRefusedWithASuite) {
  // --start was ignored with --scenario: the run began at the file's start.
  const auto out = scratch() / "nav_start";
  fs::remove_all(out);
  const NavRun run =
      navigate("walker-corridor-free.yaml", {"--start", "2.5,1.4,10", "--out", out.string()});
  ASSERT_EQ(run.r.code, 0) << run.r.err;
  const auto rows = readCsv(out / "walker-corridor-free" / "navlog.csv");
  ASSERT_GT(rows.size(), 2u);
  EXPECT_NEAR(std::stod(rows[1][1]), 2.5, 0.05);  // truth_x of the first cycle
  EXPECT_NEAR(std::stod(rows[1][2]), 1.4, 0.05);
  const auto suite = carenav({"-q", "navigate", "--suite", kScenarios, "--start", "2,1,0"});
  EXPECT_EQ(suite.code, 2);
  EXPECT_NE(suite.err.find("--start goes with one --scenario"), std::string::npos) << suite.err;
}

// The walker starts 0.4-0.65 m from the stair edge (its front 0.15-0.4 m
// from it): the edge lies in the camera's blind zone, never seen; only the
// treads below are in view. Before, RRT-GPD took a tread for the floor, the
// treads were free and the walker went down the stairs (ending 8-9 m in);
// it must stay short of the edge (the world of walker-stairs-down.yaml).
TEST(CliNavigate, WalkerStartedAtAStairEdgeItCannotSeeStaysBeforeIt) {
  for (const double x : {5.35, 5.6}) {
    const auto dir = scratch() / ("nav_stairs_start_" + std::to_string(x));
    fs::remove_all(dir);
    fs::create_directories(dir);
    std::ofstream(dir / "near.yaml")
        << "format: 1\nworld: " << kSrc << "/maps/worlds/nav/stairs_down.yaml\nprofile: " << kSrc
        << "/ini/isr-aiwalker.ini\nstart: [" << x
        << ", 2.0, 0]\nintent_heading:\n  - [0, 0.3, 0]\n"
           "duration: 15\nend: true\n";
    const RunResult r = carenav({"-q", "navigate", "--scenario", (dir / "near.yaml").string(),
                                 "--json", "--out", (dir / "out").string()});
    ASSERT_EQ(r.code, 0) << r.err;
    const auto rows = readCsv(dir / "out" / "near" / "navlog.csv");
    ASSERT_GT(rows.size(), 100u);
    double front = 0;
    for (size_t k = 1; k < rows.size(); ++k) front = std::max(front, std::stod(rows[k][1]) + 0.25);
    EXPECT_LT(front, 6.0) << "start " << x;  // the walker's front never passed the edge
  }
}

// A forbidden region is entered when any part of the robot is in it: a
// walker standing with its front (0.25 m ahead of the axle) over a strip
// 0.1-0.2 m ahead of its centre has entered it (before, only the centre
// counted: a walker with its front wheels over a stair edge succeeded).
TEST(CliNavigate, AForbiddenRegionIsEnteredByAnyPartOfTheFootprint) {
  for (const double strip : {0.1, 0.3}) {  // under the front, then just ahead of it
    const auto dir = scratch() / ("nav_forbidden_" + std::to_string(strip));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const double x0 = 1.0 + strip, x1 = x0 + 0.1;
    std::ofstream(dir / "strip.yaml")
        << "format: 1\nworld: " << kSrc << "/maps/worlds/nav/corridor_boxes.yaml\nprofile: " << kSrc
        << "/ini/isr-aiwalker.ini\nstart: [1.0, 1.5, 0]\nintent:\n  - [0, 0, 0]\n"
        << "duration: 2\nforbidden:\n  - [[" << x0 << ", 0], [" << x1 << ", 0], [" << x1
        << ", 3], [" << x0 << ", 3]]\nend: true\n";
    const RunResult r = carenav({"-q", "navigate", "--scenario", (dir / "strip.yaml").string(),
                                 "--json", "--out", (dir / "out").string()});
    ASSERT_EQ(r.code, 0) << r.err;
    const bool under = strip < 0.25;
    EXPECT_EQ(r.out.find("entered a forbidden region") != std::string::npos, under) << r.out;
    EXPECT_EQ(jsonTrue(r.out, "success"), !under) << strip << r.out;
  }
}

// A free corridor: the user's command passes (intent fidelity ~0) and a
// closed door is refused even while the user keeps pushing towards it.
TEST(CliNavigate, WalkerFollowsAFreePathAndRefusesAClosedDoor) {
  NavRun run = navigate("walker-corridor-free.yaml");
  ASSERT_EQ(run.r.code, 0) << run.r.err;
  EXPECT_TRUE(jsonTrue(run.json, "success")) << run.json;
  EXPECT_LT(jsonReal(run.json, "intent_fidelity").value_or(1), 0.02) << run.json;
  EXPECT_GT(jsonReal(run.json, "path_length_m").value_or(0), 7.0);

  run = navigate("walker-closed-door.yaml");
  ASSERT_EQ(run.r.code, 0) << run.r.err;
  EXPECT_TRUE(jsonTrue(run.json, "success")) << run.json;
  EXPECT_EQ(jsonReal(run.json, "collisions"), 0.0);
  // From x = 5 towards the door at x = 8: it came close, and its front
  // (0.25 m ahead of the axle) stayed short of the door.
  EXPECT_GT(jsonReal(run.json, "path_length_m").value_or(0), 1.5) << run.json;
  EXPECT_LT(jsonReal(run.json, "path_length_m").value_or(9), 3.0 - 0.25) << run.json;
}

// Goal navigation (Interbot): past boxes the map does not show, localised on
// the map from the simulated laser; and a goal behind a closed door is not
// forced.
TEST(CliNavigate, GoalNavigationReachesTheGoalAndDoesNotForceAClosedDoor) {
  NavRun run = navigate("goal-corridor-boxes.yaml");
  ASSERT_EQ(run.r.code, 0) << run.r.err;
  EXPECT_TRUE(jsonTrue(run.json, "success")) << run.json;
  EXPECT_LT(jsonReal(run.json, "final_goal_error_m").value_or(9), 0.6);
  EXPECT_EQ(jsonReal(run.json, "collisions"), 0.0);

  run = navigate("goal-closed-door.yaml");
  ASSERT_EQ(run.r.code, 0) << run.r.err;
  EXPECT_NE(run.json.find("no route (as expected)"), std::string::npos) << run.json;
  EXPECT_LT(jsonReal(run.json, "path_length_m").value_or(9), 0.1);
}

// People: a person walking head-on along the robot's lane (the robot must
// move aside early: it is tracked and its lane kept out of the route), a
// person crossing in front of the walker, out of and back into its
// cameras' narrow view (hidden people are remembered), and the 80 cm door
// entered on its axis.
TEST(CliNavigate, PeopleAndTheDoorwayWithoutACollision) {
  for (const auto& [scenario, plugin] :
       std::vector<std::pair<std::string, std::string>>{{"goal-person-towards.yaml", "goal-dwa"},
                                                        {"walker-person-crossing.yaml", ""},
                                                        {"goal-doorway.yaml", "goal-dwa"}}) {
    std::vector<std::string> extra;
    if (!plugin.empty()) extra = {"--plugin", plugin};
    const NavRun run = navigate(scenario, extra);
    ASSERT_EQ(run.r.code, 0) << scenario << ": " << run.r.err;
    EXPECT_TRUE(jsonTrue(run.json, "success")) << scenario << ": " << run.json;
    EXPECT_EQ(jsonReal(run.json, "collisions"), 0.0) << scenario;
  }
  // Without tracking (and so without remembering hidden people) the walker
  // meets the person.
  NavRun off = navigate("walker-person-crossing.yaml", {"--set", "navigation.predict_horizon=0"});
  ASSERT_EQ(off.r.code, 0) << off.r.err;
  EXPECT_GT(jsonReal(off.json, "collisions").value_or(0), 0.0) << off.json;
  // Cutting the corner to the door (no approach on its axis) brings the
  // robot's corner to the jamb. With contact tested on 5 cm cells that
  // wedged it (a post sharing a cell with the outline stopped every move);
  // measured to the sensed points it slides past and reaches the goal.
  off = navigate("goal-doorway.yaml", {"--plugin", "goal-dwa", "--set", "navigation.corner_deg=0"});
  ASSERT_EQ(off.r.code, 0) << off.r.err;
  EXPECT_TRUE(jsonTrue(off.json, "success")) << off.json;
  EXPECT_EQ(jsonReal(off.json, "collisions"), 0.0) << off.json;
}

// The mrpt-ptg plugin (MRPT's TP-space reactive navigation) on the same
// corridor: it reaches the goal past the unmapped boxes without a collision.
TEST(CliNavigate, MrptPtgPluginReachesTheCorridorGoal) {
  const NavRun run = navigate("goal-corridor-boxes.yaml", {"--plugin", "mrpt-ptg"});
  ASSERT_EQ(run.r.code, 0) << run.r.err;
  EXPECT_NE(run.json.find("\"plugin\": \"mrpt-ptg\""), std::string::npos) << run.json;
  EXPECT_TRUE(jsonTrue(run.json, "success")) << run.json;
  EXPECT_LT(jsonReal(run.json, "final_goal_error_m").value_or(9), 0.6);
  EXPECT_EQ(jsonReal(run.json, "collisions"), 0.0);
  EXPECT_GT(jsonReal(run.json, "path_length_m").value_or(0), 5.0);
}

// Goals by name (issue 7): a place of the places file beside the world.
TEST(CliNavigate, GoalByPlaceName) {
  const auto dir = scratch() / "nav_places";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "s.yaml") << "format: 1\nworld: " << kSrc
                                << "/maps/worlds/nav/corridor.yaml\nprofile: " << kSrc
                                << "/ini/interbot.ini\nplaces: places.yaml\nstart: [1, 1.5, 0]\n"
                                   "goal: [3, 1.5, 0]\nduration: 90\nend: true\n";
  ASSERT_EQ(carenav({"places", "add-room", "Far end", "--rect", "10.5,0.2,13.8,2.8", "--file",
                     (dir / "places.yaml").string()})
                .code,
            0);
  ASSERT_EQ(carenav({"places", "add-place", "Window", "--pose", "12.5,1.5,0", "--file",
                     (dir / "places.yaml").string()})
                .code,
            0);
  RunResult r = carenav({"-q", "navigate", "--scenario", (dir / "s.yaml").string(), "--goal",
                         "far end/window", "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("\"goal_name\": \"Far end/Window\""), std::string::npos) << r.out;
  EXPECT_TRUE(jsonTrue(r.out, "success")) << r.out;
  EXPECT_LT(jsonReal(r.out, "final_goal_error_m").value_or(9), 0.6) << r.out;
  // An unknown name: exit 2, nothing run.
  r = carenav({"-q", "navigate", "--scenario", (dir / "s.yaml").string(), "--goal", "Kitchen"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("Kitchen"), std::string::npos) << r.err;
}

// The safety supervisor in closed loop: when the user's command stops
// arriving the walker stops.
// Success is judged at the end from the simulator's truth: a run is not
// "goal reached" once the robot touched something or drove off the map.
TEST(CliNavigate, TheFirstCollisionEndsTheRunUnlessToldToContinue) {
  // Without tracking the walker meets the crossing person (60 s scenario).
  const auto dir = scratch() / "nav_collision";
  fs::remove_all(dir);
  const std::vector<std::string> off = {"--set", "navigation.predict_horizon=0", "--out",
                                        dir.string()};
  const NavRun first = navigate("walker-person-crossing.yaml", off);
  ASSERT_EQ(first.r.code, 0) << first.r.err;
  EXPECT_FALSE(jsonTrue(first.json, "success")) << first.json;
  EXPECT_EQ(jsonReal(first.json, "collisions"), 1.0) << first.json;
  EXPECT_NE(first.json.find("\"outcome\": \"1 collision(s)\""), std::string::npos);
  const double ended = jsonReal(first.json, "duration_s").value_or(0);
  EXPECT_LT(ended, 50.0) << "the run goes on after the collision";
  // The navlog's last cycle is the collision, flagged.
  const auto rows = readCsv(dir / "walker-person-crossing" / "navlog.csv");
  ASSERT_GT(rows.size(), 2u);
  ASSERT_EQ(rows.front()[18], "collision");
  EXPECT_EQ(rows.back()[18], "1");
  EXPECT_EQ(rows[rows.size() - 2][18], "0");
  std::vector<std::string> go_on = off;
  go_on.push_back("--continue-after-collision");
  const NavRun all = navigate("walker-person-crossing.yaml", go_on);
  ASSERT_EQ(all.r.code, 0) << all.r.err;
  EXPECT_FALSE(jsonTrue(all.json, "success"));
  EXPECT_GE(jsonReal(all.json, "collisions").value_or(0), 1.0);
  EXPECT_GT(jsonReal(all.json, "duration_s").value_or(0), ended + 20.0) << all.json;
}

TEST(CliNavigate, LeavingTheMapIsAFailure) {
  // A 4 m x 4 m map without walls; the user pushes the walker on past its edge.
  const auto dir = scratch() / "nav_off_map";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "open.pgm", std::ios::binary) << "P5\n80 80\n255\n"
                                                    << std::string(80 * 80, '\xff');
  std::ofstream(dir / "open.yaml")
      << "format: 1\nmap: open.pgm\nresolution: 0.05\norigin: [0, 0]\n";
  std::ofstream(dir / "s.yaml") << "format: 1\nworld: open.yaml\nprofile: " << kSrc
                                << "/ini/isr-aiwalker.ini\nstart: [1, 2, 0]\n"
                                   "intent_heading:\n  - [0, 0.3, 0]\nduration: 15\nend: true\n";
  const RunResult r = carenav(
      {"-q", "navigate", "--scenario", (dir / "s.yaml").string(), "--json", "--out", dir.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_FALSE(jsonTrue(r.out, "success")) << r.out;
  EXPECT_TRUE(jsonTrue(r.out, "left_map")) << r.out;
  EXPECT_NE(r.out.find("\"outcome\": \"left the map\""), std::string::npos) << r.out;
  EXPECT_EQ(jsonReal(r.out, "collisions"), 0.0);
  const auto rows = readCsv(dir / "s" / "navlog.csv");
  ASSERT_GT(rows.size(), 2u);
  EXPECT_GT(std::stod(rows.back()[1]), 4.0) << "the walker did drive off the map";
}

TEST(CliNavigate, WalkerStopsWhenTheUserStopsCommanding) {
  const auto dir = scratch() / "nav_stale";
  fs::remove_all(dir);
  fs::create_directories(dir);
  // The user pushes for 4 s, then lets go.
  std::ofstream(dir / "s.yaml")
      << "format: 1\nworld: " << kSrc << "/maps/worlds/nav/corridor.yaml\nprofile: " << kSrc
      << "/ini/isr-aiwalker.ini\nstart: [2, 1.5, 0]\n"
         "intent:\n  - [0, 0.3, 0]\n  - [4, 0, 0]\nduration: 8\nend: true\n";
  const RunResult r =
      carenav({"-q", "navigate", "--scenario", (dir / "s.yaml").string(), "--out", dir.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto rows = readCsv(dir / "s" / "navlog.csv");
  ASSERT_GT(rows.size(), 70u);
  // After the user let go, every command is a stop and the walker comes to rest.
  for (const auto& row : rows)
    if (row[0] != "t" && std::stod(row[0]) > 4.15) {
      EXPECT_EQ(row[13], "stop") << row[0];
      EXPECT_EQ(std::stod(row[11]), 0.0);
    }
  EXPECT_NE(rows.back()[14].find("user stopped"), std::string::npos);
}

TEST(CliNavigate, BadScenarioFilesExitTwoWithTheLine) {
  const auto dir = scratch() / "nav_bad";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string head = "format: 1\nworld: " + kSrc +
                           "/maps/worlds/nav/corridor.yaml\nprofile: " + kSrc +
                           "/ini/isr-aiwalker.ini\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"empty.yaml", ""},
      {"truncated.yaml", head + "start: [2, 1.5, 0]\nintent:\n  - [0, 0.3, 0]\n"},
      {"unknown.yaml",
       head + "start: [2, 1.5, 0]\nspeed: 3\nintent:\n  - [0, 0.3, 0]\nend: true\n"},
      {"badnum.yaml", head + "start: [2, x, 0]\nintent:\n  - [0, 0.3, 0]\nend: true\n"},
      {"both.yaml",
       head + "start: [2, 1.5, 0]\ngoal: [5, 1.5, 0]\nintent:\n  - [0, 0.3, 0]\nend: true\n"},
      {"wall.yaml", head + "start: [0.02, 1.5, 0]\nintent:\n  - [0, 0.3, 0]\nend: true\n"},
  };
  for (const auto& [name, text] : cases) {
    std::ofstream(dir / name) << text;
    const RunResult r = carenav({"navigate", "--scenario", (dir / name).string()});
    EXPECT_EQ(r.code, 2) << name << ": " << r.err;
    EXPECT_NE(r.err.find(name), std::string::npos) << name << ": " << r.err;
  }
  // The wrong plugin for the scenario's kind.
  const RunResult r = carenav(
      {"navigate", "--scenario", kScenarios + "walker-corridor-free.yaml", "--plugin", "goal-dwa"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("user-intent-dwa"), std::string::npos) << r.err;
  EXPECT_EQ(carenav({"navigate", "--scenario", kScenarios + "walker-corridor-free.yaml", "--plugin",
                     "teb"})
                .code,
            2);
}

// ------------------------------------------------------------ the live app

TEST(CliNavigateLive, ScriptedUserInAWorldAndItsLogReplaysTheRun) {
  const auto d = scratch() / "live_csv";
  fs::remove_all(d);
  fs::create_directories(d);
  // The user walks down the corridor, turns towards the wall and keeps pushing.
  std::ofstream(d / "user.csv") << "t,v,w\n0,0.3,0\n6,0.3,0.6\n9,0.3,0\n16,0,0\n";
  const std::string world = kSrc + "/maps/worlds/nav/corridor.yaml";
  const RunResult r = carenav({"-q", "navigate", "--world", world, "--start", "1.0,1.5,0",
                               "--intent", "csv:" + (d / "user.csv").string(), "--speed", "0",
                               "--json", "--out", (d / "a").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(jsonNumber(r.out, "collisions"), 0u) << "pushed at the wall, it must not hit it";
  EXPECT_GT(jsonReal(r.out, "path_length_m").value_or(0), 1.5) << "it followed the user first";
  const auto a = readCsv(d / "a" / "navlog.csv");
  ASSERT_GT(a.size(), 100u);
  // Turned towards the wall and still pushed: the walker keeps its distance.
  EXPECT_GT(jsonReal(r.out, "min_clearance_m").value_or(0), 0.0);
  EXPECT_EQ(a[1][7], "0.300") << "the user's command is in the log";
  // The log replays: the same user commands drive the same path.
  const RunResult r2 = carenav({"-q", "navigate", "--world", world, "--start", "1.0,1.5,0",
                                "--intent", "csv:" + (d / "a" / "navlog.csv").string(), "--speed",
                                "0", "--json", "--out", (d / "b").string()});
  ASSERT_EQ(r2.code, 0) << r2.err;
  const auto b = readCsv(d / "b" / "navlog.csv");
  ASSERT_GE(b.size(), a.size() - 1);
  for (size_t i = 1; i + 1 < a.size(); ++i)
    ASSERT_EQ(a[i][1] + "," + a[i][2], b[i][1] + "," + b[i][2]) << "row " << i;
}

TEST(CliNavigateLive, RealTimePaceAndTheScenarioWorld) {
  const auto d = scratch() / "live_pace";
  fs::create_directories(d);
  std::ofstream(d / "user.csv") << "0,0.3,0\n2,0,0\n";
  const RunResult r =
      carenav({"-q", "navigate", "--scenario", kScenarios + "walker-corridor-free.yaml", "--intent",
               "csv:" + (d / "user.csv").string(), "--speed", "1", "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  // Paced at real time, 2 s of script cannot end sooner in wall time.
  EXPECT_GE(jsonReal(r.out, "wall_seconds").value_or(0), 1.9);
  EXPECT_GT(jsonReal(r.out, "path_length_m").value_or(0), 0.2);
  EXPECT_TRUE(jsonTrue(r.out, "success")) << "a live user need not reach the scenario's target";
}

TEST(CliNavigateLive, BadIntentSourcesExitTwo) {
  const auto d = scratch() / "live_bad";
  fs::create_directories(d);
  std::ofstream(d / "bad.csv") << "t,v,w\n0,0.3,0\n1,0.3\n";
  const std::string world = kSrc + "/maps/worlds/nav/corridor.yaml";
  RunResult r = carenav({"navigate", "--world", world, "--start", "1.0,1.5,0", "--intent",
                         "csv:" + (d / "bad.csv").string(), "--speed", "0"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("bad.csv:3:"), std::string::npos) << r.err;
  r = shell(quote(kBin) + " navigate --world " + quote(world) +
            " --start 1.0,1.5,0 --intent keyboard --speed 0 </dev/null");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("not a terminal"), std::string::npos) << r.err;
  r = carenav({"navigate", "--world", world, "--start", "0.1,0.1,0", "--intent",
               "csv:" + (d / "bad.csv").string()});
  EXPECT_EQ(r.code, 2) << "start on the wall, or the bad script: either is bad input";
  r = carenav({"navigate", "--world", world, "--start", "1.0,1.5", "--intent", "keyboard"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("x,y,deg"), std::string::npos) << r.err;
}
