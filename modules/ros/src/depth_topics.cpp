#include "depth_topics.h"

#include "msg_convert.h"

namespace carenav::ros {

DepthTopics::DepthTopics(::ros::NodeHandle& nh, const std::string& points, const std::string& ns,
                         uint32_t queue, std::string label, const mrpt::poses::CPose3D& pose,
                         Frame frame)
    : label_(std::move(label)), pose_(pose), frame_(std::move(frame)) {
  points_ = nh.subscribe(points, queue, &DepthTopics::onPoints, this);
  image_ = nh.subscribe(ns + "/image", queue, &DepthTopics::onImage, this);
  info_sub_ = nh.subscribe(ns + "/camera_info", 1, &DepthTopics::onInfo, this);
}

void DepthTopics::onPoints(const sensor_msgs::PointCloud2& m) {
  if (auto obs = cloudFromRos(m, label_, pose_)) frame_(obs, m.header.stamp);
}

void DepthTopics::onImage(const sensor_msgs::Image& m) {
  if (!info_) return;  // no intrinsics yet
  if (auto obs = depthFromRos(m, *info_, label_, pose_)) frame_(obs, m.header.stamp);
}

}  // namespace carenav::ros
