// ROS messages <-> MRPT observations and poses (carenav's own conversions:
// mrpt-ros1bridge links OpenCV's GUI modules, which carenav must not).
#pragma once

#include <geometry_msgs/Quaternion.h>
#include <geometry_msgs/Transform.h>
#include <mrpt/core/Clock.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/poses/CPose3D.h>
#include <nav_msgs/OccupancyGrid.h>
#include <ros/time.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>

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

/** A PointCloud2 with float x, y, z fields in the sensor's body frame (x
 *  forward, y left, z up) as a depth observation of points (points with a
 *  NaN or infinite coordinate left out, each with its pixel: column, row)
 *  at `sensor_pose` on the robot;
 *  nullptr when it has no float x, y, z or its data is shorter than its
 *  size says. */
mrpt::obs::CObservation3DRangeScan::Ptr cloudFromRos(const sensor_msgs::PointCloud2& m,
                                                     const std::string& label,
                                                     const mrpt::poses::CPose3D& sensor_pose);
/** A depth image (16UC1 / mono16 in mm, 32FC1 in m; depth along the optical
 *  axis, 0 or NaN: no return) with its camera's intrinsics (K of
 *  CameraInfo) as a depth observation with a range image; `sensor_pose` is
 *  the camera's body-frame pose on the robot (x forward). nullptr for other
 *  encodings, big-endian data, a short buffer or no intrinsics. */
mrpt::obs::CObservation3DRangeScan::Ptr depthFromRos(const sensor_msgs::Image& img,
                                                     const sensor_msgs::CameraInfo& info,
                                                     const std::string& label,
                                                     const mrpt::poses::CPose3D& sensor_pose);

/** A depth observation's range image as a 16UC1 Image (mm; 0: no return)
 *  and its intrinsics as the CameraInfo (K, P, no distortion), both in
 *  `frame` (the camera's optical frame) and stamped `stamp`; false when the
 *  observation has no range image. The inverse of depthFromRos. */
bool depthToRos(const mrpt::obs::CObservation3DRangeScan& o, const std::string& frame,
                const ::ros::Time& stamp, sensor_msgs::Image& img, sensor_msgs::CameraInfo& info);

/** The pose of a camera's optical frame (z along the optical axis, x right,
 *  y down: the frame of sensor_msgs/Image) in its body frame (x forward, y
 *  left, z up; REP 103): yaw -90 deg, roll -90 deg. */
mrpt::poses::CPose3D opticalInBody();

/** A camera's label from its optical frame's name: without a trailing
 *  `_optical_frame` or `_optical` ("kinect_optical" -> "kinect"). */
std::string cameraOfOpticalFrame(const std::string& frame);

/** An MRPT grid as a ROS map in `frame`: -1 unknown (p = 0.5), else
 *  100 x p(occupied), rows along y from the grid's lower corner. */
nav_msgs::OccupancyGrid gridToRos(const mrpt::maps::COccupancyGridMap2D& g,
                                  const std::string& frame, const ::ros::Time& stamp);

/** "/a/b" -> "a/b": tf frame names compared without a leading slash. */
std::string bareFrame(const std::string& f);

}  // namespace carenav::ros
