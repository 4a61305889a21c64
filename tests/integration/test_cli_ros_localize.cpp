// `carenav ros localize --in-room NAME` on a real ROS master: started in a
// room of the places file beside the world (no initial pose), the filter's
// particles lie in that room and, with `ros sim` driven by this test's
// cmd_vel, `amcl_pose` converges near the simulator's ground truth. An
// unknown room, by option or by the `~in_room` parameter, is exit 2 naming
// the room and the places file. Skipped without the ROS part.
#include "cli_helpers.h"
#include "ros_skip.h"

#ifdef CARENAV_TEST_WITH_ROS
#include <geometry_msgs/PoseArray.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/Twist.h>
#include <nav_msgs/Odometry.h>

#include <algorithm>
#include <cmath>

#include "ros_nodes_helpers.h"
#endif

namespace {

using namespace carenav_test;

#ifdef CARENAV_TEST_WITH_ROS
using namespace carenav_ros_test;

const std::string kInterbot = kSrc + "/ini/interbot.ini";

/** The apartment world copied to `dir` with a places file beside it: the
 *  living room (x 0-7 m) as "Lounge" and the corridor as "Corridor". */
fs::path apartmentWithRooms(const fs::path& dir) {
  return apartmentWith(dir, {{"Lounge", "0.1,0.1,6.9,7.9"}, {"Corridor", "7.1,0.1,11.9,2.9"}});
}

double yawOf(const geometry_msgs::Quaternion& q) {
  return std::atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z));
}

/** cmd_vel every 0.1 s for `tenths` tenths of a second. */
void drive(::ros::Publisher& cmd, double v, double w, int tenths) {
  geometry_msgs::Twist t;
  t.linear.x = v;
  t.angular.z = w;
  for (int i = 0; i < tenths; ++i) {
    cmd.publish(t);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
}

#endif

TEST(CliRosLocalize, InRoomConvergesNearTheTruth) {
  SKIP_WITHOUT_ROS();
#ifdef CARENAV_TEST_WITH_ROS
  ASSERT_TRUE(sharedMaster().up()) << slurp(sharedMaster().dir() / "master.log");
  const fs::path dir = testDir();
  const fs::path world = apartmentWithRooms(dir);
  TopicLog<geometry_msgs::PoseWithCovarianceStamped> poses("amcl_pose");
  TopicLog<geometry_msgs::PoseArray> clouds("particlecloud");
  TopicLog<nav_msgs::Odometry> truth("ground_truth");
  ::ros::NodeHandle nh;
  auto cmd = nh.advertise<geometry_msgs::Twist>("cmd_vel", 5);
  ::ros::AsyncSpinner spinner(1);
  spinner.start();
  const pid_t sim = startRosNode(dir, "sim",
                                 {"--profile", kInterbot, "--world", world.string(), "--start",
                                  "1.5,1.5,0", "--duration", "120"});
  const pid_t loc = startRosNode(dir, "localize",
                                 {"--profile", kInterbot, "--world", world.string(), "--in-room",
                                  "lounge", "--duration", "100"});
  // The pose and the cloud of one update are two topics: either may arrive
  // first (a loaded machine delivered the pose alone).
  while (!(cmd.getNumSubscribers() > 0 && poses.count() > 0 && clouds.count() > 0) &&
         running(loc) && running(sim))
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  ASSERT_TRUE(clouds.last()) << slurp(dir / "localize.log");
  drive(cmd, 0, 0.5, 130);  // a turn in place: every wall seen
  drive(cmd, 0.2, 0, 50);   // 1 m east
  drive(cmd, 0, 0, 10);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  ::kill(loc, SIGINT);
  EXPECT_EQ(waitExit(loc), 0) << slurp(dir / "localize.log");
  ::kill(sim, SIGINT);
  EXPECT_EQ(waitExit(sim), 0) << slurp(dir / "sim.log");
  spinner.stop();
  // Every particle of the first cloud (after one filter step: motion noise
  // moves them a little) lies in the room, none in the corridor.
  const double m = 0.25;
  double x0 = 1e9, x1 = -1e9;
  for (const auto& p : clouds.all().front().poses) {
    x0 = std::min(x0, p.position.x);
    x1 = std::max(x1, p.position.x);
    EXPECT_TRUE(p.position.x >= 0.1 - m && p.position.x <= 6.9 + m && p.position.y >= 0.1 - m &&
                p.position.y <= 7.9 + m)
        << p.position.x << " " << p.position.y;
  }
  EXPECT_GT(x1 - x0, 4.0) << "the first particles spread over the room, not around one pose";
  const auto est = poses.last()->pose.pose;
  const auto real = truth.last()->pose.pose;
  std::cout << "amcl_pose (" << est.position.x << ", " << est.position.y << ", "
            << yawOf(est.orientation) * 180 / M_PI << " deg), truth (" << real.position.x << ", "
            << real.position.y << ", " << yawOf(real.orientation) * 180 / M_PI << " deg), "
            << poses.count() << " poses\n";
  EXPECT_LT(std::hypot(est.position.x - real.position.x, est.position.y - real.position.y), 0.3);
  EXPECT_LT(std::abs(std::remainder(yawOf(est.orientation) - yawOf(real.orientation), 2 * M_PI)),
            10 * M_PI / 180);
#endif
}

TEST(CliRosLocalize, UnknownRoomIsAnInputError) {
  SKIP_WITHOUT_ROS();
#ifdef CARENAV_TEST_WITH_ROS
  ASSERT_TRUE(sharedMaster().up()) << slurp(sharedMaster().dir() / "master.log");
  const fs::path dir = testDir();
  const fs::path world = apartmentWithRooms(dir);
  // By option: refused before any master is needed.
  const RunResult r = carenav({"-q", "ros", "localize", "--profile", kInterbot, "--world",
                               world.string(), "--in-room", "Kitchen"});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("no room named 'Kitchen' (rooms: Lounge, Corridor)"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find((dir / "apartment.places.yaml").string()), std::string::npos) << r.err;
  // By the ~in_room parameter, and --places naming another file.
  const fs::path other = dir / "other.places.yaml";
  fs::copy_file(dir / "apartment.places.yaml", other, fs::copy_options::overwrite_existing);
  const pid_t loc = startRosNode(dir, "localize",
                                 {"--profile", kInterbot, "--world", world.string(), "--places",
                                  other.string(), "_in_room:=Kitchen"});
  EXPECT_EQ(waitExit(loc), 2) << slurp(dir / "localize.log");
  const std::string log = slurp(dir / "localize.log");
  EXPECT_NE(log.find("no room named 'Kitchen'"), std::string::npos) << log;
  EXPECT_NE(log.find(other.string()), std::string::npos) << log;
  // A room and a start pose together.
  const RunResult both = carenav({"-q", "ros", "localize", "--profile", kInterbot, "--world",
                                  world.string(), "--in-room", "Lounge", "--start", "1.5,1.5,0"});
  EXPECT_EQ(both.code, 2) << both.err;
  EXPECT_NE(both.err.find("not both"), std::string::npos) << both.err;
#endif
}

}  // namespace
