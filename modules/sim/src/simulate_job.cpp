#include <carenav/common/json.h>
#include <carenav/common/progress.h>
#include <carenav/io/trajectory.h>
#include <carenav/sim/simulate_job.h>
#include <carenav/sim/simulator.h>

#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/io/CFileOutputStream.h>
#include <mrpt/serialization/CArchive.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>

namespace carenav::sim {

namespace fs = std::filesystem;

namespace {
std::string stem(const std::string& rawlog) {
  for (const char* ext : {".rawlog.gz", ".rawlog"}) {
    const std::string e = ext;
    if (rawlog.size() > e.size() && rawlog.compare(rawlog.size() - e.size(), e.size(), e) == 0)
      return rawlog.substr(0, rawlog.size() - e.size());
  }
  return rawlog;
}
}  // namespace

std::string groundTruthPathFor(const std::string& rawlog) { return stem(rawlog) + ".gt.tum"; }
std::string summaryPathFor(const std::string& rawlog) { return stem(rawlog) + ".summary.json"; }

namespace {

void checkSimulateOptions(const SimulateOptions& o) {
  const std::string& out = o.out;
  if (stem(out) == out)
    throw InputError("--out " + out + ": the name must end in .rawlog or .rawlog.gz");
  const fs::path dir = fs::path(out).parent_path();
  std::error_code ec;
  if (!dir.empty() && !fs::is_directory(dir, ec))
    throw InputError("--out " + out + ": folder " + dir.string() + " does not exist");
  if (o.path.empty() && !o.script) throw InputError("give --path or --script");
  if (o.path.size() == 1 && !o.start)
    throw InputError(
        "--path: one waypoint and no --start: the robot starts on it, nothing to drive");
  if (o.duration > kMaxSimSeconds)
    throw InputError("--duration " + std::to_string(o.duration) + " s: at most " +
                     std::to_string(static_cast<int>(kMaxSimSeconds)) + " s");
  bool any_sensor = false;
  for (const auto& s : o.sensors) any_sensor = any_sensor || s.type != "bumper";
  if (!any_sensor)
    throw InputError(
        "the profile has no sensor to simulate (a [sensor.<label>] of type lidar2d, "
        "range-array or depth-camera)");
}

/** --start, else the first waypoint facing the second. */
Pose2 startPose(const SimulateOptions& o) {
  Pose2 start;
  if (o.start) {
    start = *o.start;
  } else if (!o.path.empty()) {
    start = {o.path[0].x, o.path[0].y, 0};
    if (o.path.size() > 1)
      start.yaw = std::atan2(o.path[1].y - o.path[0].y, o.path[1].x - o.path[0].x);
  }
  return start;
}

void checkStart(const SimulateOptions& o, const World& world, const Simulator& sim,
                const Pose2& start) {
  if (!world.inside(world.cellX(start.x), world.cellY(start.y)))
    throw InputError(o.world + ": the start pose (" + std::to_string(start.x) + ", " +
                     std::to_string(start.y) + ") is outside the map");
  if (sim.footprintBlocked(start, 0))
    throw InputError(o.world + ": the robot's footprint at the start pose (" +
                     std::to_string(start.x) + ", " + std::to_string(start.y) +
                     ") touches an obstacle");
}

double simDuration(const SimulateOptions& o) {
  double duration = o.duration;
  if (duration <= 0) duration = o.script ? o.script->endTime() : 3600.0;
  if (duration <= 0)
    throw InputError("the script ends at t = 0: nothing to simulate (give --duration)");
  return duration;
}

/** The rawlog stream on `tmp`: gzip when `out` ends in .gz. */
std::unique_ptr<mrpt::io::CStream> openRawlog(const std::string& out, const std::string& tmp) {
  std::unique_ptr<mrpt::io::CStream> stream;
  const bool gz = out.size() > 3 && out.compare(out.size() - 3, 3, ".gz") == 0;
  try {
    if (gz) {
      auto s = std::make_unique<mrpt::io::CFileGZOutputStream>();
      if (!s->open(tmp)) throw std::runtime_error("");
      stream = std::move(s);
    } else {
      auto s = std::make_unique<mrpt::io::CFileOutputStream>();
      if (!s->open(tmp)) throw std::runtime_error("");
      stream = std::move(s);
    }
  } catch (const std::exception&) {
    throw InputError("--out " + out + ": cannot write " + tmp);
  }
  return stream;
}

/** Drives the robot for `duration` s (or until the path is done and the robot
 *  has stopped), writing every observation and the ground truth. */
void drive(const SimulateOptions& o, const SimParams& params, double duration, Simulator& sim,
           std::optional<WaypointFollower>& follower, mrpt::serialization::CArchive& arch,
           SimulateResult& r, io::Trajectory2D& gt) {
  Progress progress("simulate", 0, false);
  progress.setEnabled(o.progress && progress.enabled());
  const double control_dt = 0.05;  // the driver decides at 20 Hz
  double stop_at = -1;             // path done: run on until the robot has stopped
  while (sim.time() < duration - 1e-9) {
    double v = 0, w = 0;
    if (follower) {
      follower->command(sim.groundTruth(), v, w);
      if (follower->done() && stop_at < 0) stop_at = sim.time() + params.latency;
    } else {
      o.script->at(sim.time(), v, w);
    }
    sim.setCommand(v, w);
    const auto frames = sim.step(std::min(control_dt, duration - sim.time()));
    for (const auto& f : frames) {
      for (const auto& obs : f.observations) {
        if (!obs) continue;
        arch << *obs;
        ++r.observations[obs->sensorLabel];
      }
      gt.push_back({kSimEpoch + f.t, f.truth.x, f.truth.y, f.truth.yaw});
      ++r.frames;
    }
    progress.update(0, r.frames);
    if (stop_at >= 0 && sim.time() >= stop_at && std::abs(sim.v()) < 1e-6 &&
        std::abs(sim.w()) < 1e-6)
      break;
  }
  progress.finish();
}

void writeSummary(const SimulateOptions& o, const SimParams& params, const Simulator& sim,
                  bool with_path, const SimulateResult& r) {
  JsonWriter j;
  j.beginObject();
  j.key("world").value(o.world);
  j.key("rawlog").value(r.rawlog);
  j.key("ground_truth").value(r.ground_truth);
  j.key("seed").value(params.seed);
  j.key("sim_seconds").value(r.sim_seconds);
  j.key("wall_seconds").value(r.wall_seconds);
  j.key("speedup").value(r.wall_seconds > 0 ? r.sim_seconds / r.wall_seconds : 0.0);
  j.key("frames").value(static_cast<uint64_t>(r.frames));
  j.key("distance").value(r.distance);
  j.key("collisions").value(static_cast<uint64_t>(r.collisions));
  if (with_path) {
    j.key("path_completed").value(r.path_completed);
    j.key("waypoints_reached").value(static_cast<uint64_t>(r.waypoints_reached));
    j.key("waypoints").value(static_cast<uint64_t>(o.path.size()));
  }
  const Pose2 g = sim.groundTruth(), od = sim.odometry();
  j.key("final_truth").beginArray().value(g.x).value(g.y).value(g.yaw * 180 / M_PI).endArray();
  j.key("final_odometry")
      .beginArray()
      .value(od.x)
      .value(od.y)
      .value(od.yaw * 180 / M_PI)
      .endArray();
  j.key("observations").beginObject();
  for (const auto& [label, n] : r.observations) j.key(label).value(static_cast<uint64_t>(n));
  j.endObject();
  j.endObject();
  std::ofstream f(r.summary);
  f << j.str() << "\n";
  if (!f) throw std::runtime_error("cannot write " + r.summary);
}

}  // namespace

SimulateResult runSimulate(const SimulateOptions& o) {
  checkSimulateOptions(o);
  const std::string& out = o.out;
  auto world = std::make_shared<World>(loadWorld(o.world, o.params.wall_height));
  SimParams params = o.params;
  Simulator sim(world, o.robot, o.sensors, params);
  const Pose2 start = startPose(o);
  checkStart(o, *world, sim, start);
  sim.reset(start);
  const double duration = simDuration(o);

  const std::string tmp = out + ".tmp";
  std::unique_ptr<mrpt::io::CStream> stream = openRawlog(out, tmp);
  auto arch = mrpt::serialization::archiveFrom(*stream);
  SimulateResult r;
  io::Trajectory2D gt;
  std::optional<WaypointFollower> follower;
  if (!o.path.empty()) follower.emplace(o.path, o.robot);
  const auto wall0 = std::chrono::steady_clock::now();
  drive(o, params, duration, sim, follower, arch, r, gt);
  stream.reset();
  r.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  r.sim_seconds = sim.time();
  r.collisions = sim.collisions();
  r.distance = sim.distance();
  if (follower) {
    r.path_completed = follower->done();
    r.waypoints_reached = follower->reached();
  }
  if (r.frames == 0) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw InputError("nothing simulated: no sensor produced a frame in " +
                     std::to_string(duration) + " s");
  }
  r.rawlog = out;
  r.ground_truth = groundTruthPathFor(out);
  r.summary = summaryPathFor(out);
  fs::rename(tmp, out);
  io::writeTum(r.ground_truth, gt);
  writeSummary(o, params, sim, follower.has_value(), r);
  return r;
}

}  // namespace carenav::sim
