// `carenav ros slam`: a SLAM back end of `carenav slam` fed from topics
// (nodes.h, docs/ros.md): scans and odometry in, `map` and `map -> odom`
// out, the files of `carenav slam` written at the end and on `~save`.
#include <carenav/common/errors.h>
#include <carenav/ros/nodes.h>
#include <carenav/slam/mapper.h>
#include <carenav/slam/slam_job.h>

#include "msg_convert.h"
#include "node_common.h"

#include <nav_msgs/OccupancyGrid.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <std_msgs/Empty.h>
#include <tf2_msgs/TFMessage.h>

#include <chrono>
#include <iostream>

namespace carenav::ros {

namespace {

using mrpt::poses::CPose2D;

class SlamNode {
 public:
  SlamNode(const SlamNodeOptions& o, slam::Mapper& mapper, slam::SlamJobOptions& job,
           const SensorParams& lidar, int map_every)
      : o_(o), mapper_(mapper), job_(job), lidar_(lidar), map_every_(map_every), pnh_("~") {
    scan_ = nh_.subscribe("scan", 5, &SlamNode::onScan, this);
    odom_ = nh_.subscribe("odom", 50, &SlamNode::onOdom, this);
    tf_in_ = nh_.subscribe("tf", 50, &SlamNode::onTf, this);
    save_ = pnh_.subscribe("save", 2, &SlamNode::onSave, this);
    map_ = nh_.advertise<nav_msgs::OccupancyGrid>("map", 1, true);
    tf_ = nh_.advertise<tf2_msgs::TFMessage>("tf", 10);
    job_.rawlog = scan_.getTopic();  // what summary.json and map.png name as the source
  }
  /** The outputs of the run so far (after mapper.finish() at the end);
   *  "seconds" in summary.json: the mapper's time on the scans. */
  void save() {
    slam::writeSlamOutputs(mapper_, job_, res_,
                           "carenav ros slam " + job_.method + ": " + job_.rawlog);
  }
  size_t steps() const { return res_.steps; }

 private:
  void onScan(const sensor_msgs::LaserScan& m);
  void onOdom(const nav_msgs::Odometry& m) {
    const auto& p = m.pose.pose;
    odo_ = CPose2D(p.position.x, p.position.y, yawOf(p.orientation));
    odom_topic_ = have_odo_ = true;
  }
  // odom -> base_link of tf, when no Odometry message comes.
  void onTf(const tf2_msgs::TFMessage& m) {
    if (odom_topic_) return;
    for (const auto& t : m.transforms)
      if (bareFrame(t.header.frame_id) == o_.odom_frame &&
          bareFrame(t.child_frame_id) == o_.base_frame) {
        odo_ = CPose2D(mrpt::poses::CPose3D(poseOf(t.transform)));
        have_odo_ = true;
      }
  }
  void onSave(const std_msgs::Empty&) {
    if (res_.steps == 0) return;
    save();
    if (!o_.quiet) std::cerr << "carenav ros slam: saved " << res_.steps << " scans\n";
  }
  void publishMap(const ::ros::Time& stamp) {
    const auto grid =
        slam::gridFromSimpleMap(mapper_.simpleMap(), job_.mapper.slam.grid_resolution);
    map_.publish(gridToRos(grid, o_.map_frame, stamp));
  }
  void publishTf(const ::ros::Time& stamp);

  const SlamNodeOptions& o_;
  slam::Mapper& mapper_;
  slam::SlamJobOptions& job_;
  const SensorParams& lidar_;
  const int map_every_;
  ::ros::NodeHandle nh_, pnh_;
  ::ros::Subscriber scan_, odom_, tf_in_, save_;
  ::ros::Publisher map_, tf_;
  CPose2D odo_, last_odo_;
  bool have_odo_ = false, had_odo_ = false, odom_topic_ = false;
  size_t published_at_ = 0;  // scans inserted when the map was last published
  slam::SlamJobResult res_;
};

void SlamNode::onScan(const sensor_msgs::LaserScan& m) {
  const mrpt::poses::CPose3D pose(lidar_.x, lidar_.y, lidar_.z, mrpt::DEG2RAD(lidar_.yaw),
                                  mrpt::DEG2RAD(lidar_.pitch), mrpt::DEG2RAD(lidar_.roll));
  io::ScanStep step;
  step.index = step.entry = res_.steps;
  step.time = m.header.stamp.toSec();
  step.scan = scanFromRos(m, lidar_.label, pose);
  // The motion since the last scan: none before odometry arrives, then
  // from the odometry the last scan had (identity for the first).
  if (have_odo_) step.odometry = had_odo_ ? odo_ - last_odo_ : CPose2D();
  last_odo_ = odo_;
  had_odo_ = have_odo_;
  const auto c0 = std::chrono::steady_clock::now();
  mapper_.process(step);
  res_.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - c0).count();
  if (res_.steps++ == 0) res_.first_pose = mapper_.pose();
  res_.entries = res_.steps;
  publishTf(m.header.stamp);
  const size_t inserted = mapper_.stats().inserted;
  if (published_at_ == 0 ? inserted > 0 : inserted >= published_at_ + map_every_) {
    publishMap(m.header.stamp);
    published_at_ = inserted;
  }
}

// map -> odom: the mapper's pose of the robot after the odometry's.
void SlamNode::publishTf(const ::ros::Time& stamp) {
  geometry_msgs::TransformStamped t;
  t.header.stamp = stamp;
  t.header.frame_id = o_.map_frame;
  t.child_frame_id = o_.odom_frame;
  t.transform = transformOf(mrpt::poses::CPose3D(mapper_.pose() + (-odo_)));
  tf2_msgs::TFMessage tf;
  tf.transforms.push_back(t);
  tf_.publish(tf);
}

slam::SlamJobOptions jobOf(const SlamNodeOptions& o, const Profile& profile) {
  slam::SlamJobOptions job;
  job.out_dir = o.out_dir;
  job.mapper.slam = profile.section<slam::SlamParams>("slam");
  job.mapper.icp = profile.section<slam::IcpParams>("icp");
  job.mapper.rbpf = profile.section<slam::RbpfParams>("rbpf");
  job.method = o.method.empty() ? job.mapper.slam.method : o.method;
  return job;
}

const SensorParams& firstLidar(const navigation::SessionSetup& s, const std::string& profile) {
  for (const auto& sp : s.sensors)
    if (sp.type == "lidar2d") return sp;
  throw InputError(profile + ": no lidar2d sensor to map with");
}

}  // namespace

size_t runSlamNode(const SlamNodeOptions& o) {
  {
    const auto before = navigation::sessionSetup(o.profile, o.sets, "");  // bad input: before ROS
    firstLidar(before, o.profile);
    const auto job = jobOf(o, before.profile);
    slam::createMapper(job.method, job.mapper);
  }
  const auto setup = startNode("carenav_slam", o.profile, o.sets, "", o.ros_args, {"map_every"});
  auto job = jobOf(o, setup.profile);
  const int every = o.map_every > 0 ? o.map_every : ::ros::param::param("~map_every", 5);
  if (every <= 0) throw InputError("~map_every " + std::to_string(every) + ": give 1 or more");
  auto mapper = slam::createMapper(job.method, job.mapper);
  size_t steps = 0;
  {
    SlamNode node(o, *mapper, job, firstLidar(setup, o.profile), every);
    if (!o.quiet) std::cerr << "carenav ros slam: " << job.method << "\n";
    spinNode(o.duration, o.stop);
    steps = node.steps();
    if (steps > 0) {
      mapper->finish();
      node.save();
    }
  }
  ::ros::shutdown();
  if (steps == 0) throw InputError("no scan arrived on the scan topic: nothing mapped");
  if (!o.quiet)
    std::cerr << "carenav ros slam: " << steps << " scans mapped, " << o.out_dir << "\n";
  return steps;
}

}  // namespace carenav::ros
