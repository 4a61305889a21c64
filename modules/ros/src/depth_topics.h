// A depth camera's frames from its topics, for every node that reads a
// depth camera (`ros perceive`, `ros navigate`): a PointCloud2, or a depth
// Image with its CameraInfo (depth_topics.cpp).
#pragma once

#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/poses/CPose3D.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>

#include <functional>
#include <optional>
#include <string>

namespace carenav::ros {

/** Subscribes `points` (sensor_msgs/PointCloud2, float x, y, z in the
 *  camera's body frame: x forward, y left, z up) and `NS/image` +
 *  `NS/camera_info` (a depth image, 16UC1 / mono16 in mm or 32FC1 in m,
 *  unprojected with the K of the last CameraInfo; an image before any
 *  CameraInfo is dropped). Each frame goes to `frame` as a depth
 *  observation of camera `label` at `pose` (its body-frame pose on the
 *  robot) with the message's stamp; messages that do not convert are
 *  dropped. */
class DepthTopics {
 public:
  using Frame = std::function<void(const mrpt::obs::CObservation3DRangeScan::Ptr& obs,
                                   const ::ros::Time& stamp)>;
  DepthTopics(::ros::NodeHandle& nh, const std::string& points, const std::string& ns,
              uint32_t queue, std::string label, const mrpt::poses::CPose3D& pose, Frame frame);
  DepthTopics(const DepthTopics&) = delete;
  DepthTopics& operator=(const DepthTopics&) = delete;

 private:
  void onPoints(const sensor_msgs::PointCloud2& m);
  void onImage(const sensor_msgs::Image& m);
  void onInfo(const sensor_msgs::CameraInfo& m) { info_ = m; }

  const std::string label_;
  const mrpt::poses::CPose3D pose_;
  const Frame frame_;
  ::ros::Subscriber points_, image_, info_sub_;
  std::optional<sensor_msgs::CameraInfo> info_;
};

}  // namespace carenav::ros
