// The output files of `carenav slam` from a mapper run live (the ROS slam
// node): the same files, written the same way as slam::runSlam writes them
// at the end of a rawlog.
#pragma once

#include <carenav/slam/slam_job.h>

namespace carenav::ros {

/** Writes DIR/{map.simplemap, trajectory.tum, map.gridmap.gz, map.yaml,
 *  map.pgm, map.png, summary.json} of `mapper` (o.out_dir; o.rawlog names
 *  the source in summary.json and the picture's title); `res` holds the run's
 *  counts and first pose, and gets the final pose, stats and outputs. Each
 *  file is replaced whole (written aside, then renamed) where runSlam does so. */
void writeSlamOutputs(const slam::Mapper& mapper, const slam::SlamJobOptions& o,
                      slam::SlamJobResult& res);

}  // namespace carenav::ros
