// `carenav ros sim`: the simulator as a ROS robot (nodes.h, docs/ros.md).
#include <carenav/common/errors.h>
#include <carenav/common/json.h>
#include <carenav/common/profile.h>
#include <carenav/ros/nodes.h>
#include <carenav/runtime/session.h>
#include <carenav/sim/simulator.h>

#include "msg_convert.h"

#include <geometry_msgs/Twist.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_msgs/TFMessage.h>

#include <fstream>
#include <iostream>
#include <mutex>

namespace carenav::ros {

namespace {

using mrpt::poses::CPose3D;

struct SimWorld {
  std::string world;
  navigation::TPose2D start;
};

SimWorld simWorld(const SimNodeOptions& o) {
  if (!o.scenario.empty()) {
    const auto sc = navigation::readScenario(o.scenario);
    return {sc.world, o.start ? *o.start : sc.start};
  }
  if (o.world.empty()) throw InputError("give --world W.yaml (with --start) or --scenario S.yaml");
  return {o.world, o.start ? *o.start : navigation::TPose2D{}};
}

class SimNode {
 public:
  SimNode(const SimNodeOptions& o, sim::Simulator& sim) : o_(o), sim_(sim) {
    for (const auto& s : sim.sensors())
      if (s.type == "lidar2d") {
        lidars_[s.label] =
            nh_.advertise<sensor_msgs::LaserScan>(lidars_.empty() ? "scan" : "scan_" + s.label, 10);
        poses_[s.label] = CPose3D(s.x, s.y, s.z, mrpt::DEG2RAD(s.yaw), mrpt::DEG2RAD(s.pitch),
                                  mrpt::DEG2RAD(s.roll));
      }
    odom_ = nh_.advertise<nav_msgs::Odometry>("odom", 20);
    truth_ = nh_.advertise<nav_msgs::Odometry>("ground_truth", 20);
    tf_ = nh_.advertise<tf2_msgs::TFMessage>("tf", 50);
    clock_ = nh_.advertise<rosgraph_msgs::Clock>("clock", 10);
    cmd_ = nh_.subscribe("cmd_vel", 10, &SimNode::onCmd, this);
    if (!o.record.empty()) {
      bag_ = std::make_unique<rosbag::Bag>(o.record, rosbag::bagmode::Write);
    }
  }
  ~SimNode() {
    if (bag_) bag_->close();
  }
  void run();

 private:
  void onCmd(const geometry_msgs::Twist& m) {
    sim_.setCommand(m.linear.x, m.angular.z);
    last_cmd_ = ::ros::WallTime::now();
  }
  void publish(const sim::SimFrame& f, const ::ros::Time& now);
  /** Publishes `m` and records it (when recording). */
  template <class M>
  void send(::ros::Publisher& p, const M& m, const ::ros::Time& now) {
    p.publish(m);
    if (bag_) bag_->write(p.getTopic(), now, m);
  }
  nav_msgs::Odometry odometry(const sim::Pose2& p, const std::string& frame,
                              const ::ros::Time& now) const;
  geometry_msgs::TransformStamped link(const std::string& parent, const std::string& child,
                                       const CPose3D& p, const ::ros::Time& now) const;

  const SimNodeOptions& o_;
  sim::Simulator& sim_;
  ::ros::NodeHandle nh_;
  std::map<std::string, ::ros::Publisher> lidars_;
  std::map<std::string, CPose3D> poses_;
  ::ros::Publisher odom_, truth_, tf_, clock_;
  ::ros::Subscriber cmd_;
  ::ros::WallTime last_cmd_;
  std::unique_ptr<rosbag::Bag> bag_;
};

nav_msgs::Odometry SimNode::odometry(const sim::Pose2& p, const std::string& frame,
                                     const ::ros::Time& now) const {
  nav_msgs::Odometry m;
  m.header.stamp = now;
  m.header.frame_id = frame;
  m.child_frame_id = o_.base_frame;
  m.pose.pose.position.x = p.x;
  m.pose.pose.position.y = p.y;
  m.pose.pose.orientation = yawQuaternion(p.yaw);
  m.twist.twist.linear.x = sim_.v();
  m.twist.twist.angular.z = sim_.w();
  return m;
}

geometry_msgs::TransformStamped SimNode::link(const std::string& parent, const std::string& child,
                                              const CPose3D& p, const ::ros::Time& now) const {
  geometry_msgs::TransformStamped t;
  t.header.stamp = now;
  t.header.frame_id = parent;
  t.child_frame_id = child;
  t.transform = transformOf(p);
  return t;
}

void SimNode::publish(const sim::SimFrame& f, const ::ros::Time& now) {
  send(odom_, odometry(f.odometry, o_.odom_frame, now), now);
  send(truth_, odometry(f.truth, o_.map_frame, now), now);
  tf2_msgs::TFMessage tf;
  tf.transforms.push_back(link(o_.odom_frame, o_.base_frame,
                               CPose3D(f.odometry.x, f.odometry.y, 0, f.odometry.yaw, 0, 0), now));
  for (const auto& obs : f.observations) {
    auto scan = std::dynamic_pointer_cast<mrpt::obs::CObservation2DRangeScan>(obs);
    if (!scan || !lidars_.count(scan->sensorLabel)) continue;
    // The scan in its own frame: the sensor pose goes to tf.
    auto m = scanToRos(*scan, scan->sensorLabel);
    m.header.stamp = now;
    send(lidars_[scan->sensorLabel], m, now);
    tf.transforms.push_back(link(o_.base_frame, scan->sensorLabel, poses_[scan->sensorLabel], now));
  }
  send(tf_, tf, now);
}

void SimNode::run() {
  const double dt = 1.0 / o_.rate;
  ::ros::WallRate rate(o_.rate);
  while (::ros::ok() && !(o_.stop && o_.stop->load())) {
    if (o_.duration > 0 && sim_.time() >= o_.duration) break;
    ::ros::spinOnce();
    // A base that hears no command for cmd_timeout stops by itself.
    if (!last_cmd_.isZero() && (::ros::WallTime::now() - last_cmd_).toSec() > o_.cmd_timeout)
      sim_.setCommand(0, 0);
    const ::ros::Time now = ::ros::Time::now();
    rosgraph_msgs::Clock c;
    c.clock = now;
    clock_.publish(c);
    for (const auto& f : sim_.step(dt)) publish(f, now);
    rate.sleep();
  }
}

void writeSummary(const SimNodeOptions& o, const sim::Simulator& sim) {
  if (o.summary.empty()) return;
  JsonWriter j;
  const auto p = sim.groundTruth();
  j.beginObject();
  j.key("time_s").value(sim.time());
  j.key("collisions").value(static_cast<uint64_t>(sim.collisions()));
  j.key("distance_m").value(sim.distance());
  j.key("truth").beginObject();
  j.key("x").value(p.x).key("y").value(p.y).key("yaw_deg").value(mrpt::RAD2DEG(p.yaw));
  j.endObject();
  j.endObject();
  std::ofstream(o.summary) << j.str() << "\n";
}

}  // namespace

void runSimNode(const SimNodeOptions& o) {
  const SimWorld w = simWorld(o);
  auto setup = navigation::sessionSetup(o.profile, o.sets, "");  // bad input: before ROS
  initRosNode("carenav_sim", o.ros_args);
  if (auto sets = privateParamOverrides(); !sets.empty()) {
    sets.insert(sets.end(), o.sets.begin(), o.sets.end());
    setup = navigation::sessionSetup(o.profile, sets, "");
  }
  auto simp = setup.profile.section<sim::SimParams>("sim");
  auto world = std::make_shared<const sim::World>(sim::loadWorld(w.world, simp.wall_height));
  std::vector<SensorParams> lidars;
  for (const auto& s : setup.sensors)
    if (s.type == "lidar2d") lidars.push_back(s);
  if (lidars.empty()) throw InputError(o.profile + ": no lidar2d sensor to publish");
  sim::Simulator sim(world, setup.robot, lidars, simp);
  sim.reset({w.start.x, w.start.y, w.start.phi});
  if (sim.footprintBlocked({w.start.x, w.start.y, w.start.phi}, 0))
    throw InputError(w.world + ": the start pose puts the robot on an obstacle of the world");
  {
    SimNode node(o, sim);
    if (!o.quiet) std::cerr << "carenav ros sim: " << w.world << ", publishing\n";
    node.run();
  }
  writeSummary(o, sim);
  ::ros::shutdown();
}

}  // namespace carenav::ros
