// Latency from a scan message to the cmd_vel it causes, through a real
// rosmaster: `carenav ros navigate --on-scan` (Interbot as a walker on the
// apartment world, localising on it) is sent odometry, the user's intent
// and a scan rendered by the simulator at the start pose; the time from
// publishing the scan to receiving the next cmd_vel is measured, one scan at
// a time (docs/BENCHMARKS.md, docs/ros.md). Usage: bench_ros_latency [N]
// (default 1000 cycles after 50 to warm up). Prints median, p99, max.
#include <carenav/common/profile.h>
#include <carenav/common/robot.h>
#include <carenav/sim/simulator.h>

#include <geometry_msgs/Twist.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>

#include <algorithm>
#include <condition_variable>
#include <cstdio>
#include <iostream>
#include <limits>
#include <mutex>

#include "../integration/ros_master.h"

namespace {

using Clock = std::chrono::steady_clock;
const std::string kSrc = CARENAV_SOURCE_DIR;
const std::string kWorld = kSrc + "/maps/worlds/apartment.yaml";
const std::string kProfile = kSrc + "/ini/interbot.ini";

/** The profile's lidar as the simulator sees it at the start pose. */
sensor_msgs::LaserScan renderScan() {
  const auto profile = carenav::Profile::load(kProfile);
  auto world = std::make_shared<const carenav::sim::World>(carenav::sim::loadWorld(kWorld));
  std::vector<carenav::SensorParams> lidar;
  for (const auto& s : carenav::loadSensors(profile))
    if (s.type == "lidar2d" && lidar.empty()) lidar.push_back(s);
  carenav::sim::Simulator sim(world, profile.section<carenav::RobotParams>("robot"), lidar,
                              carenav::sim::SimParams{});
  sim.reset({1.5, 1.5, 0});
  auto o = std::dynamic_pointer_cast<mrpt::obs::CObservation2DRangeScan>(sim.observe(0));
  sensor_msgs::LaserScan m;
  m.header.frame_id = o->sensorLabel;
  const size_t n = o->getScanSize();
  m.angle_min = -o->aperture / 2;
  m.angle_max = o->aperture / 2;
  m.angle_increment = o->aperture / (n - 1);
  m.range_max = o->maxRange;
  for (size_t i = 0; i < n; ++i)
    m.ranges.push_back(o->getScanRangeValidity(i) ? o->getScanRange(i)
                                                  : std::numeric_limits<float>::infinity());
  return m;
}

double percentile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(p * (v.size() - 1) + 0.5))];
}

}  // namespace

int run(int argc, char** argv) {
  const size_t n = argc > 1 ? std::stoul(argv[1]) : 1000, warm = 50;
  const auto dir = std::filesystem::temp_directory_path() / "carenav_bench_ros";
  std::filesystem::create_directories(dir);
  carenav_ros_test::RosMaster master(dir);  // stopped on every way out of run()
  if (!master.up()) return std::cerr << "no rosmaster\n", 1;
  const sensor_msgs::LaserScan rendered = renderScan();
  const pid_t nav = carenav_ros_test::spawn(
      {CARENAV_BIN, "-q", "ros", "navigate", "--profile", kProfile, "--plugin", "user-intent-dwa",
       "--world", kWorld, "--start", "1.5,1.5,0", "--on-scan", "--duration", "600"},
      master.dir() / "nav.log");
  int rargc = 1;
  ros::init(rargc, argv, "carenav_bench", ros::init_options::NoSigintHandler);
  ros::NodeHandle nh;
  std::mutex mu;
  std::condition_variable cv;
  size_t got = 0;
  Clock::time_point last;
  auto sub = nh.subscribe<geometry_msgs::Twist>("cmd_vel", 100,
                                                [&](const geometry_msgs::Twist::ConstPtr&) {
                                                  std::lock_guard<std::mutex> l(mu);
                                                  ++got;
                                                  last = Clock::now();
                                                  cv.notify_all();
                                                });
  auto scan_pub = nh.advertise<sensor_msgs::LaserScan>("scan", 5);
  auto odom_pub = nh.advertise<nav_msgs::Odometry>("odom", 5);
  auto intent_pub = nh.advertise<geometry_msgs::Twist>("intent", 5);
  ros::AsyncSpinner spinner(1);
  spinner.start();
  while (scan_pub.getNumSubscribers() == 0 || odom_pub.getNumSubscribers() == 0 ||
         intent_pub.getNumSubscribers() == 0 || sub.getNumPublishers() == 0)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  sensor_msgs::LaserScan scan = rendered;
  nav_msgs::Odometry odom;
  odom.header.frame_id = "odom";
  odom.pose.pose.orientation.w = 1;
  geometry_msgs::Twist intent;
  intent.linear.x = 0.2;
  std::vector<double> ms;
  for (size_t k = 0; k < n + warm; ++k) {
    odom.header.stamp = ros::Time::now();
    odom_pub.publish(odom);
    intent_pub.publish(intent);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));  // odometry and intent first
    std::unique_lock<std::mutex> l(mu);
    const size_t before = got;
    const auto t0 = Clock::now();
    scan.header.stamp = ros::Time::now();
    scan_pub.publish(scan);
    if (!cv.wait_for(l, std::chrono::seconds(2), [&] { return got > before; })) {
      std::cerr << "no cmd_vel within 2 s of scan " << k << "\n";
      continue;
    }
    if (k >= warm) ms.push_back(std::chrono::duration<double, std::milli>(last - t0).count());
    l.unlock();
    std::this_thread::sleep_for(std::chrono::milliseconds(15));
  }
  ::kill(nav, SIGINT);
  carenav_ros_test::waitExit(nav);
  spinner.stop();
  ros::shutdown();
  if (ms.empty()) return 1;
  std::printf("scan -> cmd_vel over %zu cycles: median %.2f ms, p99 %.2f ms, max %.2f ms\n",
              ms.size(), percentile(ms, 0.5), percentile(ms, 0.99), percentile(ms, 1.0));
  return 0;
}

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "bench_ros_latency: " << e.what() << "\n";
    return 1;
  }
}
