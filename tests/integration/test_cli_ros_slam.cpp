// `carenav ros slam` on a real ROS master: `carenav ros sim` (Interbot in
// the apartment world) driven a short way by this test's cmd_vel; the slam
// node publishes a latched `map` with walls in it, saves on `~save` while
// running, and at SIGINT writes the outputs of `carenav slam`, which load.
// Skipped without the ROS part.
#include "cli_helpers.h"
#include "ros_skip.h"

#ifdef CARENAV_TEST_WITH_ROS
#include <carenav/io/map_io.h>
#include <carenav/io/trajectory.h>

#include <geometry_msgs/Twist.h>
#include <nav_msgs/OccupancyGrid.h>
#include <nav_msgs/Odometry.h>
#include <std_msgs/Empty.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>

#include "ros_nodes_helpers.h"
#endif

namespace {

using namespace carenav_test;

#ifdef CARENAV_TEST_WITH_ROS
using namespace carenav_ros_test;

const std::string kApartment = kSrc + "/maps/worlds/apartment.yaml";
const std::string kInterbot = kSrc + "/ini/interbot.ini";

size_t occupiedCells(const nav_msgs::OccupancyGrid& g) {
  return std::count_if(g.data.begin(), g.data.end(), [](int8_t v) { return v > 65; });
}

/** cmd_vel for `seconds` of this program's clock, every 0.1 s. */
void drive(::ros::Publisher& cmd, double v, double w, int tenths) {
  geometry_msgs::Twist t;
  t.linear.x = v;
  t.angular.z = w;
  for (int i = 0; i < tenths; ++i) {
    cmd.publish(t);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
}

/** `ros sim` (Interbot in the apartment at 1.5, 1.5, 0) and `ros slam`
 *  writing to DIR/map with `extra` arguments. */
std::pair<pid_t, pid_t> startSimAndSlam(const fs::path& dir, std::vector<std::string> extra) {
  const pid_t sim = startRosNode(
      dir, "sim",
      {"--profile", kInterbot, "--world", kApartment, "--start", "1.5,1.5,0", "--duration", "120"});
  std::vector<std::string> args{"--profile",  kInterbot, "--out", (dir / "map").string(),
                                "--duration", "100"};
  args.insert(args.end(), extra.begin(), extra.end());
  return {sim, startRosNode(dir, "slam", args)};
}

/** Ends both (SIGINT): each exits 0. */
void stopSimAndSlam(const fs::path& dir, std::pair<pid_t, pid_t> p) {
  ::kill(p.second, SIGINT);
  EXPECT_EQ(waitExit(p.second), 0) << slurp(dir / "slam.log");
  ::kill(p.first, SIGINT);
  EXPECT_EQ(waitExit(p.first), 0) << slurp(dir / "sim.log");
}

#endif

TEST(CliRosSlam, MapsAShortDriveAndSaves) {
  SKIP_WITHOUT_ROS();
#ifdef CARENAV_TEST_WITH_ROS
  ASSERT_TRUE(sharedMaster().up()) << slurp(sharedMaster().dir() / "master.log");
  const fs::path dir = testDir();
  TopicLog<nav_msgs::OccupancyGrid> maps("map");
  TopicLog<nav_msgs::Odometry> truth("ground_truth");
  ::ros::NodeHandle nh;
  auto cmd = nh.advertise<geometry_msgs::Twist>("cmd_vel", 5);
  const std::string name =
      "slam_" + std::string(testing::UnitTest::GetInstance()->current_test_info()->name());
  auto save = nh.advertise<std_msgs::Empty>(name + "/save", 1);
  ::ros::AsyncSpinner spinner(1);
  spinner.start();
  const auto out = dir / "map";
  const auto nodes = startSimAndSlam(dir, {"--map-every", "2"});
  const pid_t slam = nodes.second;
  while ((cmd.getNumSubscribers() == 0 || save.getNumSubscribers() == 0) && running(slam))
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  drive(cmd, 0.25, 0.0, 40);  // 1 m east
  drive(cmd, 0.15, 0.3, 30);  // a curve to the left
  save.publish(std_msgs::Empty());
  while (!fs::exists(out / "summary.json") && running(slam))
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_TRUE(fs::exists(out / "map.yaml")) << "~save wrote the outputs while running";
  drive(cmd, 0.2, 0.0, 20);
  stopSimAndSlam(dir, nodes);
  spinner.stop();
  // The latched map: published again as keyframes came, walls in it.
  ASSERT_GE(maps.count(), 2u) << slurp(dir / "slam.log");
  const auto map = maps.last();
  EXPECT_EQ(map->header.frame_id, "map");
  const size_t occ = occupiedCells(*map);
  std::cout << maps.count() << " map messages; the last " << map->info.width << " x "
            << map->info.height << " cells, " << occ << " occupied\n";
  EXPECT_GT(occ, 100u);
  // The outputs of `carenav slam`, and they load.
  for (const char* f : {"map.simplemap", "map.gridmap.gz", "map.yaml", "map.pgm", "map.png",
                        "trajectory.tum", "summary.json"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  const auto grid = carenav::io::loadGridMap((out / "map.yaml").string());
  EXPECT_GT(grid.getSizeX() * grid.getSizeY(), 1000u);
  EXPECT_NO_THROW(carenav::io::loadGridMap((out / "map.gridmap.gz").string()));
  const auto traj = carenav::io::readTum((out / "trajectory.tum").string());
  const std::string summary = slurp(out / "summary.json");
  EXPECT_GT(jsonNumber(summary, "steps"), 50u) << summary;
  EXPECT_EQ(traj.size(), jsonNumber(summary, "steps"));
  ASSERT_FALSE(traj.empty());
  ASSERT_TRUE(truth.last());
  std::cout << traj.size() << " scans mapped; last pose " << traj.back().x << ", " << traj.back().y
            << "; true " << truth.last()->pose.pose.position.x - 1.5 << ", "
            << truth.last()->pose.pose.position.y - 1.5 << "\n";
  // The map frame is where the robot started (1.5, 1.5, 0 in the world).
  const auto& p = truth.last()->pose.pose.position;
  EXPECT_GT(p.x - 1.5, 1.0) << "it drove east";
  EXPECT_LT(std::hypot(traj.back().x - (p.x - 1.5), traj.back().y - (p.y - 1.5)), 0.15)
      << "the mapped end pose is the true one";
#endif
}

// Without an Odometry topic (odom remapped to one nobody publishes) the
// odometry is the sim's odom -> base_link on tf: map -> odom then places
// the odometry frame (the world's, where odom starts at 1.5, 1.5) at
// (-1.5, -1.5) in the map (where the robot started); with no odometry at
// all it would be the mapper's own pose.
TEST(CliRosSlam, OdometryFromTfWithoutTheOdomTopic) {
  SKIP_WITHOUT_ROS();
#ifdef CARENAV_TEST_WITH_ROS
  ASSERT_TRUE(sharedMaster().up()) << slurp(sharedMaster().dir() / "master.log");
  const fs::path dir = testDir();
  TopicLog<tf2_msgs::TFMessage> tfs("tf");
  ::ros::NodeHandle nh;
  auto cmd = nh.advertise<geometry_msgs::Twist>("cmd_vel", 5);
  ::ros::AsyncSpinner spinner(1);
  spinner.start();
  const auto nodes = startSimAndSlam(dir, {"odom:=no_odometry_here"});
  while (cmd.getNumSubscribers() == 0 && running(nodes.second))
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  drive(cmd, 0.25, 0.0, 40);
  drive(cmd, 0.15, 0.3, 20);
  stopSimAndSlam(dir, nodes);
  spinner.stop();
  std::optional<geometry_msgs::Transform> map_odom;
  for (const auto& m : tfs.all())
    for (const auto& t : m.transforms)
      if (t.header.frame_id == "map" && t.child_frame_id == "odom") map_odom = t.transform;
  ASSERT_TRUE(map_odom) << "slam publishes map -> odom";
  std::cout << "map -> odom at the end: " << map_odom->translation.x << ", "
            << map_odom->translation.y << "\n";
  EXPECT_NEAR(map_odom->translation.x, -1.5, 0.15);
  EXPECT_NEAR(map_odom->translation.y, -1.5, 0.15);
  const auto traj = carenav::io::readTum((dir / "map" / "trajectory.tum").string());
  ASSERT_FALSE(traj.empty());
  EXPECT_GT(traj.back().x, 1.0) << "the drive east is mapped";
#endif
}

}  // namespace
