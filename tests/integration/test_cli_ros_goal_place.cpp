// `carenav ros navigate` takes a goal by place name on `~goal_place`
// (std_msgs/String), resolved in the places file beside the map as
// `carenav navigate --goal NAME`: an unknown name is a warning on `~status`
// and the robot does not move; a known one is driven to (sim + navigate on
// a real ROS master, 0 collisions). Skipped without the ROS part.
#include "cli_helpers.h"
#include "ros_skip.h"

#ifdef CARENAV_TEST_WITH_ROS
#include <geometry_msgs/Twist.h>
#include <std_msgs/String.h>

#include <algorithm>
#include <cmath>
#include <regex>

#include "ros_nodes_helpers.h"
#endif

namespace {

using namespace carenav_test;

#ifdef CARENAV_TEST_WITH_ROS
using namespace carenav_ros_test;

const std::string kInterbot = kSrc + "/ini/interbot.ini";

/** The apartment world copied to `dir` with a places file beside it: the
 *  living room and its sofa at (3.5, 3.8, 90 deg). */
fs::path apartmentWithPlaces(const fs::path& dir) {
  return apartmentWith(dir, {{"Living room", "0.2,0.2,4.6,7.5"}}, {{"Sofa", "3.5,3.8,90"}});
}

bool anyStatus(const TopicLog<std_msgs::String>& log, const std::string& text) {
  const auto all = log.all();
  return std::any_of(all.begin(), all.end(),
                     [&](const auto& m) { return m.data.find(text) != std::string::npos; });
}

#endif

TEST(CliRosGoalPlace, UnknownPlaceWarnsKnownPlaceIsReached) {
  SKIP_WITHOUT_ROS();
#ifdef CARENAV_TEST_WITH_ROS
  ASSERT_TRUE(sharedMaster().up()) << slurp(sharedMaster().dir() / "master.log");
  const fs::path dir = testDir();
  const fs::path world = apartmentWithPlaces(dir);
  const std::string nav_name =
      "navigate_" + std::string(testing::UnitTest::GetInstance()->current_test_info()->name());
  TopicLog<std_msgs::String> status(nav_name + "/status");
  TopicLog<geometry_msgs::Twist> cmds("cmd_vel");
  ::ros::NodeHandle nh;
  auto place = nh.advertise<std_msgs::String>(nav_name + "/goal_place", 2);
  ::ros::AsyncSpinner spinner(1);
  spinner.start();
  const pid_t sim =
      startRosNode(dir, "sim",
                   {"--profile", kInterbot, "--world", world.string(), "--start", "1.5,1.5,0",
                    "--duration", "150", "--summary", (dir / "sim.json").string()});
  const auto out = dir / "nav";
  const pid_t nav = startRosNode(dir, "navigate",
                                 {"--profile", kInterbot, "--world", world.string(), "--start",
                                  "1.5,1.5,0", "--duration", "120", "--out", out.string()});
  while (!(place.getNumSubscribers() > 0 && anyStatus(status, "waiting for a goal")) &&
         running(nav))
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  std_msgs::String name;
  name.data = "Kitchen";
  place.publish(name);
  while (!anyStatus(status, "warning: goal place 'Kitchen'") && running(nav))
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  std::this_thread::sleep_for(std::chrono::seconds(1));  // ten control periods
  const auto before = cmds.all();
  EXPECT_GT(before.size(), 5u) << "navigate publishes cmd_vel while it waits";
  for (const auto& c : before) EXPECT_EQ(c.linear.x, 0.0) << "no motion for an unknown place";
  name.data = "living room/sofa";
  place.publish(name);
  const int code = waitExit(nav);  // the goal reached ends the run
  ::kill(sim, SIGINT);
  EXPECT_EQ(waitExit(sim), 0) << slurp(dir / "sim.log");
  spinner.stop();
  EXPECT_EQ(code, 0) << slurp(dir / "navigate.log");
  for (const auto& s : status.all()) std::cout << "status: " << s.data << "\n";
  EXPECT_TRUE(anyStatus(status, "goal accepted: Living room/Sofa"));
  EXPECT_TRUE(anyStatus(status, "goal reached"));
  const std::string truth = slurp(dir / "sim.json");
  EXPECT_NE(truth.find("\"collisions\": 0"), std::string::npos) << truth;
  std::smatch mx, my;
  ASSERT_TRUE(std::regex_search(truth, mx, std::regex("\"x\": ([-0-9.e]+)"))) << truth;
  ASSERT_TRUE(std::regex_search(truth, my, std::regex("\"y\": ([-0-9.e]+)"))) << truth;
  EXPECT_LT(std::hypot(std::stod(mx[1]) - 3.5, std::stod(my[1]) - 3.8), 0.6)
      << "the true pose is at the sofa";
#endif
}

}  // namespace
