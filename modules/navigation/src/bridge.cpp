// The robot bridge (see bridge.h and docs/navigate.md).
#include <carenav/common/errors.h>
#include <carenav/common/profile.h>
#include <carenav/io/map_io.h>
#include <carenav/io/map_render.h>
#include <carenav/localization/localizer.h>
#include <carenav/navigation/bridge.h>
#include <carenav/navigation/global_planner.h>
#include <carenav/navigation/line_socket.h>
#include <carenav/navigation/mrpt_ptg.h>
#include <carenav/navigation/navigator.h>
#include <carenav/places/places.h>

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservationRange.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/poses/CPose3D.h>

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

namespace carenav::navigation {

namespace fs = std::filesystem;

namespace {

double number(const std::string& s, const char* what, bool allow_nonfinite = false) {
  char* end = nullptr;
  errno = 0;
  const double d = std::strtod(s.c_str(), &end);
  if (s.empty() || end != s.c_str() + s.size() || errno == ERANGE ||
      (!allow_nonfinite && !std::isfinite(d)))
    throw std::invalid_argument(std::string(what) + " '" + printableText(s, 40) +
                                "' is not a finite number");
  return d;
}

std::string fmt(double v, int prec = 3) {
  char b[48];
  std::snprintf(b, sizeof b, "%.*f", prec, v);
  return b;
}

/** A finite number within +-limit (`unit` for the message): odometry of
 *  1e300 m is refused here, naming the bridge line, instead of overflowing
 *  the picture and the path length downstream. */
double bounded(const std::string& s, const char* what, double limit, const char* unit) {
  const double d = number(s, what);
  if (std::abs(d) > limit)
    throw std::invalid_argument(std::string(what) + " '" + printableText(s, 40) + "' is beyond +-" +
                                fmt(limit, 0) + " " + unit + " (not a plausible value)");
  return d;
}

}  // namespace

std::optional<BridgeMessage> parseBridgeLine(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> tok;
  for (std::string t; in >> t;) tok.push_back(t);
  if (tok.empty() || tok[0][0] == '#') return std::nullopt;
  BridgeMessage m;
  const std::string& k = tok[0];
  auto need = [&](size_t n, const char* form) {
    if (tok.size() != n)
      throw std::invalid_argument("'" + k + "' with " + std::to_string(tok.size() - 1) +
                                  " fields, expected '" + form + "'");
  };
  if (k == "odom") {
    need(7, "odom T X Y YAW V W");
    m.kind = BridgeMessage::Kind::Odom;
    m.t = bounded(tok[1], "time", kBridgeMaxTime, "s");
    m.pose = {bounded(tok[2], "x", kBridgeMaxCoordinate, "m"),
              bounded(tok[3], "y", kBridgeMaxCoordinate, "m"),
              bounded(tok[4], "yaw", kBridgeMaxYaw, "rad")};
    m.vel = {bounded(tok[5], "v", kBridgeMaxSpeed, "m/s"),
             bounded(tok[6], "w", kBridgeMaxSpeed, "rad/s")};
  } else if (k == "scan") {
    if (tok.size() < 4)
      throw std::invalid_argument("'scan' too short, expected 'scan T LABEL N R1 .. RN'");
    m.kind = BridgeMessage::Kind::Scan;
    m.t = bounded(tok[1], "time", kBridgeMaxTime, "s");
    m.label = tok[2];
    if (m.label.size() > 64) throw std::invalid_argument("scan label longer than 64 bytes");
    const double n = number(tok[3], "N");
    if (n < 1 || n > 100000 || n != std::floor(n))
      throw std::invalid_argument("N '" + printableText(tok[3], 40) +
                                  "' is not a count of ranges (1..100000)");
    const size_t count = static_cast<size_t>(n);
    if (tok.size() - 4 != count)
      throw std::invalid_argument("scan says " + std::to_string(count) + " ranges, has " +
                                  std::to_string(tok.size() - 4) +
                                  (tok.size() - 4 < count ? " (truncated?)" : ""));
    m.ranges.reserve(count);
    for (size_t i = 0; i < count; ++i) {
      const double r = number(tok[4 + i], "range", true);
      if (r < 0)
        throw std::invalid_argument("range '" + printableText(tok[4 + i], 40) + "' is negative");
      m.ranges.push_back(static_cast<float>(r));
    }
  } else if (k == "intent") {
    need(4, "intent T V W");
    m.kind = BridgeMessage::Kind::Intent;
    m.t = bounded(tok[1], "time", kBridgeMaxTime, "s");
    m.vel = {bounded(tok[2], "v", kBridgeMaxSpeed, "m/s"),
             bounded(tok[3], "w", kBridgeMaxSpeed, "rad/s")};
  } else if (k == "bye") {
    need(1, "bye");
    m.kind = BridgeMessage::Kind::Bye;
  } else {
    throw std::invalid_argument("unknown message '" + printableText(k, 40) +
                                "' (expected odom, scan, intent or bye)");
  }
  return m;
}

std::string formatCommand(double t, const Twist& c) {
  return "cmd " + fmt(t) + " " + fmt(c.v, 4) + " " + fmt(c.w, 4);
}

std::vector<float> reduceRanges(const std::vector<float>& ranges, size_t n,
                                const std::function<bool(float)>& valid) {
  if (n == 0 || ranges.size() <= n) return ranges;
  std::vector<float> out(n, 0.0f);
  for (size_t b = 0; b < n; ++b) {
    const size_t i0 = b * ranges.size() / n, i1 = (b + 1) * ranges.size() / n;
    float best = std::numeric_limits<float>::infinity();
    for (size_t i = i0; i < i1; ++i)
      if (valid(ranges[i]) && ranges[i] < best) best = ranges[i];
    if (std::isfinite(best)) out[b] = best;  // else 0: no return
  }
  return out;
}

RunMetrics runBridge(const BridgeOptions& o) {
  Profile prof = Profile::load(o.profile);
  prof.applyOverrides(o.sets);
  prof.validate();
  configureMrptPtg(prof);  // [nav.mrpt_ptg] for the mrpt-ptg plugin
  const auto robot = prof.section<RobotParams>("robot");
  const auto sensors = loadSensors(prof);
  auto nav = prof.section<NavigationParams>("navigation");
  if (!o.plugin.empty()) nav.plugin = o.plugin;
  const auto info = prof.section<ProfileInfo>("profile");
  std::map<std::string, SensorParams> lidars;
  for (const auto& s : sensors)
    if (s.type == "lidar2d" || s.type == "range-array") lidars[s.label] = s;

  Navigator navigator(nav, robot);
  const bool walker = navigator.planner().needsUserIntent();

  // Goal navigation on a static map, localised from the first lidar.
  std::optional<mrpt::maps::COccupancyGridMap2D> grid;
  std::optional<TPose2D> goal;
  std::optional<Route> route;
  RouteReplanner replanner(o.control_rate);
  std::unique_ptr<localization::Localizer> loc;
  std::string loc_sensor;
  for (const auto& [label, s] : lidars)
    if (s.type == "lidar2d" && loc_sensor.empty()) loc_sensor = label;
  const Footprint fp(robot.footprint, nav.resolution);
  if (!o.map.empty()) grid = io::loadGridMap(o.map);
  if (!o.goal.empty()) {
    if (walker)
      throw InputError("--goal: plugin " + nav.plugin + " follows its user; use a goal plugin");
    if (!grid || !o.start)
      throw InputError("--goal with --bridge needs --map and --start (where the robot is on it)");
    goal = parsePoseText(o.goal);
    if (!goal) {
      const places::Goal g = places::resolveGoal(
          places::readPlacesFile(places::placesPathForMap(o.map)), *grid, o.goal);
      goal = TPose2D{g.x, g.y, mrpt::DEG2RAD(g.heading_deg)};
    }
    GlobalPlanner gp(*grid, fp.inscribed, nav);
    route = gp.plan({o.start->x, o.start->y}, {goal->x, goal->y});
    if (!route) throw InputError(o.map + ": no route from the start to the goal");
  } else if (!walker) {
    throw InputError("plugin " + nav.plugin +
                     " drives to a goal: give --goal (with --map, --start)");
  }
  if (grid && o.start) {
    if (loc_sensor.empty())
      throw InputError(o.profile + ": --map needs a lidar2d sensor to localise on it");
    loc = std::make_unique<localization::Localizer>(
        *grid, prof.section<localization::LocalizationParams>("localization"));
    loc->initPose(mrpt::poses::CPose2D(o.start->x, o.start->y, o.start->phi), 0.1, 0.1,
                  mrpt::DEG2RAD(3.0));
    navigator.setMapPose(*o.start);
  }
  auto routeFrom = [&](const TPoint2D& from) {
    std::vector<TPoint2D> pts{from};
    pts.insert(pts.end(), route->waypoints.begin(), route->waypoints.end());
    return pts;
  };
  if (route) navigator.setRoute(routeFrom({o.start->x, o.start->y}), *goal);

  std::pair<std::string, int> hp;
  try {
    hp = parseHostPort(o.address, "127.0.0.1");
  } catch (const std::exception& e) {
    throw InputError(std::string("--bridge: ") + e.what());
  }
  LineSocket sock;
  try {
    sock = connectTcp(hp.first, hp.second, o.connect_timeout);
  } catch (const std::exception& e) {
    throw InputError(std::string("--bridge: ") + e.what());
  }
  const std::string where = "bridge " + o.address;
  sock.sendLine("hello carenav 1 " + (info.name.empty() ? "robot" : info.name) + " " + nav.plugin);

  RunMetrics m;
  m.scenario = "bridge";
  m.plugin = nav.plugin;
  std::ofstream log;
  if (!o.out_dir.empty()) {
    fs::create_directories(o.out_dir);
    log.open(fs::path(o.out_dir) / "navlog.csv");
    log << "t,robot_t,odom_x,odom_y,odom_yaw,est_x,est_y,est_yaw,user_v,user_w,plan_v,plan_w,"
           "cmd_v,cmd_w,action,reason,clearance_m,obstacle_cells,planner_note\n";
  }
  const auto wall0 = std::chrono::steady_clock::now();
  auto now = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  };
  const bool tty = o.progress && isatty(fileno(stderr));
  const double dt = 1.0 / o.control_rate;
  double next = 0, robot_t = 0, clear_sum = 0, fid_sum = 0, cycle_ms_sum = 0;
  size_t fid_n = 0, line_no = 0, k = 0;
  bool bye = false, have_odom = false, loc_started = false, goal_reached = false;
  TPose2D odom;
  mrpt::poses::CPose2D last_loc_odo;
  std::optional<Twist> bridge_user;
  std::optional<double> bridge_user_t;
  std::optional<InputError> error;
  std::vector<TPoint2D> path;
  m.min_clearance_m = std::numeric_limits<double>::infinity();
  std::string end_reason = "finished";

  struct PendingScan {
    BridgeMessage msg;
    TPose2D odom;  // the pose when it arrived
    double t = 0;
  };
  std::map<std::string, std::optional<PendingScan>> pending;
  size_t superseded = 0, reduced = 0;
  auto integrate = [&](PendingScan& ps) {
    const SensorParams& s = lidars.at(ps.msg.label);
    const double tn = ps.t;
    const TPose2D& at = ps.odom;
    if (s.type == "range-array") {
      const auto valid = [&](float r) { return std::isfinite(r) && r > 0 && r < s.range_max; };
      const size_t cap = static_cast<size_t>(std::max(1, s.segments));
      if (ps.msg.ranges.size() > cap) ++reduced;
      const std::vector<float> ranges = reduceRanges(ps.msg.ranges, cap, valid);
      // Segments spread evenly over the fov, each a cone (the Leddar).
      mrpt::obs::CObservationRange ra;
      ra.sensorLabel = s.label;
      ra.minSensorDistance = static_cast<float>(s.range_min);
      ra.maxSensorDistance = static_cast<float>(s.range_max);
      const double seg = mrpt::DEG2RAD(s.fov) / static_cast<double>(ranges.size());
      ra.sensorConeApperture = static_cast<float>(seg);
      for (size_t i = 0; i < ranges.size(); ++i) {
        const float r = ranges[i];
        mrpt::obs::CObservationRange::TMeasurement me;
        me.sensorID = static_cast<uint16_t>(i);
        me.sensorPose = mrpt::math::TPose3D(
            s.x, s.y, s.z, mrpt::DEG2RAD(s.yaw - s.fov / 2) + (static_cast<double>(i) + 0.5) * seg,
            mrpt::DEG2RAD(s.pitch), mrpt::DEG2RAD(s.roll));
        me.sensedDistance = valid(r) ? r : static_cast<float>(s.range_max);
        ra.sensedData.push_back(me);
      }
      navigator.addObservation(ra, at, tn);
      return;
    }
    const auto valid = [&](float r) {
      return std::isfinite(r) && r >= s.range_min && r < s.range_max;
    };
    const size_t cap = static_cast<size_t>(std::max(1, s.beams));
    if (ps.msg.ranges.size() > cap) ++reduced;
    const std::vector<float> ranges = reduceRanges(ps.msg.ranges, cap, valid);
    auto scan = std::make_shared<mrpt::obs::CObservation2DRangeScan>();
    scan->sensorLabel = s.label;
    scan->aperture = static_cast<float>(mrpt::DEG2RAD(s.fov));
    scan->rightToLeft = true;
    scan->maxRange = static_cast<float>(s.range_max);
    scan->sensorPose = mrpt::poses::CPose3D(s.x, s.y, s.z, mrpt::DEG2RAD(s.yaw),
                                            mrpt::DEG2RAD(s.pitch), mrpt::DEG2RAD(s.roll));
    scan->resizeScan(ranges.size());
    for (size_t i = 0; i < ranges.size(); ++i) {
      const float r = ranges[i];
      scan->setScanRange(i, valid(r) ? r : static_cast<float>(s.range_max));
      scan->setScanRangeValidity(i, valid(r));
    }
    navigator.addObservation(*scan, at, tn);
    if (loc && s.label == loc_sensor) {
      const mrpt::poses::CPose2D now_odo(at.x, at.y, at.phi);
      const mrpt::poses::CPose2D inc =
          loc_started ? now_odo - last_loc_odo : mrpt::poses::CPose2D();
      last_loc_odo = now_odo;
      loc_started = true;
      loc->step(inc, scan, tn);
      const auto p = loc->pose();
      navigator.setMapPose({p.x(), p.y(), p.phi()});
      // HOBBIT: localisation may ask for a turn in place to relocalise.
      navigator.setRotateRequest(loc->needsRotateInPlace());
    }
  };
  // Input taken per pass of the loop: at most two of the longest lines, so
  // a robot that floods the socket cannot hold the control loop.
  const size_t max_read = 2 * sock.max_line;
  double last_heard = 0;

  while (true) {
    if (o.stop && o.stop->load()) {
      end_reason = "interrupted";
      break;
    }
    if (o.duration > 0 && now() >= o.duration) {
      end_reason = "duration over";
      break;
    }
    if (o.intent && o.intent->finished(now())) {
      end_reason = "intent source finished";
      break;
    }
    std::vector<std::string> lines;
    bool alive = true;
    try {
      alive = sock.readLines(lines, std::max(0, static_cast<int>((next - now()) * 1000)), max_read);
    } catch (const std::exception& e) {
      error = InputError(where + ": " + e.what());
      break;
    }
    if (!lines.empty()) last_heard = now();
    for (const auto& l : lines) {
      ++line_no;
      std::optional<BridgeMessage> msg;
      try {
        msg = parseBridgeLine(l);
      } catch (const std::invalid_argument& e) {
        error = InputError(where + " line " + std::to_string(line_no) + ": " + e.what());
        break;
      }
      if (!msg) continue;
      const double tn = now();
      switch (msg->kind) {
        case BridgeMessage::Kind::Odom:
          robot_t = std::max(robot_t, msg->t);
          odom = msg->pose;
          have_odom = true;
          navigator.setOdometry(odom, msg->vel, tn);
          break;
        case BridgeMessage::Kind::Scan: {
          robot_t = std::max(robot_t, msg->t);
          if (lidars.find(msg->label) == lidars.end()) {
            error = InputError(where + " line " + std::to_string(line_no) + ": scan from '" +
                               printableText(msg->label, 64) + "', which " + o.profile +
                               " has no [sensor." + printableText(msg->label, 64) +
                               "] lidar2d or range-array for");
            break;
          }
          if (!have_odom) break;  // no pose to place it at yet
          // Only the newest scan of each sensor in this batch is used: an
          // older one is superseded (and the work per cycle stays bounded).
          auto& slot = pending[msg->label];
          superseded += slot.has_value();
          slot = PendingScan{std::move(*msg), odom, tn};
          break;
        }
        case BridgeMessage::Kind::Intent:
          robot_t = std::max(robot_t, msg->t);
          bridge_user = msg->vel;
          bridge_user_t = tn;
          break;
        case BridgeMessage::Kind::Bye:
          bye = true;
          break;
      }
      if (error || bye) break;
    }
    if (error) break;
    for (auto& [label, ps] : pending)
      if (ps) {
        integrate(*ps);
        ps.reset();
      }
    if (bye) {
      end_reason = "robot said bye";
      break;
    }
    if (!alive) {
      const std::string part = sock.pendingPartial();
      error = InputError(
          where + ": the robot closed the connection without 'bye'" +
          (sock.resetByPeer() ? std::string(" (reset: nothing more can be sent to it)")
                              : std::string()) +
          (part.empty() ? std::string()
                        : " (its last line was cut: '" + printableText(part, 60) + "')"));
      break;
    }
    const double t = now();
    if (o.silence_timeout > 0 && t - last_heard > o.silence_timeout) {
      error = InputError(where + ": the robot sent nothing for " + fmt(o.silence_timeout, 1) +
                         " s (--silence-timeout)");
      break;
    }
    if (t < next) continue;
    // Cycles at the rate, and never closer than 0.9 periods after a late
    // one (so that sensor_timeout / period bounds the cycles on old data).
    next = std::max(next + dt, t + 0.9 * dt);

    // One control cycle.
    std::optional<Twist> user;
    if (walker) {
      std::optional<IntentSample> s;
      if (o.intent) {
        try {
          s = o.intent->poll(t);
        } catch (const InputError& e) {
          error = e;
          break;
        }
      } else if (bridge_user) {
        s = IntentSample{*bridge_user, *bridge_user_t};
      }
      if (s) {
        navigator.setUserIntent(s->cmd, s->t);
        if (t - s->t <= nav.intent_timeout) user = s->cmd;
      }
    }
    const auto c0 = std::chrono::steady_clock::now();
    const Navigator::Cycle cyc = navigator.cycle(t);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - c0).count();
    // A robot that does not take its command within a period is not
    // listening: the run ends (it must stop by itself without commands).
    if (!sock.sendLine(formatCommand(robot_t, cyc.decision.cmd),
                       std::max(1, static_cast<int>(dt * 1000)))) {
      error = InputError(where + (sock.open() ? ": the robot does not read its commands"
                                              : ": the robot closed the connection without 'bye'"));
      break;
    }
    cycle_ms_sum += ms;
    m.cycle_ms_max = std::max(m.cycle_ms_max, ms);
    ++m.cycles;
    m.stops += cyc.decision.action == SafetyAction::Stop;
    m.slowed += cyc.decision.action == SafetyAction::Slow;
    if (have_odom) {
      const TPose2D mp = navigator.mapPose();
      if (!path.empty()) m.path_length_m += std::hypot(mp.x - path.back().x, mp.y - path.back().y);
      path.push_back({mp.x, mp.y});
      m.min_clearance_m = std::min(m.min_clearance_m, cyc.clearance);
      clear_sum += cyc.clearance;
    }
    if (walker && user)
      if (const auto d = navigator.intentDeviation(*user, cyc.decision.cmd)) {
        fid_sum += *d;
        ++fid_n;
      }
    if (log.is_open()) {
      const TPose2D est = navigator.mapPose();
      log << fmt(t) << "," << fmt(robot_t) << "," << fmt(odom.x) << "," << fmt(odom.y) << ","
          << fmt(odom.phi, 4) << "," << fmt(est.x) << "," << fmt(est.y) << "," << fmt(est.phi, 4)
          << "," << (user ? fmt(user->v) : "") << "," << (user ? fmt(user->w) : "") << ","
          << fmt(cyc.plan.cmd.v) << "," << fmt(cyc.plan.cmd.w, 4) << "," << fmt(cyc.decision.cmd.v)
          << "," << fmt(cyc.decision.cmd.w, 4) << "," << safetyActionName(cyc.decision.action)
          << ",\"" << cyc.decision.reason << "\"," << fmt(cyc.clearance) << "," << cyc.obstacles
          << ",\"" << cyc.plan.note << "\"\n";
    }
    if (tty && k % 2 == 0) {
      std::cerr << "\r[navigate] bridge t " << fmt(t, 1) << " s";
      if (user) std::cerr << ", user " << fmt(user->v, 2) << " " << fmt(user->w, 2);
      std::cerr << ", cmd " << fmt(cyc.decision.cmd.v, 2) << " " << fmt(cyc.decision.cmd.w, 2)
                << " " << safetyActionName(cyc.decision.action) << " " << cyc.decision.reason
                << ", clearance " << fmt(cyc.clearance, 2) << " m     " << std::flush;
    }
    if (goal && cyc.goal_reached) {
      goal_reached = true;
      end_reason = "goal reached";
      break;
    }
    if (goal && grid && replanner.due(k, !navigator.predicted().empty())) {
      const TPose2D mp = navigator.mapPose();
      if (auto r2 = replanner.step(!navigator.predicted().empty(), *grid,
                                   navigator.obstaclesInMap(), {mp.x, mp.y}, {goal->x, goal->y},
                                   route, fp.inscribed, fp.circumscribed + 0.2, nav)) {
        route = r2;
        navigator.setRoute(routeFrom({mp.x, mp.y}), *goal);
      }
    }
    ++k;
  }
  if (tty) std::cerr << "\n";
  // Whatever ended the run, the robot is told to stand still.
  sock.sendLine(formatCommand(robot_t, {0, 0}));
  sock.sendLine("stop " + (error ? std::string("error") : end_reason));
  sock.close();

  m.wall_seconds = now();
  m.duration_s = m.wall_seconds;
  m.mean_speed_mps = m.duration_s > 0 ? m.path_length_m / m.duration_s : 0;
  m.mean_clearance_m = path.empty() ? 0 : clear_sum / static_cast<double>(path.size());
  if (!std::isfinite(m.min_clearance_m)) m.min_clearance_m = 0;
  m.cycle_ms_mean = m.cycles ? cycle_ms_sum / m.cycles : 0;
  m.intent_fidelity = fid_n ? fid_sum / fid_n : std::numeric_limits<double>::quiet_NaN();
  if (goal) {
    const TPose2D mp = navigator.mapPose();
    m.final_goal_error_m = std::hypot(mp.x - goal->x, mp.y - goal->y);
  }
  m.outcome = error ? std::string(error->what()) : end_reason;
  m.success = !error && (!goal || goal_reached);

  if (!o.out_dir.empty()) {
    io::RenderOptions ro;
    ro.title = "carenav navigate --bridge " + o.address + " (" + nav.plugin +
               "): robot red, obstacles orange, " + m.outcome;
    io::Overlay obs;
    obs.points = navigator.obstaclesInMap();
    obs.colour = {255, 140, 0};
    obs.points_only = true;
    io::Overlay tr;
    tr.points = path;
    tr.colour = {220, 30, 30};
    tr.start_end_markers = true;
    if (route) {
      io::Overlay r;
      r.points = routeFrom({o.start->x, o.start->y});
      r.colour = {40, 80, 220};
      ro.overlays.push_back(r);
    }
    ro.overlays.push_back(obs);
    ro.overlays.push_back(tr);
    const std::string png = (fs::path(o.out_dir) / "run.png").string();
    if (grid) {
      io::renderGridMapPng(*grid, png, ro);
    } else {
      // No map: an unknown canvas around what the robot drove and saw.
      double x0 = -1, y0 = -1, x1 = 1, y1 = 1;
      for (const auto* v : {&path, &obs.points})
        for (const auto& p : *v) {
          x0 = std::min(x0, p.x - 1);
          y0 = std::min(y0, p.y - 1);
          x1 = std::max(x1, p.x + 1);
          y1 = std::max(y1, p.y + 1);
        }
      // 5 cm cells, coarser when what was driven is larger than 200 m, so
      // the canvas stays about 4000 cells a side at most.
      const double res = std::max(0.05, std::max(x1 - x0, y1 - y0) / 4000);
      const auto canvas = io::makeGrid(x0, y0, res, static_cast<size_t>((x1 - x0) / res) + 1,
                                       static_cast<size_t>((y1 - y0) / res) + 1, 0.5f);
      io::renderGridMapPng(canvas, png, ro);
    }
    m.writeSummary(o.out_dir, png);
  }
  if (error) m.failWith(*error);
  return m;
}

}  // namespace carenav::navigation
