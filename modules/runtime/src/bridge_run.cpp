// The TCP bridge adapter of the navigation session (bridge.h,
// docs/navigate.md): a real robot's lines in, its commands out, in real time.
#include <carenav/common/errors.h>
#include <carenav/common/text.h>
#include <carenav/io/map_io.h>
#include <carenav/places/places.h>
#include <carenav/runtime/bridge.h>
#include <carenav/runtime/line_socket.h>
#include <carenav/runtime/live_run.h>
#include <carenav/runtime/session.h>

#include <chrono>
#include <cmath>
#include <map>

namespace carenav::navigation {

namespace {

/** Goal navigation on the static map (a pose or a place of the map's
 *  places file), from --start; a walker follows its user instead. */
void setBridgeGoal(const BridgeOptions& o, NavigationSession& s,
                   const mrpt::maps::COccupancyGridMap2D* grid) {
  const std::string& plugin = s.setup().nav.plugin;
  if (o.goal.empty()) {
    if (!s.walker())
      throw InputError("plugin " + plugin + " drives to a goal: give --goal (with --map, --start)");
    return;
  }
  if (s.walker())
    throw InputError("--goal: plugin " + plugin + " follows its user; use a goal plugin");
  if (!grid || !o.start)
    throw InputError("--goal with --bridge needs --map and --start (where the robot is on it)");
  auto goal = parseGoalText(o.goal);
  if (!goal) {
    const places::Goal g =
        places::resolveGoal(places::readPlacesFile(places::placesPathForMap(o.map)), *grid, o.goal);
    goal = TPose2D{g.x, g.y, mrpt::DEG2RAD(g.heading_deg)};
  }
  if (!s.setGoals({{*goal, ""}}, false, 0, {o.start->x, o.start->y}))
    throw InputError(o.map + ": no route from the start to the goal");
}

LineSocket connectBridge(const BridgeOptions& o) {
  try {
    const auto hp = parseHostPort(o.address, "127.0.0.1");
    return connectTcp(hp.first, hp.second, o.connect_timeout);
  } catch (const std::exception& e) {
    throw InputError(std::string("--bridge: ") + e.what());
  }
}

/** The loop of a bridge run: input bounded per pass (at most two of the
 *  longest lines, the newest scan of each sensor), a cycle at the control
 *  rate, and on every way out a last `cmd T 0 0` and `stop REASON`. */
class BridgeLoop {
 public:
  BridgeLoop(const BridgeOptions& o, NavigationSession& s, LineSocket& sock)
      : o_(o), s_(s), sock_(sock), where_("bridge " + o.address) {
    for (const auto& sp : s.setup().sensors)
      if (sp.type == "lidar2d" || sp.type == "range-array") lidars_[sp.label] = sp;
  }
  void run();
  double elapsed() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count();
  }
  std::optional<InputError> error;
  std::string end_reason = "finished";
  bool goal_reached = false;

 private:
  struct PendingScan {
    BridgeMessage msg;
    TPose2D odom;  // the pose when it arrived
    double t = 0;
  };
  bool pass();  // false: the run ends
  bool take(const std::string& line);
  bool inputEnded(bool alive);
  bool cycle(double t);
  void fail(const std::string& what) { error = InputError(where_ + what); }

  const BridgeOptions& o_;
  NavigationSession& s_;
  LineSocket& sock_;
  const std::string where_;
  std::map<std::string, SensorParams> lidars_;
  std::map<std::string, std::optional<PendingScan>> pending_;
  const std::chrono::steady_clock::time_point wall0_ = std::chrono::steady_clock::now();
  double next_ = 0, robot_t_ = 0, last_heard_ = 0;
  size_t line_no_ = 0;
  bool have_odom_ = false, bye_ = false;
  TPose2D odom_;
  std::optional<IntentSample> bridge_user_;
};

void BridgeLoop::run() {
  while (pass()) {
  }
  // Whatever ended the run, the robot is told to stand still.
  sock_.sendLine(formatCommand(robot_t_, {0, 0}));
  sock_.sendLine("stop " + (error ? std::string("error") : end_reason));
  sock_.close();
}

bool BridgeLoop::pass() {
  const double now = elapsed();
  if (o_.stop && o_.stop->load()) return end_reason = "interrupted", false;
  if (o_.duration > 0 && now >= o_.duration) return end_reason = "duration over", false;
  if (o_.intent && o_.intent->finished(now)) return end_reason = "intent source finished", false;
  std::vector<std::string> lines;
  bool alive = true;
  try {
    alive = sock_.readLines(lines, std::max(0, static_cast<int>((next_ - now) * 1000)),
                            2 * sock_.max_line);
  } catch (const std::exception& e) {
    return fail(std::string(": ") + e.what()), false;
  }
  if (!lines.empty()) last_heard_ = elapsed();
  for (const auto& l : lines)
    if (!take(l) || bye_) break;
  if (error) return false;
  for (auto& [label, ps] : pending_)
    if (ps) {
      s_.observation(bridgeObservation(ps->msg, lidars_.at(label)), ps->odom, ps->t);
      ps.reset();
    }
  if (inputEnded(alive)) return false;
  const double t = elapsed();
  if (t < next_) return true;
  // Cycles at the rate, and never closer than 0.9 periods after a late one
  // (so that sensor_timeout / period bounds the cycles on old data).
  const double dt = 1.0 / o_.control_rate;
  next_ = std::max(next_ + dt, t + 0.9 * dt);
  return cycle(t);
}

// One line from the robot; false on a malformed one (the run ends).
bool BridgeLoop::take(const std::string& line) {
  ++line_no_;
  const std::string at = " line " + std::to_string(line_no_) + ": ";
  std::optional<BridgeMessage> msg;
  try {
    msg = parseBridgeLine(line);
  } catch (const std::invalid_argument& e) {
    return fail(at + e.what()), false;
  }
  if (!msg) return true;
  const double tn = elapsed();
  if (msg->kind == BridgeMessage::Kind::Bye) return bye_ = true;
  robot_t_ = std::max(robot_t_, msg->t);
  s_.robotTime(robot_t_);
  if (msg->kind == BridgeMessage::Kind::Odom) {
    odom_ = msg->pose;
    have_odom_ = true;
    s_.odometry(odom_, msg->vel, tn);
  } else if (msg->kind == BridgeMessage::Kind::Intent) {
    bridge_user_ = IntentSample{msg->vel, tn};
  } else if (lidars_.count(msg->label) == 0) {
    const std::string label = printableText(msg->label, 64);
    return fail(at + "scan from '" + label + "', which " + o_.profile + " has no [sensor." + label +
                "] lidar2d or range-array for"),
           false;
  } else if (have_odom_) {  // else no pose to place it at yet
    // Only the newest scan of each sensor in this pass is used: an older one
    // is superseded (and the work per cycle stays bounded).
    const std::string label = msg->label;  // (the message is moved below)
    pending_[label] = PendingScan{std::move(*msg), odom_, tn};
  }
  return true;
}

bool BridgeLoop::inputEnded(bool alive) {
  if (bye_) return end_reason = "robot said bye", true;
  if (!alive) {
    const std::string part = sock_.pendingPartial();
    fail(std::string(": the robot closed the connection without 'bye'") +
         (sock_.resetByPeer() ? " (reset: nothing more can be sent to it)" : "") +
         (part.empty() ? std::string()
                       : " (its last line was cut: '" + printableText(part, 60) + "')"));
    return true;
  }
  if (o_.silence_timeout > 0 && elapsed() - last_heard_ > o_.silence_timeout) {
    fail(": the robot sent nothing for " + formatFixed(o_.silence_timeout, 1) +
         " s (--silence-timeout)");
    return true;
  }
  return false;
}

bool BridgeLoop::cycle(double t) {
  s_.beginWork();
  if (s_.walker()) {
    std::optional<IntentSample> u = bridge_user_;
    if (o_.intent) {
      try {
        u = o_.intent->poll(t);
      } catch (const InputError& e) {
        error = e;
        return false;
      }
    }
    if (u) s_.userIntent(u->cmd, u->t, t);
  }
  const auto st = s_.cycle(t);
  // A robot that does not take its command within a period is not
  // listening: the run ends (it must stop by itself without commands).
  const int period_ms = std::max(1, static_cast<int>(1000 / o_.control_rate));
  if (!sock_.sendLine(formatCommand(robot_t_, st.cycle.decision.cmd), period_ms))
    return fail(sock_.open() ? ": the robot does not read its commands"
                             : ": the robot closed the connection without 'bye'"),
           false;
  if (st.end == SessionEnd::GoalReached) {
    goal_reached = true;
    end_reason = "goal reached";
    return false;
  }
  if (st.end == SessionEnd::GaveUp) return end_reason = "gave up: " + s_.gaveUpNote(), false;
  return true;
}

}  // namespace

RunMetrics runBridge(const BridgeOptions& o) {
  SessionSetup setup = sessionSetup(o.profile, o.sets, o.plugin);
  const auto info = setup.profile.section<ProfileInfo>("profile");
  std::optional<mrpt::maps::COccupancyGridMap2D> grid;
  if (!o.map.empty()) grid = io::loadGridMap(o.map);
  // Localised from the first lidar2d.
  applyLiveRun(setup, o, "bridge", o.map, grid ? &*grid : nullptr, grid && o.start);
  NavigationSession session(setup);
  setBridgeGoal(o, session, setup.map);
  if (grid && o.start) {
    bool lidar = false;
    for (const auto& s : setup.sensors) lidar = lidar || s.type == "lidar2d";
    if (!lidar) throw InputError(o.profile + ": --map needs a lidar2d sensor to localise on it");
    session.navigator().setMapPose(*o.start);
  }
  LineSocket sock = connectBridge(o);
  sock.sendLine("hello carenav 1 " + (info.name.empty() ? "robot" : info.name) + " " +
                setup.nav.plugin);
  BridgeLoop loop(o, session, sock);
  loop.run();
  RunMetrics& m = finishLiveMetrics(session, loop.elapsed());
  m.outcome = loop.error ? std::string(loop.error->what()) : loop.end_reason;
  m.success = !loop.error && (!session.goal() || loop.goal_reached);
  session.writeOutputs("carenav navigate --bridge " + o.address);
  if (loop.error) m.failWith(*loop.error);
  return m;
}

}  // namespace carenav::navigation
