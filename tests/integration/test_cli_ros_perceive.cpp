// `carenav ros perceive` on a real ROS master: the ISR-AIWALKER walker in
// the simulator (`carenav ros sim`, its Kinect cloud on `points`) facing a
// staircase going down publishes a virtual scan whose ranges ahead end at
// the stair edge; facing open floor they are long or empty. Skipped
// without the ROS part. A bag the sim records with its clouds perceives as
// the rawlog `import rosbag --cloud` makes of it; a bag of `ros sim --depth`
// (depth images + CameraInfo) imports with `--depth` and perceives with the
// obstacles of the cloud bag of the same scene. A depth image with its
// CameraInfo (the test's own: floor up to a wall 2 m ahead) gives a scan
// ending at the wall.
#include "cli_helpers.h"
#include "ros_skip.h"

#ifdef CARENAV_TEST_WITH_ROS
#include <carenav/io/map_io.h>

#include <nav_msgs/OccupancyGrid.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/LaserScan.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <regex>
#include <set>

#include "ros_nodes_helpers.h"
#endif

namespace {

using namespace carenav_test;
using carenav_test::carenav;  // not the namespace carenav (carenav/io/map_io.h)

#ifdef CARENAV_TEST_WITH_ROS
using namespace carenav_ros_test;

const std::string kWalker = kSrc + "/ini/isr-aiwalker.ini";
const std::string kStairs = kSrc + "/maps/worlds/nav/stairs_down.yaml";

struct Perceived {
  std::vector<float> ahead;  ///< ranges within 10 degrees of straight ahead
  size_t scans = 0, occupied = 0;
  std::string grid_frame;
};

/** The sim's walker at `start` in the stairs world and `ros perceive` on its
 *  cloud: what the last virtual scan ahead and the last local grid hold once
 *  a dozen scans (about a second of frames) have come. */
Perceived perceiveAt(const fs::path& dir, const std::string& start, const std::string& name) {
  TopicLog<sensor_msgs::LaserScan> scans("virtual_scan");
  TopicLog<nav_msgs::OccupancyGrid> grids("local_grid");
  ::ros::AsyncSpinner spinner(1);
  spinner.start();
  const pid_t sim = startRosNode(
      dir, "sim", {"--profile", kWalker, "--world", kStairs, "--start", start, "--duration", "60"},
      "sim_" + name);
  const pid_t per =
      startRosNode(dir, "perceive", {"--profile", kWalker, "--duration", "50"}, "perceive_" + name);
  while (scans.count() < 12 && running(per))
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  ::kill(per, SIGINT);
  ::kill(sim, SIGINT);
  EXPECT_EQ(waitExit(per), 0) << slurp(dir / ("perceive_" + name + ".log"));
  EXPECT_EQ(waitExit(sim), 0) << slurp(dir / ("sim_" + name + ".log"));
  spinner.stop();
  Perceived r;
  r.scans = scans.count();
  if (const auto s = scans.last())
    for (size_t k = 0; k < s->ranges.size(); ++k)
      if (std::abs(s->angle_min + k * s->angle_increment) < 10 * M_PI / 180)
        r.ahead.push_back(s->ranges[k]);
  if (const auto g = grids.last()) {
    r.grid_frame = g->header.frame_id;
    r.occupied = std::count_if(g->data.begin(), g->data.end(), [](int8_t v) { return v > 55; });
  }
  return r;
}

/** A depth camera 0.5 m above the floor looking straight ahead (64 x 48 px,
 *  f = 50 px) at a wall 2 m away: the lower rows see the floor before it.
 *  16UC1 in mm. */
std::pair<sensor_msgs::Image, sensor_msgs::CameraInfo> floorAndWall() {
  sensor_msgs::CameraInfo info;
  info.width = 64;
  info.height = 48;
  info.K = {50, 0, 31.5, 0, 50, 23.5, 0, 0, 1};
  sensor_msgs::Image img;
  img.encoding = "16UC1";
  img.width = 64;
  img.height = 48;
  img.step = 128;
  img.data.resize(128 * 48);
  for (uint32_t r = 0; r < 48; ++r)
    for (uint32_t c = 0; c < 64; ++c) {
      const double kz = (23.5 - r) / 50;  // up along the ray per metre of depth
      const double depth = kz < -0.25 ? 0.5 / -kz : 2.0;
      const auto mm = static_cast<uint16_t>(std::lround(1000 * depth));
      std::memcpy(&img.data[r * 128 + 2 * c], &mm, 2);
    }
  return {img, info};
}

/** The "cells" object of every frame in a perceive summary.json. */
std::vector<std::string> frameCells(const std::string& summary) {
  std::vector<std::string> out;
  const std::regex re("\"cells\": \\{[^}]*\\}");
  for (auto it = std::sregex_iterator(summary.begin(), summary.end(), re);
       it != std::sregex_iterator(); ++it)
    out.push_back(it->str());
  return out;
}

float median(std::vector<float> v) {
  if (v.empty()) return std::nanf("");
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

#endif

TEST(CliRosPerceive, VirtualScanHasTheStairsDownAhead) {
  SKIP_WITHOUT_ROS();
#ifdef CARENAV_TEST_WITH_ROS
  ASSERT_TRUE(sharedMaster().up()) << slurp(sharedMaster().dir() / "master.log");
  const fs::path dir = testDir();
  // The stairs begin at x = 6 m: 1.5 m ahead of the walker's axle.
  const Perceived stairs = perceiveAt(dir, "4.5,2.0,0", "stairs");
  // Facing west over the landing: the wall is 5 m away, beyond the Kinect's 4.5 m.
  const Perceived flat = perceiveAt(dir, "5.0,2.0,180", "flat");
  ASSERT_GE(stairs.scans, 12u);
  ASSERT_GE(flat.scans, 12u);
  ASSERT_FALSE(stairs.ahead.empty());
  const float edge = median(stairs.ahead), open = median(flat.ahead);
  std::cout << "virtual scan ahead (median of +-10 deg): stairs " << edge << " m, flat floor "
            << open << " m; occupied cells " << stairs.occupied << " / " << flat.occupied << "\n";
  EXPECT_GT(edge, 1.0) << "the drop is at 1.5 m, not at the walker";
  EXPECT_LT(edge, 1.9) << "the stair edge ends the ranges ahead";
  EXPECT_GT(open, 3.5) << "open floor ahead: long or no ranges";
  EXPECT_EQ(stairs.grid_frame, "odom") << "the grid follows the sim's odometry";
  EXPECT_GT(stairs.occupied, 100u) << "the stair edge and the side walls are in the grid";
#endif
}

TEST(CliRosPerceive, SimBagCloudsPerceiveAsTheirRawlog) {
  SKIP_WITHOUT_ROS();
#ifdef CARENAV_TEST_WITH_ROS
  ASSERT_TRUE(sharedMaster().up()) << slurp(sharedMaster().dir() / "master.log");
  const fs::path dir = testDir();
  const auto bag = dir / "sim.bag";
  const pid_t sim = startRosNode(dir, "sim",
                                 {"--profile", kWalker, "--world", kStairs, "--start", "4.5,2.0,0",
                                  "--duration", "3", "--record", bag.string()});
  ASSERT_EQ(waitExit(sim), 0) << slurp(dir / "sim.log");
  const auto rawlog = dir / "sim.rawlog";
  const auto imp = carenav({"-q", "import", "rosbag", bag.string(), "--cloud", "/points=kinect",
                            "--out", rawlog.string(), "--json"});
  ASSERT_EQ(imp.code, 0) << imp.err;
  const uint64_t clouds = jsonNumber(imp.out, "clouds");
  EXPECT_GE(clouds, 20u) << imp.out;  // the Kinect at 10 Hz for 3 s
  for (const auto& [input, out] :
       {std::pair{bag, dir / "from_bag"}, {rawlog, dir / "from_rawlog"}}) {
    const auto r = carenav({"-q", "perceive", "--profile", kWalker, "--rawlog", input.string(),
                            "--out", out.string()});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(jsonNumber(slurp(out / "summary.json"), "frame_count"), clouds) << input;
  }
  const auto a = frameCells(slurp(dir / "from_bag" / "summary.json"));
  const auto b = frameCells(slurp(dir / "from_rawlog" / "summary.json"));
  EXPECT_EQ(a.size(), clouds);
  EXPECT_EQ(a, b) << "the bag and its rawlog give the same local grids";
  ASSERT_FALSE(a.empty());
  std::smatch occ;
  ASSERT_TRUE(std::regex_search(a.back(), occ, std::regex("\"occupied\": ([0-9]+)")));
  std::cout << clouds << " clouds; the last frame: " << a.back() << "\n";
  EXPECT_GT(std::stoi(occ[1]), 100) << "the stair edge and the walls are obstacles";
#endif
}

/** `ros sim` (the walker facing the stairs) for 3 s of simulated time,
 *  recording DIR/NAME.bag; `extra`: more sim options. */
fs::path recordStairs(const fs::path& dir, const std::string& name,
                      std::vector<std::string> extra = {}) {
  const auto bag = dir / (name + ".bag");
  std::vector<std::string> args{"--profile", kWalker,      "--world", kStairs,    "--start",
                                "4.5,2.0,0", "--duration", "3",       "--record", bag.string()};
  args.insert(args.end(), extra.begin(), extra.end());
  const pid_t sim = startRosNode(dir, "sim", args, "sim_" + name);
  EXPECT_EQ(waitExit(sim), 0) << slurp(dir / ("sim_" + name + ".log"));
  return bag;
}

/** The cells (i, j) of a perceive frame grid with p(occupied) above 0.55. */
std::set<std::pair<int, int>> obstacleCells(const fs::path& gridmap) {
  const auto g = carenav::io::loadGridMap(gridmap.string());
  std::set<std::pair<int, int>> out;
  for (unsigned j = 0; j < g.getSizeY(); ++j)
    for (unsigned i = 0; i < g.getSizeX(); ++i)
      if (1.0 - g.getCell(i, j) > 0.55) out.insert({static_cast<int>(i), static_cast<int>(j)});
  return out;
}

/** `carenav perceive` (the walker) on INPUT into DIR/OUT: the frames' cells. */
std::vector<std::string> perceiveCells(const fs::path& input, const fs::path& out) {
  const auto r = carenav(
      {"-q", "perceive", "--profile", kWalker, "--rawlog", input.string(), "--out", out.string()});
  EXPECT_EQ(r.code, 0) << r.err;
  return frameCells(slurp(out / "summary.json"));
}

// `ros sim --depth` publishes the Kinect as depth images with their
// CameraInfo; a bag of them imports with `--depth` as range images, and
// `carenav perceive` reads it (directly and as the imported rawlog) as it
// reads the bag of clouds of the same scene: the same local grids.
TEST(CliRosPerceive, SimDepthBagPerceivesAsItsCloudBag) {
  SKIP_WITHOUT_ROS();
#ifdef CARENAV_TEST_WITH_ROS
  ASSERT_TRUE(sharedMaster().up()) << slurp(sharedMaster().dir() / "master.log");
  const fs::path dir = testDir();
  const auto depth_bag = recordStairs(dir, "depth", {"--depth"});
  const auto cloud_bag = recordStairs(dir, "cloud");
  const auto rawlog = dir / "depth.rawlog";
  const auto imp = carenav({"-q", "import", "rosbag", depth_bag.string(), "--depth",
                            "/depth/image=kinect", "--out", rawlog.string(), "--json"});
  ASSERT_EQ(imp.code, 0) << imp.err;
  const uint64_t images = jsonNumber(imp.out, "depth_images");
  EXPECT_GE(images, 20u) << imp.out;  // the Kinect at 10 Hz for 3 s
  EXPECT_EQ(jsonNumber(imp.out, "clouds"), 0u) << imp.out;
  EXPECT_EQ(jsonNumber(imp.out, "depth_images_without_tf"), 0u) << imp.out;
  // A camera_info topic with no message: every image left out.
  const auto none = carenav({"-q", "import", "rosbag", depth_bag.string(), "--depth",
                             "/depth/image", "--camera-info", "/no/camera_info", "--out",
                             (dir / "none.rawlog").string(), "--json"});
  EXPECT_EQ(none.code, 0) << none.err;  // the odometry is still there
  EXPECT_EQ(jsonNumber(none.out, "depth_images_left_out"), images) << none.out;
  const auto mismatch =
      carenav({"-q", "import", "rosbag", depth_bag.string(), "--depth", "/a", "--depth", "/b",
               "--camera-info", "/c", "--out", (dir / "bad.rawlog").string()});
  EXPECT_EQ(mismatch.code, 2);
  EXPECT_NE(mismatch.err.find("one camera_info topic per depth topic"), std::string::npos)
      << mismatch.err;
  const auto from_bag = perceiveCells(depth_bag, dir / "depth_bag");
  const auto from_rawlog = perceiveCells(rawlog, dir / "depth_rawlog");
  const auto from_clouds = perceiveCells(cloud_bag, dir / "cloud_bag");
  EXPECT_EQ(from_bag.size(), images) << "every depth image read by default";
  EXPECT_EQ(from_bag, from_rawlog) << "the bag and its rawlog give the same local grids";
  EXPECT_EQ(from_clouds.size(), images) << "as many clouds as images";
  ASSERT_FALSE(from_bag.empty());
  // The obstacles of the clouds' last local grid are obstacles of the depth
  // images' too (an organised cloud keeps its image layout, so the drop
  // edges from the image columns run on both: 724 cells each).
  char last[32];
  std::snprintf(last, sizeof(last), "frame_%04u.gridmap.gz", static_cast<unsigned>(images - 1));
  const auto from_depth = obstacleCells(dir / "depth_bag" / last);
  const auto from_cloud = obstacleCells(dir / "cloud_bag" / last);
  size_t shared = 0;
  for (const auto& c : from_cloud) shared += from_depth.count(c);
  std::cout << images << " depth images; the last frame's obstacle cells: " << from_depth.size()
            << " from depth images, " << from_cloud.size() << " from clouds, " << shared
            << " of these in both\n";
  EXPECT_GT(from_cloud.size(), 100u) << "the stair edge and the walls are obstacles";
  EXPECT_GE(from_depth.size(), from_cloud.size());
  EXPECT_GE(shared, 0.95 * from_cloud.size()) << "the clouds' obstacles are found in the images";
#endif
}

TEST(CliRosPerceive, DepthImageWithCameraInfo) {
  SKIP_WITHOUT_ROS();
#ifdef CARENAV_TEST_WITH_ROS
  ASSERT_TRUE(sharedMaster().up()) << slurp(sharedMaster().dir() / "master.log");
  const fs::path dir = testDir();
  TopicLog<sensor_msgs::LaserScan> scans("virtual_scan");
  ::ros::NodeHandle nh;
  auto image = nh.advertise<sensor_msgs::Image>("depth/image", 2);
  auto info = nh.advertise<sensor_msgs::CameraInfo>("depth/camera_info", 2);
  ::ros::AsyncSpinner spinner(1);
  spinner.start();
  const pid_t per = startRosNode(dir, "perceive",
                                 {"--profile", kWalker, "--sensor-pose", "0,0,0.5,0,0,0",
                                  "--duration", "50", "odom:=no_odometry_here"});
  auto [img, cam] = floorAndWall();
  while (scans.count() < 5 && running(per)) {
    img.header.stamp = cam.header.stamp = ::ros::Time::now();
    info.publish(cam);
    image.publish(img);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  ::kill(per, SIGINT);
  EXPECT_EQ(waitExit(per), 0) << slurp(dir / "perceive.log");
  spinner.stop();
  const auto s = scans.last();
  ASSERT_TRUE(s) << slurp(dir / "perceive.log");
  std::vector<float> ahead;
  for (size_t k = 0; k < s->ranges.size(); ++k)
    if (std::abs(s->angle_min + k * s->angle_increment) < 10 * M_PI / 180)
      ahead.push_back(s->ranges[k]);
  const float wall = median(ahead);
  std::cout << "depth image: the wall ahead at " << wall << " m (2 m)\n";
  EXPECT_NEAR(wall, 2.0, 0.1);
  EXPECT_EQ(s->header.frame_id, "base_link");
#endif
}

}  // namespace
