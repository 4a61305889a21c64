// `carenav simulate`: drive a profile's robot through a world and write an
// observation-only rawlog, its ground truth (TUM) and a summary (JSON).
#pragma once

#include <carenav/common/robot.h>
#include <carenav/sim/drive.h>
#include <carenav/sim/sim_params.h>

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace carenav::sim {

struct SimulateOptions {
  RobotParams robot;
  std::vector<SensorParams> sensors;
  SimParams params;
  std::string world;                    ///< world YAML
  std::vector<Vec2> path;               ///< waypoints (--path), or
  std::optional<CommandScript> script;  ///< timed commands (--script)
  std::optional<Pose2> start;  ///< default: first waypoint facing the second, or the origin
  double duration = 0;         ///< s of simulated time at most (0: path 3600 s, script its end)
  std::string out;             ///< X.rawlog (or X.rawlog.gz)
  bool progress = true;
};

struct SimulateResult {
  double sim_seconds = 0, wall_seconds = 0;
  size_t frames = 0, collisions = 0;
  std::map<std::string, size_t> observations;  ///< per sensorLabel (odometry included)
  bool path_completed = false;
  size_t waypoints_reached = 0;
  double distance = 0;
  std::string rawlog, ground_truth, summary;
};

/** X.rawlog -> X.gt.tum and X.summary.json (X.rawlog.gz alike). */
std::string groundTruthPathFor(const std::string& rawlog);
std::string summaryPathFor(const std::string& rawlog);

/** Runs the simulation and writes the files (to temporary names, renamed at
 *  the end). Throws InputError for a bad world, an output path that cannot
 *  be written, a start pose in collision or outside the map. */
SimulateResult runSimulate(const SimulateOptions& o);

}  // namespace carenav::sim
