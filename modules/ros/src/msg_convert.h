// ROS messages <-> MRPT observations and poses (carenav's own conversions:
// mrpt-ros1bridge links OpenCV's GUI modules, which carenav must not).
#pragma once

#include <geometry_msgs/Quaternion.h>
#include <geometry_msgs/Transform.h>
#include <mrpt/core/Clock.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/poses/CPose3D.h>
#include <ros/time.h>
#include <sensor_msgs/LaserScan.h>

#include <string>

namespace carenav::ros {

mrpt::Clock::time_point fromRosTime(const ::ros::Time& t);
::ros::Time toRosTime(mrpt::Clock::time_point t);

double yawOf(const geometry_msgs::Quaternion& q);
geometry_msgs::Quaternion yawQuaternion(double yaw);
mrpt::poses::CPose3D poseOf(const geometry_msgs::Transform& t);
geometry_msgs::Transform transformOf(const mrpt::poses::CPose3D& p);

/** A LaserScan as an MRPT scan on a robot at `sensor_pose` (a scan not
 *  centred on its frame's x axis turns the pose by its middle bearing).
 *  Valid ranges: finite, >= range_min and > 0, <= range_max. */
mrpt::obs::CObservation2DRangeScan::Ptr scanFromRos(const sensor_msgs::LaserScan& m,
                                                    const std::string& label,
                                                    const mrpt::poses::CPose3D& sensor_pose);
/** An MRPT scan as a LaserScan in `frame` (invalid ranges: +inf). */
sensor_msgs::LaserScan scanToRos(const mrpt::obs::CObservation2DRangeScan& s,
                                 const std::string& frame);

/** "/a/b" -> "a/b": tf frame names compared without a leading slash. */
std::string bareFrame(const std::string& f);

}  // namespace carenav::ros
