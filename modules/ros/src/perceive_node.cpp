// `carenav ros perceive`: the perception pipeline of `carenav perceive` and
// of the navigation session as a ROS node (nodes.h, docs/ros.md): a depth
// camera's clouds or images in, the local grid and a virtual scan out.
#include <carenav/common/errors.h>
#include <carenav/perception/pipeline.h>
#include <carenav/ros/nodes.h>

#include "depth_topics.h"
#include "msg_convert.h"
#include "node_common.h"

#include <nav_msgs/OccupancyGrid.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <memory>

namespace carenav::ros {

namespace {

class PerceiveNode {
 public:
  PerceiveNode(const PerceiveNodeOptions& o, perception::Pipeline& pipe,
               const perception::PerceptionParams& p, std::string label,
               const mrpt::poses::CPose3D& pose)
      : o_(o), pipe_(pipe), p_(p), label_(std::move(label)), pose_(pose) {
    depth_ = std::make_unique<DepthTopics>(
        nh_, "points", "depth", 1, label_, pose_,
        [this](const auto& obs, const ::ros::Time& stamp) { frame(*obs, stamp); });
    odom_ = nh_.subscribe("odom", 20, &PerceiveNode::onOdom, this);
    grid_pub_ = nh_.advertise<nav_msgs::OccupancyGrid>("local_grid", 2);
    scan_pub_ = nh_.advertise<sensor_msgs::LaserScan>("virtual_scan", 5);
  }
  size_t frames() const { return frames_; }

 private:
  void onOdom(const nav_msgs::Odometry& m) {
    const auto& p = m.pose.pose;
    odo_ = mrpt::poses::CPose2D(p.position.x, p.position.y, yawOf(p.orientation));
    have_odom_ = true;
  }
  void frame(mrpt::obs::CObservation3DRangeScan& obs, const ::ros::Time& stamp);
  void publishGrid(const ::ros::Time& stamp);
  void publishScan(const ::ros::Time& stamp);

  const PerceiveNodeOptions& o_;
  perception::Pipeline& pipe_;
  const perception::PerceptionParams& p_;
  const std::string label_;
  const mrpt::poses::CPose3D pose_;
  ::ros::NodeHandle nh_;
  std::unique_ptr<DepthTopics> depth_;  // points, depth/image + depth/camera_info
  ::ros::Subscriber odom_;
  ::ros::Publisher grid_pub_, scan_pub_;
  mrpt::poses::CPose2D odo_;  // identity until odometry arrives
  bool have_odom_ = false;
  size_t frames_ = 0;
};

void PerceiveNode::frame(mrpt::obs::CObservation3DRangeScan& obs, const ::ros::Time& stamp) {
  const auto cloud = perception::cloudFromObservation(obs);
  if (!cloud) return;
  perception::FrameInput fi;
  fi.cloud = &*cloud;
  fi.sensor_origin = {static_cast<float>(pose_.x()), static_cast<float>(pose_.y()),
                      static_cast<float>(pose_.z())};
  fi.depth_obs = &obs;
  fi.odometry = odo_;
  pipe_.process(fi, false);
  ++frames_;
  publishGrid(stamp);
  publishScan(stamp);
}

// The robot-centred grid, axis-aligned with the odometry frame (the base
// frame until odometry arrives).
void PerceiveNode::publishGrid(const ::ros::Time& stamp) {
  grid_pub_.publish(
      gridToRos(pipe_.grid().toMrpt(), have_odom_ ? o_.odom_frame : o_.base_frame, stamp));
}

// 360 degrees around the robot, per bearing the nearest occupied cell of the
// local grid (obstacles and drops alike); none within half the grid: +inf.
void PerceiveNode::publishScan(const ::ros::Time& stamp) {
  const auto& g = pipe_.grid();
  const auto& robot = g.robot();
  const int bins = std::max(1, static_cast<int>(std::lround(360 / p_.scan_resolution)));
  const double inc = 2 * M_PI / bins, max_range = g.cells() / 2 * g.resolution();
  sensor_msgs::LaserScan m;
  m.header.stamp = stamp;
  m.header.frame_id = o_.base_frame;
  m.angle_min = static_cast<float>(-M_PI);
  m.angle_increment = static_cast<float>(inc);
  m.angle_max = static_cast<float>(-M_PI + inc * (bins - 1));
  m.range_min = 0;
  m.range_max = static_cast<float>(max_range);
  m.ranges.assign(bins, std::numeric_limits<float>::infinity());
  for (int k = 0; k < bins; ++k) {
    const double a = robot.phi() - M_PI + k * inc;
    g.walkSegment(robot.x() + max_range * std::cos(a), robot.y() + max_range * std::sin(a), 0,
                  max_range, [&](int i, int j, double d) {
                    if (g.prob(i, j) <= p_.occupied_threshold) return true;
                    m.ranges[k] = static_cast<float>(d);
                    return false;
                  });
  }
  scan_pub_.publish(m);
}

/** The camera's label and pose on the robot: --sensor, else [perception]
 *  sensor, else the first depth camera; --sensor-pose wins over the profile. */
std::pair<std::string, mrpt::poses::CPose3D> cameraOf(const PerceiveNodeOptions& o,
                                                      const navigation::SessionSetup& s,
                                                      const std::string& percp_sensor) {
  const std::string want = !o.sensor.empty() ? o.sensor : percp_sensor;
  for (const auto& sp : s.sensors) {
    if (sp.type != "depth-camera" || (!want.empty() && sp.label != want)) continue;
    const mrpt::poses::CPose3D pose(sp.x, sp.y, sp.z, mrpt::DEG2RAD(sp.yaw),
                                    mrpt::DEG2RAD(sp.pitch), mrpt::DEG2RAD(sp.roll));
    if (o.sensor_pose.empty()) return {sp.label, pose};
    return {sp.label, perception::parseSensorPose(o.sensor_pose)};
  }
  if (!o.sensor_pose.empty())
    return {want.empty() ? "camera" : want, perception::parseSensorPose(o.sensor_pose)};
  throw InputError(o.profile + ": no depth camera" + (want.empty() ? "" : " '" + want + "'") +
                   " (give --sensor LABEL or --sensor-pose x,y,z,yaw,pitch,roll)");
}

}  // namespace

size_t runPerceiveNode(const PerceiveNodeOptions& o) {
  const auto method = perception::parseMethod(o.method);  // bad input: before ROS
  if (method == perception::Method::Mrpt2DScan)
    throw InputError(
        "--method mrpt-2dscan: not offered by the node (rrt-gpd, ransac, height-band)");
  const auto before = navigation::sessionSetup(o.profile, o.sets, "");
  cameraOf(o, before, before.profile.section<perception::PerceptionParams>("perception").sensor);
  const auto setup = startNode("carenav_perceive", o.profile, o.sets, "", o.ros_args);
  const auto params = setup.profile.section<perception::PerceptionParams>("perception");
  const auto [label, pose] = cameraOf(o, setup, params.sensor);
  perception::Pipeline pipe(params, method);
  size_t frames = 0;
  {
    PerceiveNode node(o, pipe, params, label, pose);
    spinNode(o.duration, o.stop);
    frames = node.frames();
  }
  if (!o.quiet) std::cerr << "carenav ros perceive: " << frames << " frames (" << label << ")\n";
  ::ros::shutdown();
  return frames;
}

}  // namespace carenav::ros
