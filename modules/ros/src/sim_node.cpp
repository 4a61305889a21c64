// `carenav ros sim`: the simulator as a ROS robot (nodes.h, docs/ros.md).
#include <carenav/common/errors.h>
#include <carenav/common/json.h>
#include <carenav/common/profile.h>
#include <carenav/ros/nodes.h>
#include <carenav/runtime/session.h>
#include <carenav/sim/simulator.h>

#include "msg_convert.h"

#include <carenav/perception/cloud.h>
#include <geometry_msgs/Twist.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationRange.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include <cstring>
#include <limits>

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

/** A range array's segments as a LaserScan over its fov (right to left),
 *  one beam per segment; no return (at the maximum) as +inf. */
sensor_msgs::LaserScan rangeArrayToRos(const mrpt::obs::CObservationRange& ra, double fov) {
  sensor_msgs::LaserScan m;
  m.header.frame_id = ra.sensorLabel;
  const size_t n = ra.sensedData.size();
  const double seg = n ? fov / n : 0;
  m.angle_min = static_cast<float>(-fov / 2 + seg / 2);
  m.angle_max = static_cast<float>(fov / 2 - seg / 2);
  m.angle_increment = static_cast<float>(seg);
  m.range_min = ra.minSensorDistance;
  m.range_max = ra.maxSensorDistance;
  for (const auto& me : ra.sensedData)
    m.ranges.push_back(me.sensedDistance < ra.maxSensorDistance
                           ? me.sensedDistance
                           : std::numeric_limits<float>::infinity());
  return m;
}

/** Points in the sensor frame (x forward, y left, z up) as an organised
 *  PointCloud2 of float x, y, z (invalid points NaN). */
sensor_msgs::PointCloud2 cloudToRos(const perception::Cloud& c, const std::string& frame,
                                    const ::ros::Time& now) {
  sensor_msgs::PointCloud2 m;
  m.header.stamp = now;
  m.header.frame_id = frame;
  m.height = c.height > 0 ? static_cast<uint32_t>(c.height) : 1;
  m.width = static_cast<uint32_t>(c.points.size() / m.height);
  const char* names[3] = {"x", "y", "z"};
  for (uint32_t i = 0; i < 3; ++i) {
    sensor_msgs::PointField f;
    f.name = names[i];
    f.offset = 4 * i;
    f.datatype = sensor_msgs::PointField::FLOAT32;
    f.count = 1;
    m.fields.push_back(f);
  }
  m.point_step = 12;
  m.row_step = 12 * m.width;
  m.is_dense = false;
  m.data.resize(size_t{m.row_step} * m.height);
  for (size_t i = 0; i < size_t{m.width} * m.height; ++i)
    std::memcpy(&m.data[12 * i], &c.points[i], 12);
  return m;
}

class SimNode {
 public:
  SimNode(const SimNodeOptions& o, sim::Simulator& sim) : o_(o), sim_(sim) {
    // The first lidar2d on `scan`, other lidars and range arrays on
    // `scan_LABEL`; the first depth camera on `points`, others `points_LABEL`
    // (with --depth: `depth/image` + `depth/camera_info`, `depth_LABEL/...`).
    bool scan = false, points = false;
    for (const auto& s : sim.sensors()) {
      poses_[s.label] = CPose3D(s.x, s.y, s.z, mrpt::DEG2RAD(s.yaw), mrpt::DEG2RAD(s.pitch),
                                mrpt::DEG2RAD(s.roll));
      if (s.type == "lidar2d" || s.type == "range-array") {
        const bool first = s.type == "lidar2d" && !scan;
        scan = scan || first;
        pubs_[s.label] =
            nh_.advertise<sensor_msgs::LaserScan>(first ? "scan" : "scan_" + s.label, 10);
      } else if (s.type == "depth-camera" && o.depth_images) {
        const std::string ns = points ? "depth_" + s.label + "/" : "depth/";
        pubs_[s.label] = nh_.advertise<sensor_msgs::Image>(ns + "image", 2);
        info_pubs_[s.label] = nh_.advertise<sensor_msgs::CameraInfo>(ns + "camera_info", 2);
        points = true;
      } else if (s.type == "depth-camera") {
        pubs_[s.label] =
            nh_.advertise<sensor_msgs::PointCloud2>(points ? "points_" + s.label : "points", 2);
        points = true;
      }
      fov_[s.label] = mrpt::DEG2RAD(s.fov);
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
  /** A sensor's observation on its topic; false when it is of no type published. */
  bool sendObservation(const mrpt::obs::CObservation::Ptr& obs, ::ros::Publisher& pub,
                       const ::ros::Time& now);
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
  std::map<std::string, ::ros::Publisher> pubs_;       // by sensor label
  std::map<std::string, ::ros::Publisher> info_pubs_;  // depth images' CameraInfo, by label
  std::map<std::string, CPose3D> poses_;
  std::map<std::string, double> fov_;
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

// tf first (odom -> base_link, base_link -> each sensor, a depth camera's
// optical frame), so a bag places every sensor message by the tf before it.
void SimNode::publish(const sim::SimFrame& f, const ::ros::Time& now) {
  send(odom_, odometry(f.odometry, o_.odom_frame, now), now);
  send(truth_, odometry(f.truth, o_.map_frame, now), now);
  tf2_msgs::TFMessage tf;
  tf.transforms.push_back(link(o_.odom_frame, o_.base_frame,
                               CPose3D(f.odometry.x, f.odometry.y, 0, f.odometry.yaw, 0, 0), now));
  std::vector<std::pair<mrpt::obs::CObservation::Ptr, ::ros::Publisher*>> sent;
  for (const auto& obs : f.observations) {
    const auto pub = pubs_.find(obs->sensorLabel);
    if (pub == pubs_.end()) continue;
    const std::string& label = obs->sensorLabel;
    tf.transforms.push_back(link(o_.base_frame, label, poses_[label], now));
    if (info_pubs_.count(label))
      tf.transforms.push_back(link(label, label + "_optical", opticalInBody(), now));
    sent.emplace_back(obs, &pub->second);
  }
  send(tf_, tf, now);
  for (const auto& [obs, pub] : sent) sendObservation(obs, *pub, now);
}

// Each in its own frame (the sensor label; a depth image in LABEL_optical).
bool SimNode::sendObservation(const mrpt::obs::CObservation::Ptr& obs, ::ros::Publisher& pub,
                              const ::ros::Time& now) {
  if (auto scan = std::dynamic_pointer_cast<mrpt::obs::CObservation2DRangeScan>(obs)) {
    auto m = scanToRos(*scan, scan->sensorLabel);
    m.header.stamp = now;
    send(pub, m, now);
  } else if (auto ra = std::dynamic_pointer_cast<mrpt::obs::CObservationRange>(obs)) {
    auto m = rangeArrayToRos(*ra, fov_[ra->sensorLabel]);
    m.header.stamp = now;
    send(pub, m, now);
  } else if (const auto info = info_pubs_.find(obs->sensorLabel); info != info_pubs_.end()) {
    auto depth = std::dynamic_pointer_cast<mrpt::obs::CObservation3DRangeScan>(obs);
    sensor_msgs::Image img;
    sensor_msgs::CameraInfo cam;
    if (!depth || !depthToRos(*depth, obs->sensorLabel + "_optical", now, img, cam)) return false;
    send(info->second, cam, now);
    send(pub, img, now);
  } else if (auto cloud = perception::cloudFromObservation(*obs, CPose3D())) {
    send(pub, cloudToRos(*cloud, obs->sensorLabel, now), now);
  } else {
    return false;
  }
  return true;
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
  std::vector<SensorParams> used;
  for (const auto& s : setup.sensors)
    if (s.type == "lidar2d" || s.type == "range-array" || s.type == "depth-camera")
      used.push_back(s);
  if (used.empty()) throw InputError(o.profile + ": no lidar2d, range-array or depth-camera");
  sim::Simulator sim(world, setup.robot, used, simp);
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
