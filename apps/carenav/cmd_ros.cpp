// carenav ros sim|navigate|localize|perceive|slam ...: carenav as ROS 1 nodes (built with the ROS
// part only; docs/ros.md). ROS arguments (from:=to, _param:=value,
// __name:=node) follow the options.
#include "commands.h"

#include <carenav/common/errors.h>
#include <carenav/ros/nodes.h>

#include <atomic>
#include <csignal>
#include <iostream>

namespace carenav::app {

namespace {

std::atomic<bool> g_ros_stop{false};
void onRosSignal(int) { g_ros_stop = true; }

std::optional<navigation::TPose2D> poseOption(const std::string& s, const char* option) {
  if (s.empty()) return std::nullopt;
  if (const auto p = navigation::parsePoseText(s)) return p;
  throw InputError(std::string(option) + " '" + s + "': expected x,y,deg");
}

void stopOnSignals() {
  std::signal(SIGINT, onRosSignal);
  std::signal(SIGTERM, onRosSignal);
}

/** What every node command does before running its node: the ROS arguments
 *  CLI11 left over (remappings, _param:=value), the stop flag, Ctrl-C and
 *  SIGTERM. */
template <class Options>
void prepareNode(Options& o, CLI::App* cmd) {
  o.ros_args = cmd->remaining();
  o.stop = &g_ros_stop;
  stopOnSignals();
}

void addSim(CLI::App& ros, const GlobalOptions& g) {
  auto o = std::make_shared<ros::SimNodeOptions>();
  auto start = std::make_shared<std::string>();
  auto* cmd = ros.add_subcommand(
      "sim",
      "The simulator as a ROS robot, in real time: publishes scan, odom, tf, ground_truth, "
      "clock; takes cmd_vel. Ends on Ctrl-C / SIGTERM or --duration, then writes --summary.");
  cmd->add_option("--profile", o->profile, "Robot profile")->required();
  cmd->add_option("--set", o->sets, "Profile override section.key=value (repeatable)");
  cmd->add_option("--world", o->world, "Simulator world YAML");
  cmd->add_option("--scenario", o->scenario, "A scenario: its world and start");
  cmd->add_option("--start", *start, "Start pose x,y,deg on the world");
  cmd->add_option("--rate", o->rate, "Simulation steps per second")->capture_default_str();
  cmd->add_option("--duration", o->duration, "Seconds; 0: until stopped")->capture_default_str();
  cmd->add_option("--summary", o->summary, "JSON written at the end: truth pose, collisions");
  cmd->add_option("--record", o->record,
                  "Bag of what the node publishes (odom, scans, tf, ground_truth)");
  cmd->add_flag("--depth", o->depth_images,
                "Depth cameras publish depth images (depth/image 16UC1 mm + depth/camera_info) "
                "instead of point clouds");
  cmd->allow_extras();
  cmd->callback([o, start, cmd, &g] {
    if (!o->summary.empty()) prepareOutputFile(o->summary, "--summary");
    if (!o->record.empty()) prepareOutputFile(o->record, "--record");
    o->start = poseOption(*start, "--start");
    o->quiet = g.quiet;
    prepareNode(*o, cmd);
    ros::runSimNode(*o);
  });
}

void addNavigate(CLI::App& ros, const GlobalOptions& g) {
  auto o = std::make_shared<ros::NavigateNodeOptions>();
  auto start = std::make_shared<std::string>();
  auto* cmd = ros.add_subcommand(
      "navigate",
      "The navigation session as a ROS node: subscribes scan, odom, move_base_simple/goal "
      "(and intent for a walker); publishes cmd_vel every control period, plan and ~status. "
      "Stale scans or odometry (by their stamps) give zero velocity. Ends when the goal is "
      "reached (unless --stay), on Ctrl-C / SIGTERM or after --duration; writes --out.");
  cmd->add_option("--profile", o->profile, "Robot profile")->required();
  cmd->add_option("--set", o->sets, "Profile override section.key=value (repeatable)");
  cmd->add_option("--plugin", o->plugin, "Local planner (default: the profile's)");
  cmd->add_option("--map", o->map, "Static map (gridmap, ROS YAML, ...)");
  cmd->add_option("--world", o->world, "Or a simulator world's map");
  cmd->add_option("--start", *start, "Where the robot is on the map: x,y,deg");
  cmd->add_option("--goal", o->goal, "Goal x,y,deg or a place of the map's places file");
  cmd->add_option("--rate", o->control_rate, "Control rate (Hz)")->capture_default_str();
  cmd->add_option("--duration", o->duration, "Seconds; 0: until the goal is reached");
  cmd->add_flag("--stay", o->stay, "After a goal, wait for the next one");
  cmd->add_flag("--external-pose", o->external_pose,
                "Take the map pose from amcl_pose (carenav ros localize, amcl) instead of "
                "localising here");
  cmd->add_flag("--on-scan", o->cycle_on_scan,
                "Run the control cycle on each scan (the timer only as a fallback)");
  cmd->add_option("--out", o->out_dir, "Folder for run.png, navlog.csv, summary.json");
  cmd->allow_extras();
  cmd->callback([o, start, cmd, &g] {
    if (!o->out_dir.empty()) prepareOutputFolder(o->out_dir);
    o->start = poseOption(*start, "--start");
    o->progress = !g.quiet;
    prepareNode(*o, cmd);
    const auto m = ros::runNavigateNode(*o);
    if (!g.quiet) std::cerr << "carenav ros navigate: " << m.outcome << "\n";
    std::cout << m.toJson() << std::flush;
    if (!m.success) throw std::runtime_error("the goal was not reached: " + m.outcome);
  });
}

void addLocalize(CLI::App& ros, const GlobalOptions& g) {
  auto o = std::make_shared<ros::LocalizeNodeOptions>();
  auto start = std::make_shared<std::string>();
  auto* cmd = ros.add_subcommand(
      "localize",
      "Monte Carlo localisation on a known map as a ROS node: subscribes scan, odom, "
      "initialpose; publishes amcl_pose, particlecloud and map -> odom on tf. Starts at "
      "--start, in a room (--in-room) or globally.");
  cmd->add_option("--profile", o->profile, "Robot profile ([localization], its lidar2d)")
      ->required();
  cmd->add_option("--set", o->sets, "Profile override section.key=value (repeatable)");
  cmd->add_option("--map", o->map, "Static map (gridmap, ROS YAML, ...)");
  cmd->add_option("--world", o->world, "Or a simulator world's map");
  cmd->add_option("--start", *start, "Start pose x,y,deg (default: global, over the free cells)");
  cmd->add_option("--in-room", o->in_room,
                  "Start over the free cells of this room of the places file only (default: "
                  "the ~in_room parameter, else global)");
  cmd->add_option("--places", o->places,
                  "Places file for --in-room (default: the one beside --map / --world)");
  cmd->add_option("--duration", o->duration, "Seconds; 0: until stopped");
  cmd->allow_extras();
  cmd->callback([o, start, cmd, &g] {
    o->start = poseOption(*start, "--start");
    o->quiet = g.quiet;
    prepareNode(*o, cmd);
    ros::runLocalizeNode(*o);
  });
}

void addPerceive(CLI::App& ros, const GlobalOptions& g) {
  auto o = std::make_shared<ros::PerceiveNodeOptions>();
  auto* cmd = ros.add_subcommand(
      "perceive",
      "The perception pipeline as a ROS node: subscribes points (PointCloud2 in the camera's "
      "body frame) or depth/image + depth/camera_info, and odom; publishes local_grid "
      "(OccupancyGrid) and virtual_scan (LaserScan: obstacles, stairs down, gutters, outlets).");
  cmd->add_option("--profile", o->profile, "Robot profile ([perception], its depth camera)")
      ->required();
  cmd->add_option("--set", o->sets, "Profile override section.key=value (repeatable)");
  cmd->add_option("--method", o->method, "rrt-gpd (default), ransac or height-band");
  cmd->add_option("--sensor", o->sensor,
                  "The depth camera [sensor.LABEL] (default: the profile's)");
  cmd->add_option(
      "--sensor-pose", o->sensor_pose,
      "Camera pose on the robot x,y,z,yaw,pitch,roll (m, deg) instead of the profile's");
  cmd->add_option("--duration", o->duration, "Seconds; 0: until stopped");
  cmd->allow_extras();
  cmd->callback([o, cmd, &g] {
    o->quiet = g.quiet;
    prepareNode(*o, cmd);
    ros::runPerceiveNode(*o);
  });
}

void addSlam(CLI::App& ros, const GlobalOptions& g) {
  auto o = std::make_shared<ros::SlamNodeOptions>();
  auto* cmd = ros.add_subcommand(
      "slam",
      "A SLAM back end as a ROS node: subscribes scan, odom (or tf) and ~save; publishes map "
      "(latched, every --map-every scans inserted) and map -> odom on tf. Writes the outputs of "
      "carenav slam to --out on ~save and at the end (Ctrl-C / SIGTERM or --duration).");
  cmd->add_option("--profile", o->profile, "Robot profile ([slam], [icp], [rbpf], its lidar2d)")
      ->required();
  cmd->add_option("--set", o->sets, "Profile override section.key=value (repeatable)");
  cmd->add_option("--method", o->method, "icp | icp-graph | rbpf (default: the profile's)");
  cmd->add_option("--out", o->out_dir, "Output folder (created)")->required();
  cmd->add_option("--map-every", o->map_every,
                  "Scans inserted in the map between map messages (default: ~map_every, else 5)");
  cmd->add_option("--duration", o->duration, "Seconds; 0: until stopped");
  cmd->allow_extras();
  cmd->callback([o, cmd, &g] {
    prepareOutputFolder(o->out_dir);
    o->quiet = g.quiet;
    prepareNode(*o, cmd);
    ros::runSlamNode(*o);
  });
}

void addRosCommand(CLI::App& app, const GlobalOptions& g) {
  auto* cmd = app.add_subcommand("ros", "carenav as ROS 1 nodes (docs/ros.md)");
  cmd->require_subcommand(1);
  addSim(*cmd, g);
  addNavigate(*cmd, g);
  addLocalize(*cmd, g);
  addPerceive(*cmd, g);
  addSlam(*cmd, g);
}

}  // namespace

CARENAV_COMMAND(110, addRosCommand);

}  // namespace carenav::app
