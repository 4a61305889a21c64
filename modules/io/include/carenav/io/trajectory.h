// Trajectories in the TUM text format ("t x y z qx qy qz qw" per line), the
// format evo and most SLAM evaluation tools read.
#pragma once

#include <string>
#include <vector>

namespace carenav::io {

/** A planar pose at a time (UNIX seconds). */
struct TimedPose2D {
  double t = 0;
  double x = 0, y = 0, yaw = 0;  ///< m, m, rad
};

using Trajectory2D = std::vector<TimedPose2D>;

/** Writes TUM lines (z = 0, rotation about z as a quaternion), with a '#'
 *  header line. Writes to a temporary file and renames it, so a crash never
 *  leaves half a file. Throws std::runtime_error when the file cannot be
 *  written. */
void writeTum(const std::string& path, const Trajectory2D& traj);

/** Reads a TUM file; 3D poses are projected to the plane (yaw of the
 *  rotation). Blank lines and '#' comments are skipped. Throws InputError
 *  naming the file and line of any malformed line, and for a missing or
 *  empty file. Poses are returned in time order: real logs have timestamps
 *  that step back (the Intel CARMEN log does, 4 times), so such files are
 *  sorted (stable), and `reordered`, when given, receives how many poses
 *  were out of order. */
Trajectory2D readTum(const std::string& path, size_t* reordered = nullptr);

}  // namespace carenav::io
