// `carenav ros navigate`: the navigation session as a ROS node, a third
// adapter beside the simulator runner (scenario_run.cpp) and the TCP bridge
// (bridge_run.cpp): scans, odometry, goals and the user's intent in from
// topics, cmd_vel out every control period (nodes.h, docs/ros.md).
#include <carenav/common/errors.h>
#include <carenav/io/map_io.h>
#include <carenav/places/places.h>
#include <carenav/ros/nodes.h>
#include <carenav/runtime/bridge.h>
#include <carenav/runtime/live_run.h>
#include <carenav/runtime/session.h>
#include <carenav/sim/world.h>

#include "depth_topics.h"
#include "msg_convert.h"
#include "node_common.h"

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/Twist.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <std_msgs/String.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <cmath>
#include <memory>

namespace carenav::ros {

namespace {

using navigation::NavigationSession;
using navigation::SessionEnd;
using navigation::TPose2D;

mrpt::maps::COccupancyGridMap2D loadMap(const NavigateNodeOptions& o) {
  if (!o.world.empty()) return sim::loadWorld(o.world).grid();
  return io::loadGridMap(o.map);
}

/** A place or room of the map's places file (as `carenav navigate --goal
 *  NAME`); throws InputError for an unknown name or a bad places file. */
navigation::SessionGoal placeGoal(const NavigateNodeOptions& o,
                                  const mrpt::maps::COccupancyGridMap2D& grid,
                                  const std::string& name) {
  const std::string places = places::placesPathForMap(!o.world.empty() ? o.world : o.map);
  const places::Goal g = places::resolveGoal(places::readPlacesFile(places), grid, name);
  return {TPose2D{g.x, g.y, mrpt::DEG2RAD(g.heading_deg)},
          g.place.empty() ? g.room : g.room + "/" + g.place};
}

std::optional<TPose2D> goalFromText(const NavigateNodeOptions& o,
                                    const mrpt::maps::COccupancyGridMap2D& grid) {
  if (o.goal.empty()) return std::nullopt;
  if (auto g = navigation::parseGoalText(o.goal)) return g;
  return placeGoal(o, grid, o.goal).pose;
}

class NavigateNode {
 public:
  NavigateNode(const NavigateNodeOptions& o, NavigationSession& s) : o_(o), s_(s), pnh_("~") {
    for (const auto& sp : s.setup().sensors)
      if (sp.type == "lidar2d" && !lidar_) lidar_ = sp;
    if (lidar_) scan_ = nh_.subscribe("scan", 5, &NavigateNode::onScan, this);
    subscribeOthers();
    odom_ = nh_.subscribe("odom", 20, &NavigateNode::onOdom, this);
    goal_ = nh_.subscribe("move_base_simple/goal", 2, &NavigateNode::onGoal, this);
    place_ = pnh_.subscribe("goal_place", 2, &NavigateNode::onGoalPlace, this);
    if (s.walker()) intent_ = nh_.subscribe("intent", 5, &NavigateNode::onIntent, this);
    if (o.external_pose) amcl_ = nh_.subscribe("amcl_pose", 5, &NavigateNode::onPose, this);
    cmd_ = nh_.advertise<geometry_msgs::Twist>("cmd_vel", 5);
    path_ = nh_.advertise<nav_msgs::Path>("plan", 1, true);
    status_ = pnh_.advertise<std_msgs::String>("status", 5, true);
    if (s.setup().localise) {
      pose_ = pnh_.advertise<geometry_msgs::PoseStamped>("pose", 5);
      tf_ = nh_.advertise<tf2_msgs::TFMessage>("tf", 10);
    }
  }
  /** Runs the control loop; the reason it ended. */
  std::string run();
  bool reached() const { return reached_; }
  double elapsed() const { return (::ros::WallTime::now() - wall0_).toSec(); }

 private:
  /** A stamp on the node's clock (s since it started); messages without one: now. */
  double t(const ::ros::Time& stamp) const {
    return stamp.isZero() ? elapsed() : stamp.toSec() - t0_;
  }
  void onScan(const sensor_msgs::LaserScan& m);
  void subscribeOthers();
  void onOtherScan(const SensorParams& sp, const sensor_msgs::LaserScan& m);
  void onDepth(const mrpt::obs::CObservation3DRangeScan::Ptr& o, const ::ros::Time& stamp);
  void onOdom(const nav_msgs::Odometry& m);
  void onGoal(const geometry_msgs::PoseStamped& m);
  void onGoalPlace(const std_msgs::String& m);
  void acceptGoal(const navigation::SessionGoal& g);
  /** A localiser's pose (amcl_pose): the navigator's map pose from now on
   *  (it follows odometry from there). */
  void onPose(const geometry_msgs::PoseWithCovarianceStamped& m) {
    const auto& p = m.pose.pose;
    s_.navigator().setMapPose({p.position.x, p.position.y, yawOf(p.orientation)});
  }
  void onIntent(const geometry_msgs::Twist& m) {
    intent_cmd_ = navigation::Twist{m.linear.x, m.angular.z};
    intent_t_ = elapsed();
  }
  bool cycle();
  void say(const std::string& text);
  void publishPath();
  void publishPose();

  const NavigateNodeOptions& o_;
  NavigationSession& s_;
  ::ros::NodeHandle nh_, pnh_;
  ::ros::Subscriber scan_, odom_, goal_, place_, intent_, amcl_;
  std::vector<::ros::Subscriber> others_;             // scan_LABEL
  std::vector<std::unique_ptr<DepthTopics>> depths_;  // points[_LABEL], depth[_LABEL]/image
  ::ros::Publisher cmd_, path_, status_, pose_, tf_;
  std::optional<SensorParams> lidar_;
  const ::ros::WallTime wall0_ = ::ros::WallTime::now();
  const double t0_ = ::ros::Time::now().toSec();
  bool have_odom_ = false, reached_ = false, route_sent_ = false, scan_arrived_ = false;
  TPose2D odom_pose_;
  std::optional<navigation::Twist> intent_cmd_;
  double intent_t_ = 0;
  std::string last_status_;
};

void NavigateNode::onScan(const sensor_msgs::LaserScan& m) {
  if (!lidar_ || !have_odom_) return;  // no pose to place it at yet
  const auto& l = *lidar_;
  const mrpt::poses::CPose3D pose(l.x, l.y, l.z, mrpt::DEG2RAD(l.yaw), mrpt::DEG2RAD(l.pitch),
                                  mrpt::DEG2RAD(l.roll));
  s_.observation(scanFromRos(m, l.label, pose), odom_pose_, t(m.header.stamp));
  scan_arrived_ = true;
}

// Other lidars and range arrays on scan_LABEL (as the bridge's scan lines),
// the first depth camera on `points` or `depth/image` + `depth/camera_info`,
// others on points_LABEL or depth_LABEL/...
void NavigateNode::subscribeOthers() {
  bool points = false;
  for (const auto& sp : s_.setup().sensors) {
    if ((sp.type == "lidar2d" && (!lidar_ || sp.label != lidar_->label)) ||
        sp.type == "range-array") {
      others_.push_back(nh_.subscribe<sensor_msgs::LaserScan>(
          "scan_" + sp.label, 5,
          [this, sp](const sensor_msgs::LaserScan::ConstPtr& m) { onOtherScan(sp, *m); }));
    } else if (sp.type == "depth-camera") {
      const mrpt::poses::CPose3D pose(sp.x, sp.y, sp.z, mrpt::DEG2RAD(sp.yaw),
                                      mrpt::DEG2RAD(sp.pitch), mrpt::DEG2RAD(sp.roll));
      depths_.push_back(std::make_unique<DepthTopics>(
          nh_, points ? "points_" + sp.label : "points", points ? "depth_" + sp.label : "depth", 2,
          sp.label, pose,
          [this](const auto& obs, const ::ros::Time& stamp) { onDepth(obs, stamp); }));
      points = true;
    }
  }
}

void NavigateNode::onOtherScan(const SensorParams& sp, const sensor_msgs::LaserScan& m) {
  if (!have_odom_) return;
  navigation::BridgeMessage b;
  b.kind = navigation::BridgeMessage::Kind::Scan;
  b.t = t(m.header.stamp);
  b.label = sp.label;
  b.ranges = m.ranges;
  if (m.angle_increment < 0) std::reverse(b.ranges.begin(), b.ranges.end());
  s_.observation(navigation::bridgeObservation(b, sp), odom_pose_, b.t);
}

// A depth camera's frame (placed by the profile's pose) for perception.
void NavigateNode::onDepth(const mrpt::obs::CObservation3DRangeScan::Ptr& o,
                           const ::ros::Time& stamp) {
  if (have_odom_) s_.observation(o, odom_pose_, t(stamp));
}

void NavigateNode::onOdom(const nav_msgs::Odometry& m) {
  const auto& p = m.pose.pose;
  odom_pose_ = TPose2D{p.position.x, p.position.y, yawOf(p.orientation)};
  have_odom_ = true;
  s_.robotTime(m.header.stamp.toSec());
  s_.odometry(odom_pose_, {m.twist.twist.linear.x, m.twist.twist.angular.z}, t(m.header.stamp));
}

void NavigateNode::onGoal(const geometry_msgs::PoseStamped& m) {
  if (s_.walker()) return say("goal ignored: the walker follows its user");
  acceptGoal({{m.pose.position.x, m.pose.position.y, yawOf(m.pose.orientation)}, ""});
}

// A place name: resolved as `navigate --goal NAME`; an unknown one (or no
// map, no places file) is a warning and leaves the goal as it was.
void NavigateNode::onGoalPlace(const std_msgs::String& m) {
  if (s_.walker()) return say("goal ignored: the walker follows its user");
  if (!s_.setup().map) return say("warning: goal place '" + m.data + "': no map (--map, --world)");
  try {
    acceptGoal(placeGoal(o_, *s_.setup().map, m.data));
  } catch (const InputError& e) {
    say(std::string("warning: goal place '") + m.data + "': " + e.what() + "; goal unchanged");
  }
}

void NavigateNode::acceptGoal(const navigation::SessionGoal& g) {
  const TPose2D here = s_.navigator().mapPose();
  const bool ok = s_.setGoals({g}, false, 0, {here.x, here.y});
  route_sent_ = false;
  const std::string what = g.label.empty() ? "goal accepted" : "goal accepted: " + g.label;
  say(ok ? what : what + ", no route yet (replanning)");
}

void NavigateNode::say(const std::string& text) {
  if (text == last_status_) return;
  last_status_ = text;
  std_msgs::String m;
  m.data = text;
  status_.publish(m);
}

void NavigateNode::publishPath() {
  if (route_sent_ || !s_.hasRoute()) return;
  nav_msgs::Path p;
  p.header.frame_id = o_.map_frame;
  p.header.stamp = ::ros::Time::now();
  for (const auto& pt : s_.routePoints()) {
    geometry_msgs::PoseStamped ps;
    ps.header = p.header;
    ps.pose.position.x = pt.x;
    ps.pose.position.y = pt.y;
    ps.pose.orientation.w = 1;
    p.poses.push_back(ps);
  }
  path_.publish(p);
  route_sent_ = true;
}

// Where the localiser puts the robot: ~pose and map -> odom on tf.
void NavigateNode::publishPose() {
  if (!pose_ || !have_odom_) return;
  const TPose2D mp = s_.navigator().mapPose();
  const ::ros::Time now = ::ros::Time::now();
  geometry_msgs::PoseStamped p;
  p.header.stamp = now;
  p.header.frame_id = o_.map_frame;
  p.pose.position.x = mp.x;
  p.pose.position.y = mp.y;
  p.pose.orientation = yawQuaternion(mp.phi);
  pose_.publish(p);
  const mrpt::poses::CPose2D map_odom =
      mrpt::poses::CPose2D(mp) + (-mrpt::poses::CPose2D(odom_pose_));
  geometry_msgs::TransformStamped t;
  t.header = p.header;
  t.child_frame_id = o_.odom_frame;
  t.transform = transformOf(mrpt::poses::CPose3D(map_odom));
  tf2_msgs::TFMessage tf;
  tf.transforms.push_back(t);
  tf_.publish(tf);
}

// One control period: false when the run ends (goal reached, gave up).
bool NavigateNode::cycle() {
  const double now = elapsed();
  s_.beginWork();
  geometry_msgs::Twist cmd;  // zero unless the session commands otherwise
  if (s_.walker() && intent_cmd_) s_.userIntent(*intent_cmd_, intent_t_, now);
  if (!s_.walker() && !s_.goalMode()) {
    say("waiting for a goal");
    cmd_.publish(cmd);
    return true;
  }
  const auto st = s_.cycle(now);
  cmd.linear.x = st.cycle.decision.cmd.v;
  cmd.angular.z = st.cycle.decision.cmd.w;
  cmd_.publish(cmd);
  publishPath();
  publishPose();
  if (st.cycle.decision.action == navigation::SafetyAction::Stop &&
      !st.cycle.decision.reason.empty())
    say("stop: " + st.cycle.decision.reason);
  else
    say(s_.walker() ? "following the user" : "driving to the goal");
  if (st.end == SessionEnd::GoalReached) {
    reached_ = true;
    say("goal reached");
    return o_.stay;
  }
  if (st.end == SessionEnd::GaveUp) return say("gave up: " + s_.gaveUpNote()), false;
  return true;
}

// Cycles at the control rate (or on each scan), messages handled while
// waiting for the next; on every way out a last zero command.
std::string NavigateNode::run() {
  const double period = 1.0 / o_.control_rate;
  double next = elapsed();
  std::string why = "stopped";
  auto* queue = ::ros::getGlobalCallbackQueue();
  while (::ros::ok()) {
    if (o_.stop && o_.stop->load()) break;
    if (o_.duration > 0 && elapsed() >= o_.duration) {
      why = "duration over";
      break;
    }
    queue->callAvailable(::ros::WallDuration(std::max(0.0, next - elapsed())));
    const double now = elapsed();
    if (now < next && !(o_.cycle_on_scan && scan_arrived_)) continue;
    scan_arrived_ = false;
    if (!cycle()) {
      why = reached_ ? "goal reached" : "gave up: " + s_.gaveUpNote();
      break;
    }
    // The timer: the next period, never closer than 0.9 periods after a late
    // cycle (on scans: one period after the last cycle, a fallback).
    next = o_.cycle_on_scan ? now + period : std::max(next + period, now + 0.9 * period);
  }
  cmd_.publish(geometry_msgs::Twist());  // whatever ended the run, the robot stands
  say("ended: " + why);
  return why;
}

}  // namespace

navigation::RunMetrics runNavigateNode(const NavigateNodeOptions& o) {
  auto setup = startNode("carenav_navigate", o.profile, o.sets, o.plugin, o.ros_args);
  std::optional<mrpt::maps::COccupancyGridMap2D> grid;
  if (!o.map.empty() || !o.world.empty()) grid = loadMap(o);
  navigation::applyLiveRun(setup, o, "ros", !o.world.empty() ? o.world : o.map,
                           grid ? &*grid : nullptr, grid && o.start && !o.external_pose);
  NavigationSession session(setup);
  if (!session.walker() && (!grid || !o.start))
    throw InputError("plugin " + setup.nav.plugin +
                     " drives to goals on a map: give --map or --world, and --start");
  if (session.walker() && !o.goal.empty())
    throw InputError("--goal: plugin " + setup.nav.plugin + " follows its user; use a goal plugin");
  if (grid && o.start) session.navigator().setMapPose(*o.start);
  const auto goal = grid ? goalFromText(o, *grid) : std::nullopt;
  if (goal && !session.setGoals({{*goal, ""}}, false, 0, {o.start->x, o.start->y}))
    throw InputError(setup.origin + ": no route from the start to the goal");
  NavigateNode node(o, session);
  const std::string why = node.run();
  navigation::RunMetrics& m = navigation::finishLiveMetrics(session, node.elapsed());
  m.outcome = why;
  m.success = !session.goal() || node.reached();
  session.writeOutputs("carenav ros navigate");
  ::ros::shutdown();
  return m;
}

}  // namespace carenav::ros
