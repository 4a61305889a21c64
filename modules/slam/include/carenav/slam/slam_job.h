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

/** A grid built by inserting each frame of the simple map at its pose. */
mrpt::maps::COccupancyGridMap2D gridFromSimpleMap(const mrpt::maps::CSimpleMap& sm,
                                                  double resolution);

}  // namespace carenav::slam
