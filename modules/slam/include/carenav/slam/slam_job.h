// `carenav slam`: a rawlog through a SLAM back end into map files.
#pragma once

#include <carenav/slam/mapper.h>

#include <mrpt/maps/COccupancyGridMap2D.h>

#include <optional>
#include <string>
#include <vector>

namespace carenav::slam {

struct SlamJobOptions {
  std::string rawlog;
  std::string out_dir;
  std::string method = "icp-graph";
  MapperConfig mapper;
  bool progress = true;  ///< progress line on stderr (only on a terminal)
};

struct SlamJobResult {
  MapperStats stats;
  size_t steps = 0;    ///< scans fed to the back end
  size_t entries = 0;  ///< rawlog entries read
  double seconds = 0;  ///< wall time of the mapping (reading included)
  mrpt::poses::CPose2D first_pose, final_pose;
  mrpt::math::CMatrixDouble33 final_cov;
  std::vector<std::string> outputs;  ///< files written
  /** Set when the rawlog broke: everything above covers the scans before. */
  std::optional<std::string> rawlog_error;
  std::string summaryJson(const SlamJobOptions& o) const;
};

/** Runs the job and writes DIR/{map.simplemap, map.gridmap.gz, map.yaml,
 *  map.pgm, map.png, trajectory.tum, summary.json}. A broken rawlog still
 *  writes the map of what was read (result.rawlog_error tells). Throws
 *  InputError when nothing could be mapped (no usable 2D scan). */
SlamJobResult runSlam(const SlamJobOptions& o);

/** Writes the outputs of `carenav slam` for `mapper` to o.out_dir (created):
 *  map.simplemap, trajectory.tum, map.gridmap.gz, map.yaml + map.pgm,
 *  map.png (the grid with the trajectory, headed `title`) and summary.json
 *  (o.rawlog names the source). `res` holds the run's counts and first
 *  pose; it gets the mapper's stats, final pose and covariance, and the
 *  files written (its outputs, replaced). The simple map and the summary are
 *  written aside and renamed. runSlam calls it at the end of the rawlog, the
 *  ROS slam node at each save. */
void writeSlamOutputs(const Mapper& mapper, const SlamJobOptions& o, SlamJobResult& res,
                      const std::string& title);

/** A grid built by inserting each frame of the simple map at its pose. */
mrpt::maps::COccupancyGridMap2D gridFromSimpleMap(const mrpt::maps::CSimpleMap& sm,
                                                  double resolution);

}  // namespace carenav::slam
