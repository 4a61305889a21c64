// ROS bags as input (docs/ros.md): their laser scans and odometry as MRPT
// observations, so a `.bag` reads wherever a rawlog does, `carenav import
// rosbag` to a rawlog, and a rawlog written out as a bag (tests, benchmarks).
// This header includes no ROS header.
#pragma once

#include <carenav/io/rawlog_formats.h>

#include <mrpt/poses/CPose3D.h>

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace carenav::ros {

/** What a bag is read for: which topics, and how frames become poses. */
struct BagReadOptions {
  /** sensor_msgs/LaserScan topics, each optionally "TOPIC=LABEL" (the
   *  observation's sensor label; default: the scan's frame_id, else the
   *  topic without its leading '/'). Empty: every LaserScan topic. */
  std::vector<std::string> scans;
  /** sensor_msgs/PointCloud2 topics (float x, y, z in the frame_id's
   *  frame), each optionally "TOPIC=LABEL" as for scans; empty: every
   *  PointCloud2 topic; {"none"}: none. */
  std::vector<std::string> clouds;
  /** sensor_msgs/Image depth topics (16UC1 / mono16 in mm, 32FC1 in m),
   *  each optionally "TOPIC=LABEL" (default label: the image's frame_id
   *  without a trailing `_optical_frame` / `_optical`, else the topic). Each
   *  is unprojected with the last CameraInfo of its sibling topic
   *  (`/cam/depth/image_raw` -> `/cam/depth/camera_info`) or of
   *  camera_infos[i]. Empty: every Image topic in 16UC1 or 32FC1 whose
   *  sibling has a CameraInfo; {"none"}: none. */
  std::vector<std::string> depths;
  /** The CameraInfo topic of each of `depths`, in order; empty: the siblings. */
  std::vector<std::string> camera_infos;
  /** Odometry: a nav_msgs/Odometry topic, "tf" (the odom_frame ->
   *  base_frame transform of /tf), "none", or "" (the first Odometry topic
   *  of the bag, else tf). */
  std::string odom;
  std::string odom_frame = "odom";
  std::string base_frame = "base_link";
  /** Sensor poses on the robot by label (the profile's [sensor.*] pose),
   *  used when /tf_static (or /tf) does not link the scan's frame to
   *  base_frame. */
  std::map<std::string, mrpt::poses::CPose3D> sensor_poses;
};

/** What reading a bag met beyond the observations it gave. */
struct BagReadNotes {
  size_t messages = 0;      ///< bag messages read (every topic)
  size_t scans = 0;         ///< laser scans given out
  size_t odometry = 0;      ///< odometry readings given out
  size_t skipped = 0;       ///< messages of topics not read
  size_t scans_no_tf = 0;   ///< scans whose frame tf did not place on the robot
  size_t clouds = 0;        ///< point clouds given out
  size_t clouds_no_tf = 0;  ///< clouds whose frame tf did not place
  size_t depth_images = 0;  ///< depth images given out
  size_t depth_no_tf = 0;   ///< depth images whose frame tf did not place
  /** Depth images left out: no CameraInfo before them, or not decodable
   *  (an encoding other than 16UC1 / mono16 / 32FC1, a short buffer). */
  size_t depth_dropped = 0;
  std::map<std::string, std::string> topics;  ///< topic -> type, as met
};

/** A bag as an observation source (rawlog_formats.h): CObservation2DRangeScan,
 *  CObservation3DRangeScan (clouds as points in the sensor frame, depth
 *  images as range images with their intrinsics; the sensor pose from tf:
 *  an image's optical frame turned to the camera's body frame) and
 *  CObservationOdometry (label "odometry") in the
 *  bag's order, stamped
 *  with the messages' header stamps. Throws InputError when the file is not
 *  a bag; a bag broken further on throws io::RawlogError from next() naming
 *  the file, the message count and the byte. `notes` (optional) is filled
 *  while reading. */
std::unique_ptr<io::ObservationSource> openBag(const std::string& path, BagReadOptions options,
                                               std::shared_ptr<BagReadNotes> notes = nullptr);

/** Registers `.bag` with the rawlog reader (default BagReadOptions). */
void registerBagFormat();

struct BagImportOptions {
  std::string input, output;  ///< BAG, X.rawlog (gzip, written atomically)
  BagReadOptions read;
  bool progress = false;
};
struct BagImportStats {
  BagReadNotes notes;
  size_t written = 0;
  std::string toText() const;
  std::string toJson() const;
};
/** `carenav import rosbag`: the bag's scans and odometry to an observation-
 *  only rawlog. A broken bag: what was read before is written, then
 *  io::RawlogError (exit 2); `stats` gets what was written either way. */
BagImportStats importRosbag(const BagImportOptions& o, BagImportStats* stats = nullptr);

struct BagWriteOptions {
  std::string scan_topic = "/scan";
  std::string odom_topic = "/odom";
  std::string odom_frame = "odom";
  std::string base_frame = "base_link";
  bool tf_odometry = false;             ///< also publish odom -> base_frame on /tf
  uint32_t chunk_bytes = 768 * 1024;    ///< rosbag's chunk threshold (its default)
  std::string default_frame = "laser";  ///< frame of scans without a sensor label
};
/** A rawlog (either form) as a bag (uncompressed, through rosbag storage):
 *  2D scans as sensor_msgs/LaserScan (frame_id = the sensor label, its pose
 *  on /tf_static), odometry (actions' increments summed, or odometry
 *  observations) as nav_msgs/Odometry. Returns the number of scans written.
 *  A broken rawlog: throws after writing (and closing) what was read. */
size_t writeBagFromRawlog(const std::string& rawlog, const std::string& bag,
                          const BagWriteOptions& o = {});

}  // namespace carenav::ros
