// A rawlog written as a bag through rosbag storage (bag.h).
#include <carenav/io/rawlog_reader.h>
#include <carenav/ros/bag.h>

#include "msg_convert.h"

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <tf2_msgs/TFMessage.h>

#include <optional>
#include <set>

namespace carenav::ros {

namespace {

class BagWriter {
 public:
  BagWriter(const std::string& path, const BagWriteOptions& o) : o_(o) {
    bag_.open(path, rosbag::bagmode::Write);
    bag_.setChunkThreshold(o.chunk_bytes);
  }
  ~BagWriter() { bag_.close(); }
  void entry(const io::RawlogEntry& e);
  size_t scans() const { return scans_; }

 private:
  ::ros::Time stamp(mrpt::Clock::time_point t) {
    // Bag times never go back (the last one is kept for an entry without one).
    if (t != INVALID_TIMESTAMP) last_ = std::max(last_, toRosTime(t));
    return last_;
  }
  void odometry(mrpt::Clock::time_point t, const mrpt::poses::CPose2D& odo, double v, double w);
  void scan(const mrpt::obs::CObservation2DRangeScan& s);

  rosbag::Bag bag_;
  BagWriteOptions o_;
  ::ros::Time last_{1.0};
  std::optional<mrpt::poses::CPose2D> pose_;  // odometry summed from increments
  std::set<std::string> placed_;              // sensor frames sent on /tf_static
  size_t scans_ = 0;
};

void BagWriter::odometry(mrpt::Clock::time_point t, const mrpt::poses::CPose2D& odo, double v,
                         double w) {
  const ::ros::Time ts = stamp(t);
  nav_msgs::Odometry m;
  m.header.stamp = ts;
  m.header.frame_id = o_.odom_frame;
  m.child_frame_id = o_.base_frame;
  m.pose.pose.position.x = odo.x();
  m.pose.pose.position.y = odo.y();
  m.pose.pose.orientation = yawQuaternion(odo.phi());
  m.twist.twist.linear.x = v;
  m.twist.twist.angular.z = w;
  bag_.write(o_.odom_topic, ts, m);
  if (!o_.tf_odometry) return;
  tf2_msgs::TFMessage tf;
  geometry_msgs::TransformStamped t2;
  t2.header = m.header;
  t2.child_frame_id = o_.base_frame;
  t2.transform = transformOf(mrpt::poses::CPose3D(odo));
  tf.transforms.push_back(t2);
  bag_.write("/tf", ts, tf);
}

void BagWriter::scan(const mrpt::obs::CObservation2DRangeScan& s) {
  const ::ros::Time ts = stamp(s.timestamp);
  const std::string frame = s.sensorLabel.empty() ? o_.default_frame : s.sensorLabel;
  if (placed_.insert(frame).second) {
    tf2_msgs::TFMessage tf;
    geometry_msgs::TransformStamped t;
    t.header.stamp = ts;
    t.header.frame_id = o_.base_frame;
    t.child_frame_id = frame;
    t.transform = transformOf(s.sensorPose);
    tf.transforms.push_back(t);
    bag_.write("/tf_static", ts, tf);
  }
  auto m = scanToRos(s, frame);
  m.header.stamp = ts;
  bag_.write(o_.scan_topic, ts, m);
  ++scans_;
}

void BagWriter::entry(const io::RawlogEntry& e) {
  if (e.odometry_source == io::OdometrySource::Action && e.odometry_increment) {
    // A reading at the origin first, so the first increment is one too.
    if (!pose_) odometry(e.timestamp, *(pose_ = mrpt::poses::CPose2D()), 0, 0);
    pose_ = *pose_ + *e.odometry_increment;
    odometry(e.timestamp, *pose_, 0, 0);
  }
  for (const auto& o : e.observations()) {
    if (auto odo = std::dynamic_pointer_cast<mrpt::obs::CObservationOdometry>(o))
      odometry(odo->timestamp, odo->odometry, odo->hasVelocities ? odo->velocityLocal.vx : 0,
               odo->hasVelocities ? odo->velocityLocal.omega : 0);
    else if (auto s = std::dynamic_pointer_cast<mrpt::obs::CObservation2DRangeScan>(o))
      scan(*s);
  }
}

}  // namespace

size_t writeBagFromRawlog(const std::string& rawlog, const std::string& bag,
                          const BagWriteOptions& o) {
  io::RawlogReader reader(rawlog);
  BagWriter w(bag, o);
  io::RawlogEntry e;
  while (reader.next(e)) w.entry(e);
  return w.scans();
}

}  // namespace carenav::ros
