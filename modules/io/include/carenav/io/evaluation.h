// Trajectory accuracy: association by timestamp, SE(2) alignment, absolute
// trajectory error (ATE), relative pose error (RPE) and the relations metric of
// Kümmerle et al. 2009. Pure functions on Trajectory2D; docs/eval.md has
// the formulas.
#pragma once

#include <carenav/io/trajectory.h>
#include <mrpt/math/TPose2D.h>

#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace carenav::io {

/** How estimated poses are paired with reference poses.
 *  Default (nearest): an estimated pose and a reference pose match when each
 *  is the other's nearest in time and they are at most `max_dt` apart, so a
 *  pose is used at most once (as TUM's associate.py does).
 *  With `interpolate`: every estimated pose whose time falls between two
 *  reference poses at most `max_gap` apart gets the reference pose linearly
 *  interpolated at its time (yaw along the shorter arc); outside such gaps the
 *  nearest rule applies. Use it when the reference is sampled at other times
 *  than the estimate (e.g. motion capture at 100 Hz, SLAM at 10 Hz). */
struct AssociationParams {
  double max_dt = 0.02;      ///< s, largest time difference of a nearest match
  bool interpolate = false;  ///< interpolate the reference between neighbours
  double max_gap = 0.5;      ///< s, longest reference gap to interpolate across
  /** Pair the k-th estimated pose with the k-th reference pose, times
   *  ignored (both must have the same number of poses): for logs whose
   *  timestamps repeat, e.g. one pose per scan of a log stamped in whole
   *  seconds or not at all. */
  bool by_index = false;
};

/** Matched pairs: est[k] and ref[k] describe the same instant (est's time). */
struct Association {
  Trajectory2D est, ref;
  std::vector<size_t> est_index;  ///< index of each pair in the input estimate
  size_t est_total = 0, ref_total = 0;
  size_t interpolated = 0;  ///< pairs whose reference pose was interpolated
  size_t size() const { return est.size(); }
};

/** Pairs the poses of two trajectories by time. Throws InputError when fewer
 *  than 2 pairs match, saying the timestamps do not overlap and giving both
 *  time ranges; both trajectories must be sorted by time (readTum checks it). */
Association associate(const Trajectory2D& est, const Trajectory2D& ref,
                      const AssociationParams& p = {});

/** The pose of `traj` at time t under the same rules as associate() (nearest
 *  within max_dt, or interpolated), or nothing when there is none. */
std::optional<TimedPose2D> poseAt(const Trajectory2D& traj, double t,
                                  const AssociationParams& p = {});

/** Summary of a set of non-negative errors. All fields are NaN when n == 0
 *  (JSON null). std is the population standard deviation. */
struct ErrorStats {
  static constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
  size_t n = 0;
  double rmse = kNone, mean = kNone, median = kNone, std = kNone, min = kNone, max = kNone;
  static ErrorStats of(std::vector<double> values);
};

/** The rigid transform T = (x, y, yaw) minimising sum_k |T ⊕ est_k - ref_k|²
 *  over the positions of the pairs (Horn/Umeyama in 2D, no scale): centroids,
 *  then the rotation from the 2x2 cross-covariance in closed form.
 *  Needs est.size() == ref.size(); with fewer than 2 pairs or coincident
 *  positions the rotation is undetermined and 0 is returned for it. */
mrpt::math::TPose2D alignSE2(const Trajectory2D& est, const Trajectory2D& ref);

/** T ⊕ p for every pose (positions rotated and shifted, yaw + T.phi). */
Trajectory2D transformTrajectory(const Trajectory2D& traj, const mrpt::math::TPose2D& T);

/** Absolute trajectory error (Sturm et al. 2012) of an association. */
struct AteResult {
  bool aligned = true;
  mrpt::math::TPose2D alignment;     ///< applied to the estimate (identity without alignment)
  ErrorStats translation;            ///< m, |ref_k - T ⊕ est_k| (positions)
  ErrorStats rotation;               ///< deg, |yaw_ref - yaw_est - T.phi| wrapped to [0, 180]
  std::vector<double> trans_errors;  ///< m, per pair
  std::vector<double> rot_errors;    ///< deg, per pair
  Trajectory2D est_aligned;          ///< the estimate's matched poses after T
};
AteResult computeAte(const Association& a, bool align = true);

/** Relative pose error (Sturm et al. 2012) over a travelled distance: for each
 *  pair i, j is the first later pair where the reference path length from i
 *  reaches `distance`; the error is E = (ref_i⁻¹ ref_j)⁻¹ (est_i⁻¹ est_j).
 *  distance <= 0 means consecutive pairs (j = i + 1). Independent of any
 *  global alignment. */
struct RpeResult {
  double distance = 0;             ///< m, 0 for per-step
  ErrorStats translation;          ///< m, |trans(E)|
  ErrorStats rotation;             ///< deg, |rot(E)|
  double drift_percent = 0;        ///< mean of |trans(E)| / path length(i..j) * 100
  double rot_drift_deg_per_m = 0;  ///< mean of |rot(E)| / path length(i..j)
};
RpeResult computeRpe(const Association& a, double distance);

/** One line of a relations file: the reference relative pose from the pose
 *  at t1 to the pose at t2, in the frame of the pose at t1. */
struct Relation {
  double t1 = 0, t2 = 0;
  mrpt::math::TPose2D delta;  ///< x, y (m), phi (rad): the yaw of the file's roll/pitch/yaw
  int line = 0;               ///< line in the file (0 when generated)
};

/** Reads a relations file as used with the Freiburg SLAM benchmark: one
 *  relation per line, `t1 t2 x y z roll pitch yaw` (s, m, rad); blank lines
 *  and '#' comments are skipped; z, roll and pitch are read and ignored (2D).
 *  Throws InputError naming the file and line of any malformed line, and for a
 *  missing or empty file. */
std::vector<Relation> readRelations(const std::string& path);

/** Writes relations in the same format (z = roll = pitch = 0), atomically.
 *  Throws std::runtime_error when the file cannot be written. */
void writeRelations(const std::string& path, const std::vector<Relation>& rels);

/** Relations from a reference trajectory: from every pose i to the first pose
 *  j where the path length from i reaches `distance` (m). */
std::vector<Relation> makeRelations(const Trajectory2D& ref, double distance);

/** The metric of Kümmerle et al. 2009 ("On measuring the accuracy of SLAM
 *  algorithms", Autonomous Robots 27(4)): for each relation whose two times
 *  both have an estimated pose (poseAt), E = δ*⁻¹ δ with δ = est(t1)⁻¹ est(t2)
 *  and δ* the relation; statistics of |trans(E)|, |trans(E)|², |rot(E)| and
 *  |rot(E)|², translation and rotation kept apart as in the paper. */
struct RelationsResult {
  size_t total = 0, used = 0;  ///< relations in the file, relations with both poses
  ErrorStats translation;      ///< m
  ErrorStats translation_sq;   ///< m²
  ErrorStats rotation;         ///< deg
  ErrorStats rotation_sq;      ///< deg²
};
/** Throws InputError when no relation has both poses in the estimate. */
RelationsResult computeRelationsError(const Trajectory2D& est, const std::vector<Relation>& rels,
                                      const AssociationParams& p = {});

/** Angle wrapped to (-pi, pi]. */
double wrapAngle(double a);

}  // namespace carenav::io
