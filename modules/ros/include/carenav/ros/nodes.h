// carenav as ROS 1 nodes (docs/ros.md): the simulator as a ROS robot, and
// the navigation session as a node (a third adapter of NavigationSession,
// beside the simulator runner and the TCP bridge). Topic names are relative
// (remappable: `scan:=/base_scan`); ROS arguments (remappings, `_param:=v`,
// `__name:=n`) are passed in `ros_args`. This header includes no ROS header.
#pragma once

#include <carenav/runtime/live_run.h>
#include <carenav/runtime/scenario.h>

#include <atomic>
#include <optional>
#include <string>
#include <vector>

namespace carenav::ros {

/** `carenav ros sim`: the built-in simulator in real time. Publishes `scan`
 *  (sensor_msgs/LaserScan, the profile's first lidar2d; others `scan_LABEL`),
 *  `odom` (nav_msgs/Odometry, with noise as the profile's [sim]), `tf`
 *  (odom -> base_link, base_link -> each lidar), `ground_truth`
 *  (nav_msgs/Odometry in the world's `map` frame), `clock`; takes `cmd_vel`
 *  (geometry_msgs/Twist; none for `cmd_timeout` s: the base stops). */
struct SimNodeOptions {
  std::string profile;
  std::vector<std::string> sets;
  std::string world;  ///< world YAML
  std::optional<navigation::TPose2D> start;
  std::string scenario;      ///< alternative: its world and start
  double rate = 50;          ///< Hz, simulation steps (paced to the wall clock)
  double duration = 0;       ///< s; 0: until stopped
  double cmd_timeout = 0.5;  ///< s
  std::string summary;       ///< JSON written at the end: truth, collisions, distance
  /** A bag of what the node publishes (odom, scans, tf, ground_truth), as
   *  `rosbag record` would write it (rosbag storage); empty: none. */
  std::string record;
  /** Depth cameras publish depth images (`depth/image`, sensor_msgs/Image
   *  16UC1 in mm, in the optical frame `LABEL_optical`) and their
   *  `depth/camera_info` instead of `points` clouds (others: `depth_LABEL/`). */
  bool depth_images = false;
  std::string odom_frame = "odom", base_frame = "base_link", map_frame = "map";
  std::vector<std::string> ros_args;
  const std::atomic<bool>* stop = nullptr;
  bool quiet = false;
};
/** Runs until stopped, `duration`, or the ROS master goes away. Throws
 *  InputError for bad files. */
void runSimNode(const SimNodeOptions& o);

/** `carenav ros navigate`: subscribes `scan`, `odom`, `move_base_simple/goal`
 *  (geometry_msgs/PoseStamped, map frame) and, for a walker, `intent`
 *  (geometry_msgs/Twist); publishes `cmd_vel` every control period, `plan`
 *  (nav_msgs/Path) and `~status` (std_msgs/String). Stale scans or odometry
 *  (by their header stamps against the node's clock) stop the robot within
 *  one period (the safety supervisor). */
/** With LiveRunOptions (profile, sets, plugin, start on the map,
 *  control_rate, out_dir, stop, progress); `duration` 0: until the goal is
 *  reached, or stopped. */
struct NavigateNodeOptions : navigation::LiveRunOptions {
  std::string map;    ///< static map (any map carenav reads) ...
  std::string world;  ///< ... or a simulator world's map
  std::string goal;   ///< "x,y,deg" or a place of the map's places file; else from the topic
  bool stay = false;  ///< after a goal, wait for the next one instead of ending
  /** Run the control cycle as soon as a scan arrives (its command follows
   *  it at once), with the timer only as a fallback one period after the
   *  last cycle (so stale data still stops the robot). */
  bool cycle_on_scan = false;
  /** Take the robot's map pose from `amcl_pose` (e.g. `carenav ros
   *  localize`) instead of localising in the node; needs --map/--world and
   *  --start (until the first pose arrives). */
  bool external_pose = false;
  std::string odom_frame = "odom", map_frame = "map";
  std::vector<std::string> ros_args;
};
navigation::RunMetrics runNavigateNode(const NavigateNodeOptions& o);

/** `carenav ros localize`: Monte Carlo localisation on a known map (the
 *  `localize` command's Localizer). Subscribes `scan`, `odom`, `initialpose`
 *  (geometry_msgs/PoseWithCovarianceStamped: starts again there); publishes
 *  `amcl_pose` (geometry_msgs/PoseWithCovarianceStamped, amcl's convention),
 *  `particlecloud` (geometry_msgs/PoseArray) and `map -> odom` on `tf`.
 *  Starts at `start`, in a room (`in_room`, else the `~in_room` parameter)
 *  or globally. */
struct LocalizeNodeOptions {
  std::string profile;
  std::vector<std::string> sets;
  std::string map, world;                    ///< the map (as navigate)
  std::optional<navigation::TPose2D> start;  ///< else a room, else a global start
  /** A room of the places file: particles over its free cells only (as
   *  `carenav localize --in-room`); empty: the `~in_room` parameter, if any. */
  std::string in_room;
  std::string places;      ///< places file for the room; empty: the one beside the map/world
  double duration = 0;     ///< s; 0: until stopped
  size_t cloud_max = 500;  ///< particles published at most
  std::string odom_frame = "odom", map_frame = "map";
  std::vector<std::string> ros_args;
  const std::atomic<bool>* stop = nullptr;
  bool quiet = false;
};
void runLocalizeNode(const LocalizeNodeOptions& o);

/** `carenav ros perceive`: carenav's perception pipeline (that of `carenav
 *  perceive` and of the navigation session) on a depth camera's frames.
 *  Subscribes `points` (sensor_msgs/PointCloud2 in the camera's body frame:
 *  x forward, y left, z up), `depth/image` + `depth/camera_info`
 *  (sensor_msgs/Image 16UC1 mm or 32FC1 m, and its CameraInfo) and, to
 *  move the local grid, `odom`; publishes `local_grid`
 *  (nav_msgs/OccupancyGrid, the robot-centred grid in the odometry frame)
 *  and `virtual_scan` (sensor_msgs/LaserScan, 360 degrees in the base frame:
 *  per bearing the first occupied cell of the grid, so stairs down, gutters
 *  and outlets are in it as well as obstacles). */
struct PerceiveNodeOptions {
  std::string profile;
  std::vector<std::string> sets;
  std::string method = "rrt-gpd";  ///< rrt-gpd | ransac | height-band (perception::Method)
  /** The depth camera ([sensor.LABEL]: its pose on the robot); empty: the
   *  profile's [perception] sensor, else its first depth camera. */
  std::string sensor;
  std::string sensor_pose;  ///< "x,y,z,yaw,pitch,roll" (m, deg) instead of the profile's
  double duration = 0;      ///< s; 0: until stopped
  std::string odom_frame = "odom", base_frame = "base_link";
  std::vector<std::string> ros_args;
  const std::atomic<bool>* stop = nullptr;
  bool quiet = false;
};
/** Runs until stopped or `duration`; returns the number of frames processed. */
size_t runPerceiveNode(const PerceiveNodeOptions& o);

/** `carenav ros slam`: a SLAM back end of `carenav slam` (slam::createMapper)
 *  fed live. Subscribes `scan` (sensor_msgs/LaserScan, the profile's first
 *  lidar2d, placed by its pose), `odom` (nav_msgs/Odometry; without any, the
 *  `odom -> base_link` transform of `tf`) and `~save` (std_msgs/Empty);
 *  publishes `map` (nav_msgs/OccupancyGrid, latched, every `map_every`
 *  scans inserted in the map) and `map -> odom` on `tf`. At the end and on
 *  each `~save` it writes the outputs of `carenav slam` to `out_dir`. */
struct SlamNodeOptions {
  std::string profile;
  std::vector<std::string> sets;
  std::string method;   ///< icp | icp-graph | rbpf; empty: the profile's [slam] method
  std::string out_dir;  ///< map.simplemap, map.gridmap.gz, map.yaml/.pgm, map.png, ...
  /** Scans inserted in the map (keyframes) between two `map` messages; 0:
   *  the `~map_every` parameter, else 5. */
  int map_every = 0;
  double duration = 0;  ///< s; 0: until stopped
  std::string odom_frame = "odom", base_frame = "base_link", map_frame = "map";
  std::vector<std::string> ros_args;
  const std::atomic<bool>* stop = nullptr;
  bool quiet = false;
};
/** Runs until stopped or `duration`, then writes the outputs; returns the
 *  number of scans mapped. Throws InputError when none was (nothing to write). */
size_t runSlamNode(const SlamNodeOptions& o);

/** ros::init with the node's name and ROS arguments (once per process);
 *  throws InputError when the master cannot be reached within `wait_s`. */
void initRosNode(const std::string& name, const std::vector<std::string>& ros_args,
                 double wait_s = 10);

/** The node's private parameters as profile overrides: `~navigation/v_max`
 *  -> "navigation.v_max=VALUE", `~sensor/laser/x` -> "sensor.laser.x=VALUE"
 *  (every '/' but the last becomes '.'; ROS names have no dots). Call after
 *  initRosNode; command-line --set values go after these and win. */
/** `node_keys`: the node's own parameters (e.g. `map_every`), not profile keys, left out. */
std::vector<std::string> privateParamOverrides(const std::vector<std::string>& node_keys = {});

/** "section.key=value" from a parameter's name below the node's namespace
 *  and its value as text (exposed for tests); "" for a name without a
 *  section. */
std::string overrideFromParam(const std::string& relative_name, const std::string& value);

}  // namespace carenav::ros
