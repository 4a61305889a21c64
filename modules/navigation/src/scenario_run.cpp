// Running a scenario: the simulator drives the Navigator in closed loop,
// faster than real time; metrics from the simulator's ground truth.
#include <carenav/common/errors.h>
#include <carenav/common/json.h>
#include <carenav/common/profile.h>
#include <carenav/common/run_health.h>
#include <carenav/io/map_render.h>
#include <carenav/localization/localizer.h>
#include <carenav/navigation/global_planner.h>
#include <carenav/navigation/mrpt_ptg.h>
#include <carenav/navigation/navigator.h>
#include <carenav/navigation/scenario.h>
#include <carenav/perception/pipeline.h>
#include <carenav/places/places.h>
#include <carenav/sim/simulator.h>

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/poses/CPose2D.h>

#include <unistd.h>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <sstream>
#include <thread>

namespace carenav::navigation {

namespace fs = std::filesystem;

namespace {

/** Footprint clearance against the true world: walls, floor height changes
 *  (steps up or down, holes, stairs), table tops lower than the robot and
 *  people. */
class TruthClearance {
 public:
  TruthClearance(const sim::World& w, const RobotParams& robot, double step)
      : w_(w), fp_(robot.footprint, w.resolution()) {
    const int nx = w.sizeX(), ny = w.sizeY();
    std::vector<uint8_t> free(static_cast<size_t>(nx) * ny, 1);
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x) {
        const sim::Cell& c = w.cell(x, y);
        const bool blocked =
            c.wall() || std::abs(c.floor) > step || (c.hasSlab() && c.slab_lo < robot.height);
        if (blocked) free[static_cast<size_t>(y) * nx + x] = 0;
      }
    const auto d2 = squaredDistanceTransform(free, nx, ny);
    dist_.resize(d2.size());
    for (size_t i = 0; i < d2.size(); ++i)
      dist_[i] = std::isinf(d2[i]) ? 1e3f : static_cast<float>(std::sqrt(d2[i]) * w.resolution());
  }
  double at(const sim::Pose2& p, const std::vector<sim::PersonNow>& people) const {
    const double c = std::cos(p.yaw), s = std::sin(p.yaw);
    double best = std::numeric_limits<double>::infinity();
    for (const auto& b : fp_.boundary) {
      const double x = p.x + c * b.x - s * b.y, y = p.y + s * b.x + c * b.y;
      const int cx = w_.cellX(x), cy = w_.cellY(y);
      double d = 0;
      if (w_.inside(cx, cy)) d = dist_[static_cast<size_t>(cy) * w_.sizeX() + cx];
      for (const auto& q : people) d = std::min(d, std::hypot(x - q.x, y - q.y) - q.r);
      best = std::min(best, d);
    }
    return std::max(0.0, best - w_.resolution() / 2);
  }

 private:
  const sim::World& w_;
  Footprint fp_;
  std::vector<float> dist_;
};

/** The route as the local planner follows it: from where it was planned. */
std::vector<TPoint2D> withStart(const TPoint2D& start, const std::vector<TPoint2D>& waypoints) {
  std::vector<TPoint2D> out{start};
  out.insert(out.end(), waypoints.begin(), waypoints.end());
  return out;
}

/** Cells of the perception grid above this occupancy probability are obstacles. */
constexpr double perception_occupied = 0.6;

/** A path kept for the picture: beyond kMaxPathPoints every second point is
 *  dropped, so a run of any length holds a bounded number of them. */
constexpr size_t kMaxPathPoints = 20000;
void appendBounded(std::vector<TPoint2D>& path, const TPoint2D& p) {
  if (path.size() >= kMaxPathPoints) {
    size_t j = 0;
    for (size_t i = 0; i < path.size(); i += 2) path[j++] = path[i];
    path.resize(j);
  }
  path.push_back(p);
}

/** Resident memory is sampled every this many simulated seconds, and the
 *  cycle-time percentile is reported per window of kWindowSeconds. */
constexpr double kMemorySampleSeconds = 60, kWindowSeconds = 600;

std::string fmt(double v, int prec = 3) {
  char b[48];
  std::snprintf(b, sizeof b, "%.*f", prec, v);
  return b;
}

/** Resident memory into the run's samples (none where /proc cannot tell). */
void sampleMemory(RunMetrics& m) {
  const double mb = residentMegabytes();
  if (std::isfinite(mb)) m.rss_mb.push_back(mb);
}

/** How a patrol's leg ended: the robot reported the goal reached (checked
 *  against the truth), or it gave up or ran out of time. */
enum class LegEnd { Reported, Failed };

std::string patrolOutcome(const RunMetrics& m) {
  const size_t legs = m.legs_completed + m.legs_missed + m.legs_failed;
  if (m.legs_failed == 0 && m.legs_missed == 0 && m.legs_completed > 0)
    return "patrolled " + std::to_string(m.legs_completed) + " legs";
  std::string s =
      std::to_string(m.legs_failed) + " of " + std::to_string(legs) + " patrol legs failed";
  if (m.legs_missed > 0)
    s += ", " + std::to_string(m.legs_missed) + " reported reached up to " +
         fmt(m.leg_miss_max_m, 2) + " m from the goal";
  return s;
}

}  // namespace

RunMetrics runScenario(const Scenario& scenario, const RunOptions& o) {
  Scenario sc = scenario;
  if (!o.goal.empty()) {
    if (!sc.intent.empty())
      throw InputError(sc.file + ": --goal given for a scenario that scripts a user (intent)");
    sc.goal.reset();
    sc.goal_name.clear();
    sc.goal = parsePoseText(o.goal);
    if (!sc.goal) sc.goal_name = o.goal;
    sc.patrol.clear();
  }
  // Profile: --profile, else the scenario's.
  const std::string profile_path = !o.profile.empty() ? o.profile : sc.profile;
  if (profile_path.empty())
    throw InputError(sc.file + ": no robot profile: give --profile or 'profile:' in the scenario");
  // A path the scenario gives that leads nowhere is the scenario's fault: name it.
  auto mustExist = [&](const std::string& path, const char* key) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
      throw InputError(sc.file + ": '" + key + ":' " + path + ": no such file");
  };
  if (o.profile.empty()) mustExist(profile_path, "profile");
  mustExist(sc.world, "world");
  Profile prof = Profile::load(profile_path);
  prof.applyOverrides(o.sets);
  prof.validate();
  configureMrptPtg(prof);  // [nav.mrpt_ptg] for the mrpt-ptg plugin
  const auto robot = prof.section<RobotParams>("robot");
  const auto sensors = loadSensors(prof);
  auto nav = prof.section<NavigationParams>("navigation");
  if (!sc.plugin.empty()) nav.plugin = sc.plugin;
  if (!o.plugin.empty()) nav.plugin = o.plugin;
  auto simp = prof.section<sim::SimParams>("sim");
  simp.seed = sc.seed;
  const auto locp = prof.section<localization::LocalizationParams>("localization");

  auto world = std::make_shared<const sim::World>(sim::loadWorld(sc.world, simp.wall_height));
  // 2D lidars and range arrays go to the obstacle memory; depth cameras
  // through the perception pipeline (2.5D grid, RRT-GPD ground plane,
  // inverse sensor model: stairs down and gutters become obstacles).
  std::vector<SensorParams> used;
  for (const auto& s : sensors)
    if (s.type == "lidar2d" || s.type == "range-array" || s.type == "depth-camera")
      used.push_back(s);
  sim::Simulator sim(world, robot, used, simp);
  const auto perc_params = prof.section<perception::PerceptionParams>("perception");
  perception::Pipeline perceive(perc_params, perception::Method::RrtGpd);
  size_t depth_frames = 0;
  double perceive_ms = 0;
  sim.reset({sc.start.x, sc.start.y, sc.start.phi});
  if (sim.footprintBlocked({sc.start.x, sc.start.y, sc.start.phi}, 0))
    throw InputError(sc.file + ": the start pose puts the robot on an obstacle of the world");

  Navigator navigator(nav, robot);
  navigator.setRecoveryParams(prof.section<RecoveryParams>("nav.recovery"));
  const bool walker = navigator.planner().needsUserIntent();
  // Goals by name: a place, a room's default place or its most central free cell.
  std::optional<places::PlacesFile> places_file;
  auto resolve = [&](const GoalRef& ref) -> std::pair<TPose2D, std::string> {
    if (ref.pose) return {*ref.pose, ""};
    if (!places_file)
      places_file = places::readPlacesFile(sc.places.empty() ? places::placesPathForMap(sc.world)
                                                             : sc.places);
    const places::Goal g = places::resolveGoal(*places_file, world->grid(), ref.name);
    return {TPose2D{g.x, g.y, mrpt::DEG2RAD(g.heading_deg)},
            g.room + (g.place.empty() ? "" : "/" + g.place)};
  };
  std::vector<std::pair<TPose2D, std::string>> patrol;  // a patrol's goals, resolved
  for (const auto& ref : sc.patrol) patrol.push_back(resolve(ref));
  const bool patrolling = !patrol.empty();
  std::optional<TPose2D> goal;
  std::string goal_label;
  if (sc.goal || !sc.goal_name.empty())
    std::tie(goal, goal_label) = resolve(GoalRef{sc.goal, sc.goal_name});
  const bool goal_mode = goal.has_value();
  // A walker with a goal: the scripted user walks there along the route (a
  // user who knows the way), steering at heading_gain towards the point
  // `lookahead` ahead on it, at user_speed; the walker keeps them safe.
  const bool user_walks_route = walker && goal_mode;
  if (o.intent && !walker)
    throw InputError("--intent " + o.intent->describe() + ": plugin " + nav.plugin +
                     " drives to a goal; a user's commands need a walker plugin "
                     "(user-intent-dwa)");
  if (o.intent && goal_mode)
    throw InputError("--intent " + o.intent->describe() +
                     ": the user drives the walker; give no goal with it");
  if (!walker && !goal_mode)
    throw PluginMismatchError(sc.file + ": plugin " + nav.plugin +
                              " drives to a goal; this scenario scripts a user (use "
                              "user-intent-dwa)");

  RunMetrics m;
  m.scenario = sc.name;
  m.goal_name = goal_label;
  m.plugin = nav.plugin;

  // Goal navigation: route on the world's map, localisation on it from the
  // first 2D lidar (odometry alone when the robot has none).
  std::unique_ptr<localization::Localizer> loc;
  std::string loc_sensor;
  for (const auto& s : sensors)
    if (s.type == "lidar2d" && loc_sensor.empty()) loc_sensor = s.label;
  std::optional<Route> route;
  const Footprint fp(robot.footprint, nav.resolution);
  std::unique_ptr<GlobalPlanner> gp;
  NavigationParams route_nav = nav;  // the route's clearance (narrowed when nothing else fits)
  // The route from `from` to the goal; when there is no way with
  // plan_clearance to spare, a passage the footprint fits with its padding
  // is taken (and later routes may use it too).
  auto planRoute = [&](const TPoint2D& from) {
    auto plan = [&] {
      try {
        return gp->plan(from, {goal->x, goal->y});
      } catch (const InputError& e) {  // a start or goal off the map: the scenario's fault
        throw InputError(sc.file + ": " + e.what());
      }
    };
    auto r = plan();
    if (!r && route_nav.plan_clearance > route_nav.footprint_padding) {
      route_nav.plan_clearance = route_nav.footprint_padding;
      gp = std::make_unique<GlobalPlanner>(world->grid(), fp.inscribed, route_nav);
      r = plan();
    }
    return r;
  };
  for (const auto& [g, label] : patrol)
    if (!world->inside(world->cellX(g.x), world->cellY(g.y)))
      throw InputError(sc.file + ": patrol goal " + (label.empty() ? "" : label + " ") + "at (" +
                       fmt(g.x, 2) + ", " + fmt(g.y, 2) + ") is off the world's map");
  if (goal_mode) {
    gp = std::make_unique<GlobalPlanner>(world->grid(), fp.inscribed, nav);
    route = planRoute({sc.start.x, sc.start.y});
    if (route) navigator.setRoute(withStart({sc.start.x, sc.start.y}, route->waypoints), *goal);
    if (!loc_sensor.empty()) {
      loc = std::make_unique<localization::Localizer>(world->grid(), locp);
      loc->initPose(mrpt::poses::CPose2D(sc.start.x, sc.start.y, sc.start.phi), 0.1, 0.1,
                    mrpt::DEG2RAD(3.0));
    }
  }

  const TruthClearance truth_clear(*world, robot, simp.bumper_step);
  const double dt = 1.0 / o.control_rate;
  std::vector<TPoint2D> truth_path{{sc.start.x, sc.start.y}}, user_path{{sc.start.x, sc.start.y}};
  TPose2D user_pose = sc.start;  // where the user's commands alone would take a free walker
  mrpt::poses::CPose2D last_loc_odo;
  bool loc_started = false;
  double clear_sum = 0, fid_sum = 0, cycle_ms_sum = 0;
  size_t fid_n = 0;
  m.min_clearance_m = std::numeric_limits<double>::infinity();
  bool reached = false, goal_reached = false, left_map = false;
  std::string gave_up;
  const double duration = o.duration ? *o.duration : sc.duration;
  double t_end = duration;
  std::optional<InputError> input_error;  // a live source's bad message: outputs first
  bool intent_over = false;
  std::ofstream log;
  if (!o.out_dir.empty()) {
    fs::create_directories(o.out_dir);
    log.open(fs::path(o.out_dir) / "navlog.csv");
    log << "t,truth_x,truth_y,truth_yaw,est_x,est_y,est_yaw,user_v,user_w,plan_v,plan_w,cmd_v,"
           "cmd_w,action,reason,clearance_m,obstacle_cells,planner_note,collision,recovery\n";
  }
  const auto wall0 = std::chrono::steady_clock::now();
  const bool tty = o.progress && isatty(fileno(stderr));
  const auto& odo0 = sim.odometry();
  navigator.setOdometry({odo0.x, odo0.y, odo0.yaw}, {0, 0}, 0);
  const size_t steps = std::isfinite(duration)
                           ? static_cast<size_t>(std::ceil(duration / dt - 1e-9))
                           : std::numeric_limits<size_t>::max();
  RouteReplanner replanner(o.control_rate);
  size_t recovery_cycles = 0;
  std::string last_recovery;
  bool collision_end = false;
  TPoint2D route_start{sc.start.x, sc.start.y};
  // A patrol: the leg to the current goal ends (reached in truth, or not:
  // given up, timed out, stopped away from it) and the next goal is taken.
  size_t leg = 0;
  double leg_t0 = 0;
  auto nextLeg = [&](LegEnd end, const sim::Pose2& truth, double now) {
    if (end == LegEnd::Reported) {
      const double err = std::hypot(truth.x - goal->x, truth.y - goal->y);
      if (err > nav.goal_tolerance) {
        ++m.legs_missed;  // the robot's localisation put it there; the truth did not
        m.leg_miss_max_m = std::max(m.leg_miss_max_m, err);
      } else {
        ++m.legs_completed;
      }
    } else {
      ++m.legs_failed;
    }
    leg = (leg + 1) % patrol.size();
    std::tie(goal, goal_label) = patrol[leg];
    leg_t0 = now;
    const TPose2D mp = navigator.mapPose();
    route_start = {mp.x, mp.y};
    route = planRoute(route_start);
    if (route)
      navigator.setRoute(withStart(route_start, route->waypoints), *goal);
    else
      navigator.clearRoute();  // the replanner keeps trying; the leg times out otherwise
  };
  // Health of the run: the robot's work per control period (sensor
  // processing, localisation, the navigator, replanning), in a histogram of
  // fixed size; resident memory sampled every kMemorySampleSeconds.
  DurationHistogram work_all, work_window;
  double work_ms = 0;
  auto sampleHealth = [&](size_t k) {
    work_all.add(work_ms);
    work_window.add(work_ms);
    const auto per = [&](double s) {
      return std::max<size_t>(1, std::llround(s * o.control_rate));
    };
    if (k % per(kMemorySampleSeconds) == 0) sampleMemory(m);
    if ((k + 1) % per(kWindowSeconds) == 0) {
      m.work_ms_p99_windows.push_back(work_window.quantile(0.99));
      work_window.clear();
    }
  };
  for (size_t k = 0; k < steps; ++k) {
    if (o.stop && o.stop->load()) break;
    if (o.speed > 0) {
      // Live pace: simulated time runs `speed` times the wall clock.
      const auto due = wall0 + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                   std::chrono::duration<double>(sim.time() / o.speed));
      std::this_thread::sleep_until(due);
    }
    // Sensors and odometry of the last period.
    const auto frames = sim.step(dt);
    const double work0 = threadCpuMs();
    for (const auto& f : frames) {
      const TPose2D odo{f.odometry.x, f.odometry.y, f.odometry.yaw};
      navigator.setOdometry(odo, {sim.v(), sim.w()}, f.t);
      for (const auto& obs : f.observations) {
        if (dynamic_cast<const mrpt::obs::CObservationOdometry*>(obs.get())) continue;
        if (auto* depth = dynamic_cast<mrpt::obs::CObservation3DRangeScan*>(obs.get())) {
          if (!perc_params.sensor.empty() && depth->sensorLabel != perc_params.sensor) continue;
          const auto cloud = perception::cloudFromObservation(*depth);
          if (!cloud) continue;
          perception::FrameInput fi;
          fi.cloud = &*cloud;
          fi.sensor_origin = {static_cast<float>(depth->sensorPose.x()),
                              static_cast<float>(depth->sensorPose.y()),
                              static_cast<float>(depth->sensorPose.z())};
          fi.odometry = mrpt::poses::CPose2D(odo.x, odo.y, odo.phi);
          const auto c0 = std::chrono::steady_clock::now();
          const auto fr = perceive.process(fi, false);
          perceive_ms +=
              std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - c0)
                  .count();
          ++depth_frames;
          // Occupied cells of the local grid are obstacles for navigation.
          const auto& g = perceive.grid();
          std::vector<TPoint2D> occ;
          for (int j = 0; j < g.cells(); ++j)
            for (int i = 0; i < g.cells(); ++i)
              if (g.prob(i, j) > perception_occupied) occ.push_back({g.centreX(i), g.centreY(j)});
          navigator.setPerceivedObstacles(std::move(occ), f.t);
          // The frame's own floor and obstacle voxels: people walking in.
          // (Not the grid's ray-cleared cells: rays pass over a box's top.)
          std::vector<TPoint2D> seen_free, seen_hit;
          const auto& ev = perceive.elevation();
          const int me = ev.cells();
          const double ca = std::cos(odo.phi), sa = std::sin(odo.phi);
          if (fr.voxel_classes.size() == static_cast<size_t>(me) * me)
            for (int i = 0; i < me; ++i)
              for (int j = 0; j < me; ++j) {
                const auto vc = fr.voxel_classes[static_cast<size_t>(i) * me + j];
                if (vc == perception::VoxelClass::None) continue;
                const double x = ev.centre(i), y = ev.centre(j);
                const TPoint2D w{odo.x + ca * x - sa * y, odo.y + sa * x + ca * y};
                (vc == perception::VoxelClass::Ground ? seen_free : seen_hit).push_back(w);
              }
          navigator.addPerceivedFrame(seen_free, seen_hit, f.t);
          continue;
        }
        navigator.addObservation(*obs, odo, f.t);
        if (loc && obs->sensorLabel == loc_sensor) {
          const mrpt::poses::CPose2D now_odo(odo.x, odo.y, odo.phi);
          const mrpt::poses::CPose2D inc =
              loc_started ? now_odo - last_loc_odo : mrpt::poses::CPose2D();
          last_loc_odo = now_odo;
          loc_started = true;
          loc->step(inc, std::dynamic_pointer_cast<mrpt::obs::CObservation2DRangeScan>(obs), f.t);
          const auto p = loc->pose();
          navigator.setMapPose({p.x(), p.y(), p.phi()});
          // HOBBIT: localisation may ask for a turn in place to relocalise.
          navigator.setRotateRequest(loc->needsRotateInPlace());
        }
      }
    }
    const double t = sim.time();
    const sim::Pose2 truth = sim.groundTruth();
    std::optional<Twist> user;
    if (user_walks_route) {
      const bool there = std::hypot(truth.x - goal->x, truth.y - goal->y) < nav.goal_tolerance;
      if (patrolling && (there || t - leg_t0 > sc.leg_timeout)) {
        nextLeg(there ? LegEnd::Reported : LegEnd::Failed, truth, t);
      } else if (std::hypot(truth.x - goal->x, truth.y - goal->y) < nav.goal_tolerance) {
        goal_reached = true;
        t_end = t;
        break;
      }
      if (route) {
        const auto pts = withStart(route_start, route->waypoints);
        const TPoint2D la = lookaheadPoint(pts, truth.x, truth.y, nav.lookahead);
        const double err =
            std::remainder(std::atan2(la.y - truth.y, la.x - truth.x) - truth.yaw, 2 * M_PI);
        // A person turns on the spot before walking off in a new direction.
        const double v = std::abs(err) > M_PI / 3 ? 0.0 : sc.user_speed;
        user = Twist{v, std::clamp(sc.heading_gain * err, -robot.w_max, robot.w_max)};
        navigator.setUserIntent(*user, t);
        appendBounded(user_path, {truth.x, truth.y});
      }
    } else if (o.intent) {
      std::optional<IntentSample> s;
      try {
        s = o.intent->poll(t);
      } catch (const InputError& e) {
        input_error = e;
        sim.setCommand(0, 0);
        break;
      }
      if (s) {
        navigator.setUserIntent(s->cmd, s->t);
        if (t - s->t <= nav.intent_timeout) {
          user = s->cmd;
          user_pose = integrateArc(user_pose, s->cmd.v,
                                   std::clamp(s->cmd.w, -robot.w_max, robot.w_max), dt);
          appendBounded(user_path, {user_pose.x, user_pose.y});
        }
      }
      // The source has ended (script over, q pressed): stop once the walker stands.
      if (o.intent->finished(t)) {
        if (intent_over && std::abs(sim.v()) < 1e-3 && std::abs(sim.w()) < 1e-3) {
          t_end = t;
          break;
        }
        intent_over = true;
      }
    } else if (walker) {
      if (const auto u = sc.userAt(t, truth.yaw)) {
        user = Twist{u->first, u->second};
        navigator.setUserIntent(*user, t);
        // The user's intended path: their commands on a free floor.
        const auto ui = sc.userAt(t, user_pose.phi);
        user_pose = integrateArc(user_pose, ui->first,
                                 std::clamp(ui->second, -robot.w_max, robot.w_max), dt);
        appendBounded(user_path, {user_pose.x, user_pose.y});
      }
    }
    const auto c0 = std::chrono::steady_clock::now();
    const Navigator::Cycle cyc = navigator.cycle(t);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - c0).count();
    cycle_ms_sum += ms;
    work_ms = threadCpuMs() - work0;
    m.cycle_ms_max = std::max(m.cycle_ms_max, ms);
    ++m.cycles;
    sim.setCommand(cyc.decision.cmd.v, cyc.decision.cmd.w);
    m.stops += cyc.decision.action == SafetyAction::Stop;
    m.slowed += cyc.decision.action == SafetyAction::Slow;

    // Metrics from the truth.
    const double cl = truth_clear.at(truth, sim::peopleAt(*world, t));
    m.min_clearance_m = std::min(m.min_clearance_m, cl);
    clear_sum += cl;
    appendBounded(truth_path, {truth.x, truth.y});
    for (const auto& poly : sc.forbidden)
      if (places::pointInPolygon(poly, truth.x, truth.y)) m.entered_forbidden = true;
    // Off the world's map: the run is a failure.
    {
      const int cx = world->cellX(truth.x), cy = world->cellY(truth.y);
      if (!world->inside(cx, cy)) left_map = true;
    }
    const bool collided_now = sim.collided();
    if (!cyc.recovery.empty()) ++recovery_cycles;
    if (!cyc.recovery.empty() && last_recovery.empty()) ++m.recoveries;
    last_recovery = cyc.recovery;
    if (sc.reach &&
        std::hypot(truth.x - sc.reach->first.x, truth.y - sc.reach->first.y) <= sc.reach->second)
      reached = true;
    // Fidelity where the user's own command is free of collisions.
    if (walker && user)
      if (const auto d = navigator.intentDeviation(*user, cyc.decision.cmd)) {
        fid_sum += *d;
        ++fid_n;
      }
    if (log.is_open()) {
      const TPose2D est = navigator.mapPose();
      log << fmt(t) << "," << fmt(truth.x) << "," << fmt(truth.y) << "," << fmt(truth.yaw, 4) << ","
          << fmt(est.x) << "," << fmt(est.y) << "," << fmt(est.phi, 4) << ","
          << (user ? fmt(user->v) : "") << "," << (user ? fmt(user->w) : "") << ","
          << fmt(cyc.plan.cmd.v) << "," << fmt(cyc.plan.cmd.w, 4) << "," << fmt(cyc.decision.cmd.v)
          << "," << fmt(cyc.decision.cmd.w, 4) << "," << safetyActionName(cyc.decision.action)
          << ",\"" << cyc.decision.reason << "\"," << fmt(cl) << "," << cyc.obstacles << ",\""
          << cyc.plan.note << "\"," << (collided_now ? 1 : 0) << "," << cyc.recovery << "\n";
    }
    if (tty && k % (o.speed > 0 ? 2 : 20) == 0) {
      // The status line.
      std::cerr << "\r[navigate] " << sc.name << " t " << fmt(t, 1);
      if (std::isfinite(duration)) std::cerr << " / " << fmt(duration, 0);
      std::cerr << " s";
      if (user) std::cerr << ", user " << fmt(user->v, 2) << " m/s " << fmt(user->w, 2) << " rad/s";
      std::cerr << ", cmd " << fmt(cyc.decision.cmd.v, 2) << " " << fmt(cyc.decision.cmd.w, 2)
                << " " << safetyActionName(cyc.decision.action) << ", clearance " << fmt(cl, 2)
                << " m, " << sim.collisions() << " collisions   " << std::flush;
    }
    if (patrolling && !walker && (cyc.goal_reached || cyc.gave_up || t - leg_t0 > sc.leg_timeout)) {
      nextLeg(cyc.goal_reached ? LegEnd::Reported : LegEnd::Failed, truth, t);
    } else if (goal_mode && cyc.goal_reached) {
      goal_reached = true;
      t_end = t;
      break;
    }
    // The first collision ends the run (unless asked to go on).
    if (sim.collisions() > 0 && !o.continue_after_collision) {
      t_end = t;
      collision_end = true;
      break;
    }
    if (cyc.gave_up && !patrolling) {
      gave_up = cyc.plan.note;
      t_end = t;
      break;
    }
    // Replan from the localised pose with the obstacles the robot has seen
    // marked on the map (boxes and people the map does not show; when that
    // finds no route, the last one stays). A walker's scripted user walks
    // the new route too: a user sees boxes and people.
    const double replan0 = threadCpuMs();
    if (goal_mode && gp && (cyc.replan || replanner.due(k, !navigator.predicted().empty()))) {
      const TPose2D mp = navigator.mapPose();
      if (auto r2 = replanner.step(!navigator.predicted().empty(), world->grid(),
                                   navigator.obstaclesInMap(), {mp.x, mp.y}, {goal->x, goal->y},
                                   route, fp.inscribed, fp.circumscribed + 0.2, route_nav)) {
        route = r2;
        route_start = {mp.x, mp.y};
        navigator.setRoute(withStart({mp.x, mp.y}, route->waypoints), *goal);
      }
    }
    work_ms += threadCpuMs() - replan0;
    sampleHealth(k);
  }
  if (tty) std::cerr << "\n";
  if (work_window.count() > 0) m.work_ms_p99_windows.push_back(work_window.quantile(0.99));
  m.work_ms_p99 = work_all.quantile(0.99);
  m.work_ms_max = work_all.max();
  sampleMemory(m);
  m.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  m.collisions = sim.collisions();
  m.duration_s = !patrolling && (goal_reached || intent_over || collision_end || !gave_up.empty())
                     ? t_end
                     : sim.time();
  m.recovery_cycles = recovery_cycles;
  m.left_map = left_map;
  m.path_length_m = sim.distance();
  m.mean_speed_mps = m.duration_s > 0 ? m.path_length_m / m.duration_s : 0;
  m.mean_clearance_m = m.cycles ? clear_sum / m.cycles : 0;
  m.cycle_ms_mean = m.cycles ? cycle_ms_sum / m.cycles : 0;
  m.depth_frames = depth_frames;
  m.perception_ms_mean = depth_frames ? perceive_ms / depth_frames : 0;
  m.intent_fidelity = fid_n ? fid_sum / fid_n : std::numeric_limits<double>::quiet_NaN();
  const sim::Pose2 end = sim.groundTruth();
  if (goal_mode) m.final_goal_error_m = std::hypot(end.x - goal->x, end.y - goal->y);
  // At the goal means at the goal in truth, at the end: the robot's own
  // "goal reached" (from its localisation) is not enough.
  const bool at_goal = goal_mode && goal_reached && m.final_goal_error_m <= nav.goal_tolerance;

  // Outcome.
  if (m.collisions > 0)
    m.outcome = std::to_string(m.collisions) + " collision(s)";
  else if (m.entered_forbidden)
    m.outcome = "entered a forbidden region";
  else if (left_map)
    m.outcome = "left the map";
  else if (!gave_up.empty())
    m.outcome = gave_up;
  else if (patrolling)
    m.outcome = patrolOutcome(m);
  else if (goal_mode && !route)
    m.outcome = sc.path_exists ? "no route to the goal" : "no route (as expected)";
  else if (goal_mode && !goal_reached)
    m.outcome = "goal not reached in " + fmt(duration, 0) + " s";
  else if (goal_mode && !at_goal && route)
    m.outcome = "reported the goal reached " + fmt(m.final_goal_error_m, 2) + " m from it";
  else if (sc.reach && !o.intent && !reached)
    m.outcome = "did not reach the target region";
  else
    m.outcome = goal_mode ? "goal reached" : "ok";
  const bool goal_ok = patrolling ? m.legs_failed == 0 && m.legs_missed == 0 && m.legs_completed > 0
                                  : at_goal || (!route && !sc.path_exists);
  m.success = m.collisions == 0 && !m.entered_forbidden && !left_map && gave_up.empty() &&
              (goal_mode ? goal_ok : true) &&
              (!sc.reach || o.intent || reached);  // a live user goes where they like

  if (!o.out_dir.empty()) {
    io::RenderOptions ro;
    ro.title = "carenav navigate " + sc.name + " (" + nav.plugin + "): robot red" +
               std::string(walker ? ", user's intended path blue" : ", route blue") + ", " +
               m.outcome;
    if (walker) {
      io::Overlay u;
      u.points = user_path;
      u.colour = {40, 80, 220};
      ro.overlays.push_back(u);
    } else if (route) {
      io::Overlay r;
      r.points.push_back({sc.start.x, sc.start.y});
      for (const auto& w : route->waypoints) r.points.push_back(w);
      r.colour = {40, 80, 220};
      ro.overlays.push_back(r);
    }
    io::Overlay obs;
    for (const auto& p : navigator.obstaclesInMap()) obs.points.push_back(p);
    obs.colour = {255, 140, 0};
    obs.points_only = true;
    ro.overlays.push_back(obs);
    for (const auto& poly : sc.forbidden) {
      io::Overlay f;
      f.points = poly;
      f.points.push_back(poly.front());
      f.colour = {200, 0, 200};
      ro.overlays.push_back(f);
    }
    io::Overlay tr;
    tr.points = truth_path;
    tr.colour = {220, 30, 30};
    tr.start_end_markers = true;
    ro.overlays.push_back(tr);
    const std::string png = (fs::path(o.out_dir) / "run.png").string();
    io::renderGridMapPng(world->grid(), png, ro);
    m.writeSummary(o.out_dir, png);
  }
  if (input_error) m.failWith(*input_error);
  return m;
}

void RunMetrics::writeSummary(const std::string& out_dir, const std::string& png) {
  outputs.push_back(png);
  outputs.push_back((fs::path(out_dir) / "navlog.csv").string());
  const std::string js = (fs::path(out_dir) / "summary.json").string();
  std::ofstream(js) << toJson() << "\n";
  outputs.push_back(js);
}

void RunMetrics::failWith(const InputError& error) const {
  for (const auto& f : outputs) std::cerr << "[navigate] wrote " << f << "\n";
  throw error;
}

std::string RunMetrics::toJson() const {
  JsonWriter j;
  j.beginObject();
  j.key("scenario").value(scenario);
  j.key("plugin").value(plugin);
  if (!goal_name.empty()) j.key("goal_name").value(goal_name);
  j.key("success").value(success);
  j.key("outcome").value(outcome);
  j.key("collisions").value(static_cast<uint64_t>(collisions));
  j.key("min_clearance_m").value(std::isfinite(min_clearance_m) ? min_clearance_m : 0.0);
  j.key("mean_clearance_m").value(mean_clearance_m);
  j.key("duration_s").value(duration_s);
  j.key("path_length_m").value(path_length_m);
  j.key("mean_speed_mps").value(mean_speed_mps);
  if (std::isnan(intent_fidelity))
    j.key("intent_fidelity").null();
  else
    j.key("intent_fidelity").value(intent_fidelity);
  j.key("final_goal_error_m").value(final_goal_error_m);
  j.key("recoveries").value(static_cast<uint64_t>(recoveries));
  j.key("legs_completed").value(static_cast<uint64_t>(legs_completed));
  j.key("legs_failed").value(static_cast<uint64_t>(legs_failed));
  j.key("legs_missed").value(static_cast<uint64_t>(legs_missed));
  j.key("leg_miss_max_m").value(leg_miss_max_m);
  j.key("recovery_cycles").value(static_cast<uint64_t>(recovery_cycles));
  j.key("left_map").value(left_map);
  j.key("cycles").value(static_cast<uint64_t>(cycles));
  j.key("stops").value(static_cast<uint64_t>(stops));
  j.key("slowed").value(static_cast<uint64_t>(slowed));
  j.key("cycle_ms_mean").value(cycle_ms_mean);
  j.key("cycle_ms_max").value(cycle_ms_max);
  j.key("work_ms_p99").value(work_ms_p99);
  j.key("work_ms_max").value(work_ms_max);
  j.key("work_ms_p99_per_10min").beginArray();
  for (double v : work_ms_p99_windows) j.value(v);
  j.endArray();
  j.key("rss_mb_per_minute").beginArray();
  for (double v : rss_mb) j.value(v);
  j.endArray();
  j.key("depth_frames").value(static_cast<uint64_t>(depth_frames));
  j.key("perception_ms_mean").value(perception_ms_mean);
  j.key("wall_seconds").value(wall_seconds);
  j.endObject();
  return j.str();
}

}  // namespace carenav::navigation
