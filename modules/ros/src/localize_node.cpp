// `carenav ros localize`: the Localizer of `carenav localize` as a ROS node
// (nodes.h, docs/ros.md): scans and odometry in, amcl's topics out.
#include <carenav/common/errors.h>
#include <carenav/io/map_io.h>
#include <carenav/localization/localization_params.h>
#include <carenav/localization/localizer.h>
#include <carenav/places/places.h>
#include <carenav/places/places_report.h>
#include <carenav/ros/nodes.h>
#include <carenav/runtime/session.h>
#include <carenav/sim/world.h>

#include "msg_convert.h"
#include "node_common.h"

#include <geometry_msgs/PoseArray.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <nav_msgs/Odometry.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_msgs/TFMessage.h>

#include <iostream>
#include <optional>

namespace carenav::ros {

namespace {

using mrpt::poses::CPose2D;

const char* const kInRoomParam = "in_room";  // ~in_room: the node's own, not a profile key

class LocalizeNode {
 public:
  LocalizeNode(const LocalizeNodeOptions& o, localization::Localizer& loc,
               const SensorParams& lidar)
      : o_(o), loc_(loc), lidar_(lidar) {
    scan_ = nh_.subscribe("scan", 5, &LocalizeNode::onScan, this);
    odom_ = nh_.subscribe("odom", 20, &LocalizeNode::onOdom, this);
    init_ = nh_.subscribe("initialpose", 2, &LocalizeNode::onInitialPose, this);
    pose_ = nh_.advertise<geometry_msgs::PoseWithCovarianceStamped>("amcl_pose", 5, true);
    cloud_ = nh_.advertise<geometry_msgs::PoseArray>("particlecloud", 2, true);
    tf_ = nh_.advertise<tf2_msgs::TFMessage>("tf", 10);
  }

 private:
  void onOdom(const nav_msgs::Odometry& m) {
    const auto& p = m.pose.pose;
    odo_ = CPose2D(p.position.x, p.position.y, yawOf(p.orientation));
    have_odom_ = true;
  }
  void onInitialPose(const geometry_msgs::PoseWithCovarianceStamped& m) {
    const auto& p = m.pose.pose;
    const double sx = std::sqrt(std::max(m.pose.covariance[0], 0.01));
    const double sy = std::sqrt(std::max(m.pose.covariance[7], 0.01));
    const double sa = std::sqrt(std::max(m.pose.covariance[35], 0.003));
    loc_.initPose(CPose2D(p.position.x, p.position.y, yawOf(p.orientation)), sx, sy, sa);
    started_ = false;
  }
  void onScan(const sensor_msgs::LaserScan& m);
  void publish(const ::ros::Time& stamp);

  const LocalizeNodeOptions& o_;
  localization::Localizer& loc_;
  const SensorParams& lidar_;
  ::ros::NodeHandle nh_;
  ::ros::Subscriber scan_, odom_, init_;
  ::ros::Publisher pose_, cloud_, tf_;
  CPose2D odo_, last_odo_;
  bool have_odom_ = false, started_ = false;
  const double t0_ = ::ros::Time::now().toSec();
};

void LocalizeNode::onScan(const sensor_msgs::LaserScan& m) {
  if (!have_odom_) return;
  const mrpt::poses::CPose3D pose(lidar_.x, lidar_.y, lidar_.z, mrpt::DEG2RAD(lidar_.yaw),
                                  mrpt::DEG2RAD(lidar_.pitch), mrpt::DEG2RAD(lidar_.roll));
  const CPose2D inc = started_ ? odo_ - last_odo_ : CPose2D();
  last_odo_ = odo_;
  started_ = true;
  loc_.step(inc, scanFromRos(m, lidar_.label, pose), m.header.stamp.toSec() - t0_);
  publish(m.header.stamp);
}

void LocalizeNode::publish(const ::ros::Time& stamp) {
  const CPose2D p = loc_.pose();
  const auto cov = loc_.covariance();
  geometry_msgs::PoseWithCovarianceStamped m;
  m.header.stamp = stamp;
  m.header.frame_id = o_.map_frame;
  m.pose.pose.position.x = p.x();
  m.pose.pose.position.y = p.y();
  m.pose.pose.orientation = yawQuaternion(p.phi());
  // x, y, yaw of the 6x6 (x y z roll pitch yaw) row-major covariance.
  const int idx[3] = {0, 1, 5};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m.pose.covariance[idx[r] * 6 + idx[c]] = cov(r, c);
  pose_.publish(m);
  geometry_msgs::PoseArray cloud;
  cloud.header = m.header;
  const auto& parts = loc_.particles().m_particles;
  const size_t step = std::max<size_t>(1, parts.size() / std::max<size_t>(1, o_.cloud_max));
  for (size_t i = 0; i < parts.size(); i += step) {
    geometry_msgs::Pose q;
    q.position.x = parts[i].d.x;
    q.position.y = parts[i].d.y;
    q.orientation = yawQuaternion(parts[i].d.phi);
    cloud.poses.push_back(q);
  }
  cloud_.publish(cloud);
  geometry_msgs::TransformStamped t;
  t.header = m.header;
  t.child_frame_id = o_.odom_frame;
  t.transform = transformOf(mrpt::poses::CPose3D(p + (-odo_)));
  tf2_msgs::TFMessage tf;
  tf.transforms.push_back(t);
  tf_.publish(tf);
}

}  // namespace

namespace {

/** The room the filter starts in (`--in-room`, else `~in_room`), read from
 *  the places file; none when no room is named. Throws InputError for an
 *  unknown room ("FILE: no room named 'NAME' (rooms: ...)"), a bad places
 *  file, or a room together with --start. */
std::optional<places::RoomArea> startRoom(const LocalizeNodeOptions& o, const std::string& name) {
  if (name.empty()) return std::nullopt;
  if (o.start) throw InputError("give --start or --in-room (~in_room), not both");
  const std::string file =
      !o.places.empty() ? o.places : places::placesPathForMap(!o.world.empty() ? o.world : o.map);
  return places::readRoomArea(file, name);
}

void initFilter(localization::Localizer& loc, const LocalizeNodeOptions& o,
                const std::optional<places::RoomArea>& room) {
  if (o.start)
    loc.initPose(CPose2D(o.start->x, o.start->y, o.start->phi), 0.2, 0.2, mrpt::DEG2RAD(5.0));
  else if (room)
    loc.initInRegion(room->inside, "room '" + room->name + "'");
  else
    loc.initGlobal();
}

}  // namespace

void runLocalizeNode(const LocalizeNodeOptions& o) {
  auto setup = navigation::sessionSetup(o.profile, o.sets, "");  // bad input: before ROS
  if (o.map.empty() == o.world.empty()) throw InputError("give --map M or --world W.yaml");
  const auto grid = !o.world.empty() ? sim::loadWorld(o.world).grid() : io::loadGridMap(o.map);
  auto room = startRoom(o, o.in_room);
  initRosNode("carenav_localize", o.ros_args);
  if (auto sets = privateParamOverrides({kInRoomParam}); !sets.empty()) {
    sets.insert(sets.end(), o.sets.begin(), o.sets.end());
    setup = navigation::sessionSetup(o.profile, sets, "");
  }
  if (o.in_room.empty()) room = startRoom(o, ::ros::param::param<std::string>("~in_room", ""));
  const SensorParams* lidar = nullptr;
  for (const auto& s : setup.sensors)
    if (s.type == "lidar2d" && !lidar) lidar = &s;
  if (!lidar) throw InputError(o.profile + ": no lidar2d sensor to localise with");
  localization::Localizer loc(
      grid, setup.profile.section<localization::LocalizationParams>("localization"));
  initFilter(loc, o, room);
  {
    LocalizeNode node(o, loc, *lidar);
    if (!o.quiet)
      std::cerr << "carenav ros localize: " << loc.particleCount() << " particles"
                << (room ? " in room '" + room->name + "'" : std::string()) << "\n";
    spinNode(o.duration, o.stop);
  }
  ::ros::shutdown();
}

}  // namespace carenav::ros
