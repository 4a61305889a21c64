// carenav import rosbag BAG --out X.rawlog [--scan TOPIC[=LABEL]]... [--cloud TOPIC[=LABEL]]...
//                        [--depth TOPIC[=LABEL]]... [--camera-info TOPIC]... [--odom TOPIC|tf|none]
// (built with the ROS part only). Also registers `.bag` with the rawlog
// reader, so every command that reads a rawlog reads a bag.
#include "commands.h"

#include <carenav/common/errors.h>
#include <carenav/common/profile.h>
#include <carenav/common/robot.h>
#include <carenav/io/rawlog_reader.h>
#include <carenav/ros/bag.h>

#include <mrpt/core/bits_math.h>

#include <iostream>

namespace carenav::app {

namespace {

const bool kBagRegistered = (ros::registerBagFormat(), true);

void addImportRosbag(CLI::App& import_cmd, const GlobalOptions& g) {
  struct Args {
    ros::BagImportOptions opt;
    std::string profile;
    std::vector<std::string> sets;
    bool json = false;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = import_cmd.add_subcommand(
      "rosbag",
      "Convert a ROS 1 bag to an MRPT rawlog (observation-only form, gzip): its "
      "sensor_msgs/LaserScan as 2D scans, PointCloud2 as 3D points and depth Images (with "
      "their CameraInfo) as range images (sensor pose from "
      "/tf_static or /tf up to the base frame, else the profile's [sensor.LABEL]) and its odometry "
      "(nav_msgs/Odometry, or the "
      "odom -> base_link transform of /tf) with the messages' own time stamps. The bag is read "
      "front to back without its index: a truncated or corrupt bag stops with exit 2 naming "
      "the byte where it broke; what was read before it is written.");
  cmd->add_option("bag", a->opt.input, "ROS bag (format 2.0; chunks none, lz4 or bz2)")->required();
  cmd->add_option("-o,--out", a->opt.output, "Rawlog to write (gzip, written atomically)")
      ->required();
  cmd->add_option("--scan", a->opt.read.scans,
                  "LaserScan topic to read, TOPIC or TOPIC=LABEL (the sensor label; default: "
                  "the scan's frame_id); repeatable. Default: every LaserScan topic");
  cmd->add_option("--cloud", a->opt.read.clouds,
                  "PointCloud2 topic to read, TOPIC or TOPIC=LABEL (as --scan), as "
                  "CObservation3DRangeScan points for carenav perceive; repeatable, or 'none'. "
                  "Default: every PointCloud2 topic");
  cmd->add_option("--depth", a->opt.read.depths,
                  "Depth image topic (sensor_msgs/Image, 16UC1 mm or 32FC1 m) to read, TOPIC or "
                  "TOPIC=LABEL (default label: the image's frame without _optical_frame), as "
                  "CObservation3DRangeScan range images with the intrinsics of its "
                  "camera_info; repeatable, or 'none'. Default: every 16UC1 / 32FC1 Image topic "
                  "with a CameraInfo on its sibling camera_info topic");
  cmd->add_option("--camera-info", a->opt.read.camera_infos,
                  "CameraInfo topic of each --depth, in order (default: the depth topic's "
                  "sibling, /cam/depth/image_raw -> /cam/depth/camera_info)");
  cmd->add_option("--odom", a->opt.read.odom,
                  "Odometry: a nav_msgs/Odometry topic, 'tf' (odom -> base frame on /tf) or "
                  "'none'. Default: the bag's first Odometry topic, else tf");
  cmd->add_option("--odom-frame", a->opt.read.odom_frame, "tf odometry frame")
      ->capture_default_str();
  cmd->add_option("--base-frame", a->opt.read.base_frame, "tf robot frame")->capture_default_str();
  cmd->add_option("--profile", a->profile,
                  "Robot profile: the pose of [sensor.LABEL] for scans tf does not place");
  cmd->add_option("--set", a->sets, "Profile override section.key=value (repeatable)");
  cmd->add_flag("--json", a->json, "Print the summary as JSON");
  cmd->footer(
      "Example:\n"
      "  carenav import rosbag run.bag --scan /scan=laser --out run.rawlog\n"
      "  carenav slam --profile ini/interbot.ini --rawlog run.bag --out map/   (bags read "
      "directly too)\nSee docs/ros.md.");
  cmd->callback([a, &g] {
    prepareOutputFile(a->opt.output);
    if (!a->profile.empty()) {
      Profile p = Profile::load(a->profile);
      p.applyOverrides(a->sets);
      p.validate();
      for (const auto& s : loadSensors(p))
        a->opt.read.sensor_poses[s.label] = mrpt::poses::CPose3D(
            s.x, s.y, s.z, mrpt::DEG2RAD(s.yaw), mrpt::DEG2RAD(s.pitch), mrpt::DEG2RAD(s.roll));
    }
    a->opt.progress = !g.quiet;
    ros::BagImportStats st;
    try {
      ros::importRosbag(a->opt, &st);
    } catch (const io::RawlogError&) {
      std::cout << (a->json ? st.toJson() : st.toText()) << std::flush;
      throw;
    }
    std::cout << (a->json ? st.toJson() : st.toText()) << std::flush;
  });
}

}  // namespace

CARENAV_IMPORT(addImportRosbag);

}  // namespace carenav::app
