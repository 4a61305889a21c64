// carenav's ROS nodes on a real ROS master (rosmaster on a free loopback
// port, never the default 11311): `carenav ros sim` + `carenav ros
// navigate` drive Interbot to a goal in the apartment world with 0
// collisions (the simulator's ground truth); killing the sim makes navigate
// publish zero velocity within sensor_timeout + one control period (cmd_vel
// as received by this test's own subscriber). Skipped without the ROS part.
#include "cli_helpers.h"
#include "ros_skip.h"

#ifdef CARENAV_TEST_WITH_ROS
#include <geometry_msgs/Twist.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>

#include <mutex>

#include "ros_nodes_helpers.h"
#endif

namespace {

using namespace carenav_test;

#ifdef CARENAV_TEST_WITH_ROS
using namespace carenav_ros_test;

const std::string kApartment = kSrc + "/maps/worlds/apartment.yaml";
const std::string kInterbot = kSrc + "/ini/interbot.ini";

pid_t startSim(const fs::path& dir, const std::string& start) {
  return spawn({kBin, "-q", "ros", "sim", "--profile", kInterbot, "--world", kApartment, "--start",
                start, "--duration", "150", "--summary", (dir / "sim.json").string(), "--record",
                (dir / "sim.bag").string()},
               dir / "sim.log");
}

#endif

TEST(CliRosNodes, SimAndNavigateReachTheGoalWithoutCollision) {
  SKIP_WITHOUT_ROS();
#ifdef CARENAV_TEST_WITH_ROS
  ASSERT_TRUE(sharedMaster().up()) << slurp(sharedMaster().dir() / "master.log");
  const fs::path dir = testDir();
  const pid_t sim = startSim(dir, "1.5,1.5,0");
  const auto out = dir / "nav";
  // --duration bounds the run (the node's own clock), not the test.
  const pid_t nav =
      spawn({kBin, "-q", "ros", "navigate", nodeName("navigate"), "--profile", kInterbot, "--world",
             kApartment, "--start", "1.5,1.5,0", "--goal", "3.5,3.8,90", "--duration", "120",
             "--out", out.string(), "_robot/v_max:=0.2"},
            dir / "nav.log");
  const int nav_code = waitExit(nav);
  ::kill(sim, SIGINT);
  EXPECT_EQ(waitExit(sim), 0) << slurp(dir / "sim.log");
  EXPECT_EQ(nav_code, 0) << slurp(dir / "nav.log");
  const std::string summary = slurp(out / "summary.json");
  EXPECT_NE(summary.find("\"outcome\": \"goal reached\""), std::string::npos) << summary;
  const std::string truth = slurp(dir / "sim.json");
  EXPECT_NE(truth.find("\"collisions\": 0"), std::string::npos) << truth;
  std::smatch mx, my;
  ASSERT_TRUE(std::regex_search(truth, mx, std::regex("\"x\": ([-0-9.e]+)"))) << truth;
  ASSERT_TRUE(std::regex_search(truth, my, std::regex("\"y\": ([-0-9.e]+)"))) << truth;
  EXPECT_LT(std::hypot(std::stod(mx[1]) - 3.5, std::stod(my[1]) - 3.8), 0.6)
      << "the true pose is at the goal (tolerance 0.5 m)";
  // ~robot/v_max (a private parameter) is the profile's [robot] v_max: 0.2, not 0.25.
  std::istringstream log(slurp(out / "navlog.csv"));
  std::string line;
  std::getline(log, line);
  double vmax = 0;
  while (std::getline(log, line)) {
    std::istringstream row(line);
    std::string cell;
    for (int i = 0; i <= 11; ++i) std::getline(row, cell, ',');
    vmax = std::max(vmax, std::stod(cell));
  }
  EXPECT_GT(vmax, 0.15);
  EXPECT_LE(vmax, 0.2 + 1e-9) << "~robot/v_max 0.2 is applied";
  // The run recorded by the sim maps as a bag: its scans, odometry and tf.
  const auto bag = dir / "sim.bag";
  const auto slam = carenav_test::carenav({"-q", "slam", "--profile", kInterbot, "--rawlog",
                                           bag.string(), "--out", (dir / "map").string()});
  EXPECT_EQ(slam.code, 0) << slam.err;
  const std::string map_summary = slurp(dir / "map" / "summary.json");
  EXPECT_GT(jsonNumber(map_summary, "steps"), 50u) << map_summary;
#endif
}

TEST(CliRosNodes, KillingTheSimStopsTheRobot) {
  SKIP_WITHOUT_ROS();
#ifdef CARENAV_TEST_WITH_ROS
  ASSERT_TRUE(sharedMaster().up()) << slurp(sharedMaster().dir() / "master.log");
  const fs::path dir = testDir();
  // This test's own subscriber: every cmd_vel with its arrival time.
  struct Cmd {
    std::chrono::steady_clock::time_point t;
    double v, w;
  };
  std::mutex mu;
  std::vector<Cmd> cmds;
  initTestNode();
  ::ros::NodeHandle nh;
  auto sub = nh.subscribe<geometry_msgs::Twist>(
      "cmd_vel", 100, [&](const geometry_msgs::Twist::ConstPtr& m) {
        std::lock_guard<std::mutex> l(mu);
        cmds.push_back({std::chrono::steady_clock::now(), m->linear.x, m->angular.z});
      });
  ::ros::AsyncSpinner spinner(1);
  spinner.start();
  const pid_t sim = startSim(dir, "1.0,1.5,0");
  const pid_t nav =
      spawn({kBin, "-q", "ros", "navigate", nodeName("navigate"), "--profile", kInterbot, "--world",
             kApartment, "--start", "1.0,1.5,0", "--goal", "4.2,1.5,0", "--duration", "60"},
            dir / "nav.log");
  // Until the robot drives (a command above 5 cm/s), then the sim is killed.
  auto moving = [&] {
    std::lock_guard<std::mutex> l(mu);
    return !cmds.empty() && cmds.back().v > 0.05;
  };
  while (!moving() && running(nav)) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  ASSERT_TRUE(moving()) << slurp(dir / "nav.log");
  ::kill(sim, SIGKILL);
  const auto killed = std::chrono::steady_clock::now();
  waitExit(sim);
  std::this_thread::sleep_for(std::chrono::seconds(2));
  ::kill(nav, SIGINT);
  waitExit(nav);
  spinner.stop();
  sub.shutdown();  // (the callbacks use this test's locals)
  // sensor_timeout 0.5 s + one control period 0.1 s (+ delivery): from then on zero.
  const auto bound = killed + std::chrono::milliseconds(750);
  std::lock_guard<std::mutex> l(mu);
  size_t after = 0;
  for (const auto& c : cmds) {
    if (c.t <= bound) continue;
    ++after;
    EXPECT_EQ(c.v, 0.0);
    EXPECT_EQ(c.w, 0.0);
  }
  EXPECT_GT(after, 5u) << "navigate goes on publishing (zero) every period";
  for (const auto& c : cmds)
    if (c.t > killed && c.v == 0 && c.w == 0) {
      std::cout << "first zero cmd_vel "
                << std::chrono::duration<double, std::milli>(c.t - killed).count()
                << " ms after the sim was killed\n";
      break;
    }
#endif
}

TEST(CliRosNodes, PrivateParametersAreProfileKeys) {
  SKIP_WITHOUT_ROS();
#ifdef CARENAV_TEST_WITH_ROS
  ASSERT_TRUE(sharedMaster().up()) << slurp(sharedMaster().dir() / "master.log");
  const fs::path dir = testDir();
  // ~navigation/no_such_key is [navigation] no_such_key: refused as the
  // profile refuses it (exit 2). (A parameter taken: the test above.)
  const pid_t bad =
      spawn({kBin, "-q", "ros", "navigate", nodeName("navigate"), "--profile", kInterbot, "--world",
             kApartment, "--start", "1.5,1.5,0", "_navigation/no_such_key:=1"},
            dir / "bad.log");
  EXPECT_EQ(waitExit(bad), 2) << slurp(dir / "bad.log");
  EXPECT_NE(slurp(dir / "bad.log").find("no_such_key"), std::string::npos)
      << slurp(dir / "bad.log");
#endif
}

TEST(CliRosNodes, SimLocalizeNavigateReachTheGoal) {
  SKIP_WITHOUT_ROS();
#ifdef CARENAV_TEST_WITH_ROS
  ASSERT_TRUE(sharedMaster().up()) << slurp(sharedMaster().dir() / "master.log");
  const fs::path dir = testDir();
  const pid_t sim = startSim(dir, "1.5,1.5,0");
  const pid_t loc = spawn({kBin, "-q", "ros", "localize", "--profile", kInterbot, "--world",
                           kApartment, "--start", "1.5,1.5,0"},
                          dir / "loc.log");
  // navigate is told a start 1 m off: only the localiser's amcl_pose takes
  // the robot to the goal in truth.
  const auto out = dir / "nav";
  const pid_t nav =
      spawn({kBin, "-q", "ros", "navigate", nodeName("navigate"), "--profile", kInterbot, "--world",
             kApartment, "--start", "1.5,2.5,0", "--goal", "3.5,3.8,90", "--external-pose",
             "--duration", "120", "--out", out.string()},
            dir / "nav.log");
  const int nav_code = waitExit(nav);
  ::kill(sim, SIGINT);
  ::kill(loc, SIGINT);
  EXPECT_EQ(waitExit(sim), 0) << slurp(dir / "sim.log");
  EXPECT_EQ(waitExit(loc), 0) << slurp(dir / "loc.log");
  EXPECT_EQ(nav_code, 0) << slurp(dir / "nav.log");
  const std::string truth = slurp(dir / "sim.json");
  EXPECT_NE(truth.find("\"collisions\": 0"), std::string::npos) << truth;
  std::smatch mx, my;
  ASSERT_TRUE(std::regex_search(truth, mx, std::regex("\"x\": ([-0-9.e]+)"))) << truth;
  ASSERT_TRUE(std::regex_search(truth, my, std::regex("\"y\": ([-0-9.e]+)"))) << truth;
  EXPECT_LT(std::hypot(std::stod(mx[1]) - 3.5, std::stod(my[1]) - 3.8), 0.6)
      << "the true pose is at the goal: navigate followed amcl_pose";
#endif
}

TEST(CliRosNodes, WalkerFollowsTheIntentTopic) {
  SKIP_WITHOUT_ROS();
#ifdef CARENAV_TEST_WITH_ROS
  ASSERT_TRUE(sharedMaster().up()) << slurp(sharedMaster().dir() / "master.log");
  const fs::path dir = testDir();
  initTestNode();
  ::ros::NodeHandle nh;
  auto intent = nh.advertise<geometry_msgs::Twist>("intent", 5);
  const pid_t sim = startSim(dir, "1.5,1.5,0");
  // Interbot driven as a walker (user-intent-dwa): the user's Twist on `intent`.
  const pid_t nav = spawn({kBin, "-q", "ros", "navigate", nodeName("navigate"), "--profile",
                           kInterbot, "--plugin", "user-intent-dwa", "--duration", "60"},
                          dir / "nav.log");
  while (intent.getNumSubscribers() == 0 && running(nav))
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  geometry_msgs::Twist push;
  push.linear.x = 0.2;
  const auto push0 = std::chrono::steady_clock::now();
  for (int i = 0; i < 40; ++i) {  // 4 s of pushing forwards, then the user lets go
    intent.publish(push);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  const double push_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - push0).count();
  std::this_thread::sleep_for(std::chrono::seconds(2));
  ::kill(sim, SIGINT);
  EXPECT_EQ(waitExit(sim), 0) << slurp(dir / "sim.log");
  ::kill(nav, SIGINT);
  waitExit(nav);
  const std::string truth = slurp(dir / "sim.json");
  EXPECT_NE(truth.find("\"collisions\": 0"), std::string::npos) << truth;
  std::smatch mx, my;
  ASSERT_TRUE(std::regex_search(truth, mx, std::regex("\"x\": ([-0-9.e]+)"))) << truth;
  ASSERT_TRUE(std::regex_search(truth, my, std::regex("\"y\": ([-0-9.e]+)"))) << truth;
  // 0.2 m/s while pushed and intent_timeout (0.5 s) after, straight on, then
  // it stands (2 s more at 0.2 m/s would be 0.4 m further).
  EXPECT_GT(std::stod(mx[1]), 1.5 + 0.4) << truth;
  EXPECT_LT(std::stod(mx[1]), 1.5 + 0.2 * (push_s + 0.5) + 0.1)
      << "it stands once the user lets go; pushed " << push_s << " s: " << truth;
  EXPECT_NEAR(std::stod(my[1]), 1.5, 0.1) << truth;
#endif
}

#ifdef CARENAV_TEST_WITH_ROS
/** What pushing the ISR-AIWALKER at the stairs gave: the farthest east its
 *  true centre got, the sim's summary and navigate's summary.json. */
struct StairsPush {
  double max_x = -1e9;
  std::string truth, summary;
};

/** ISR-AIWALKER (Kinect as `points`, or with `sim_extra` {"--depth"} as
 *  `depth/image` + `depth/camera_info`; Leddar as `scan_leddar`) pushed at
 *  0.3 m/s for 20 s at a staircase going down that starts at x = 6 m
 *  (walker-stairs-down.yaml), with `ros navigate` between the user and the
 *  base. */
StairsPush pushWalkerAtStairs(const fs::path& dir, std::vector<std::string> sim_extra = {}) {
  initTestNode();
  ::ros::NodeHandle nh;
  auto intent = nh.advertise<geometry_msgs::Twist>("intent", 5);
  // The farthest east the true walker got (the sim's ground_truth topic).
  std::mutex mu;
  StairsPush r;
  auto truth_sub = nh.subscribe<nav_msgs::Odometry>(
      "ground_truth", 100, [&](const nav_msgs::Odometry::ConstPtr& m) {
        std::lock_guard<std::mutex> l(mu);
        r.max_x = std::max(r.max_x, m->pose.pose.position.x);
      });
  ::ros::AsyncSpinner spinner(1);
  spinner.start();
  const std::string walker = kSrc + "/ini/isr-aiwalker.ini";
  std::vector<std::string> sim_args{
      kBin,         "-q",   "ros",        "sim",
      "--profile",  walker, "--scenario", kSrc + "/maps/scenarios/walker-stairs-down.yaml",
      "--duration", "150",  "--summary",  (dir / "sim.json").string()};
  sim_args.insert(sim_args.end(), sim_extra.begin(), sim_extra.end());
  const pid_t sim = spawn(sim_args, dir / "sim.log");
  const auto out = dir / "nav";
  const pid_t nav = spawn({kBin, "-q", "ros", "navigate", nodeName("navigate"), "--profile", walker,
                           "--duration", "120", "--out", out.string()},
                          dir / "nav.log");
  while (intent.getNumSubscribers() == 0 && running(nav))
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  geometry_msgs::Twist push;
  push.linear.x = 0.3;
  for (int i = 0; i < 200; ++i) {  // 20 s at 0.3 m/s would be 6 m: far past the edge
    intent.publish(push);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  ::kill(sim, SIGINT);
  EXPECT_EQ(waitExit(sim), 0) << slurp(dir / "sim.log");
  ::kill(nav, SIGINT);
  waitExit(nav);
  spinner.stop();
  truth_sub.shutdown();  // (the callback uses this function's locals)
  std::lock_guard<std::mutex> l(mu);
  r.truth = slurp(dir / "sim.json");
  r.summary = slurp(out / "summary.json");
  return r;
}
#endif

TEST(CliRosNodes, WalkerRefusesTheStairs) {
  SKIP_WITHOUT_ROS();
#ifdef CARENAV_TEST_WITH_ROS
  ASSERT_TRUE(sharedMaster().up()) << slurp(sharedMaster().dir() / "master.log");
  const fs::path dir = testDir();
  const auto [max_x, truth, summary] = pushWalkerAtStairs(dir);
  EXPECT_NE(truth.find("\"collisions\": 0"), std::string::npos) << truth;
  EXPECT_GT(max_x, 4.0) << "the walker walked towards the stairs: " << truth;
  EXPECT_LT(max_x, 6.0) << "its centre never reached the stairs (x >= 6 m): " << truth;
  std::cout << "farthest east: x = " << max_x << " m (the stairs begin at 6 m)\n";
  EXPECT_GT(jsonNumber(summary, "depth_frames"), 10u) << summary;
#endif
}

// The same walker with its Kinect as depth images and their CameraInfo
// (`ros sim --depth`) instead of clouds: it refuses the stairs as well.
TEST(CliRosNodes, WalkerOnDepthImagesRefusesTheStairs) {
  SKIP_WITHOUT_ROS();
#ifdef CARENAV_TEST_WITH_ROS
  ASSERT_TRUE(sharedMaster().up()) << slurp(sharedMaster().dir() / "master.log");
  const fs::path dir = testDir();
  const auto [max_x, truth, summary] = pushWalkerAtStairs(dir, {"--depth"});
  EXPECT_NE(truth.find("\"collisions\": 0"), std::string::npos) << truth;
  EXPECT_GT(max_x, 4.0) << "the walker walked towards the stairs: " << truth;
  EXPECT_LT(max_x, 6.0) << "its centre never reached the stairs (x >= 6 m): " << truth;
  std::cout << "farthest east on depth images: x = " << max_x << " m (the stairs begin at 6 m), "
            << jsonNumber(summary, "depth_frames") << " depth frames\n";
  EXPECT_GT(jsonNumber(summary, "depth_frames"), 10u)
      << "the images reached perception: " << summary;
#endif
}

}  // namespace
