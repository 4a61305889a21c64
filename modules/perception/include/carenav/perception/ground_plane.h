// Ground-plane detection: RRT-GPD ([Garrote17, Alg. 1]; docs/design.md, 'Ground plane') and the
// RANSAC-only baseline.
#pragma once

#include <carenav/perception/elevation_grid.h>
#include <carenav/perception/perception_params.h>

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <random>
#include <vector>

namespace carenav::perception {

/** a x + b y + c z + d = 0 with (a, b, c) a unit normal and c >= 0 (up). */
struct Plane {
  double a = 0, b = 0, c = 1, d = 0;
  Eigen::Vector3d normal() const { return {a, b, c}; }
  double signedDistance(double x, double y, double z) const { return a * x + b * y + c * z + d; }
  double distance(double x, double y, double z) const { return std::abs(signedDistance(x, y, z)); }
  /** Elevation of the plane at (x, y); nullopt for (near-)vertical planes. */
  std::optional<double> zAt(double x, double y) const;
  /** Plane through `p` with normal `n` (normalised and turned up). */
  static Plane fromPointNormal(const Eigen::Vector3d& p, Eigen::Vector3d n);
};

/** Total least-squares plane (smallest principal axis). nullopt when there
 *  are fewer than 3 points or they are (nearly) collinear. */
std::optional<Plane> fitPlane(const std::vector<Eigen::Vector3d>& pts);

struct RansacResult {
  std::optional<Plane> plane;
  size_t inliers = 0;
};
/** RANSAC plane (3-point hypotheses, `threshold` inlier distance), refined
 *  by least squares on the inliers of the best hypothesis. */
RansacResult ransacPlane(const std::vector<Eigen::Vector3d>& pts, int iterations, double threshold,
                         std::mt19937& rng);

/** One RRT node: centre (x, y, z), local plane normal, parent index (-1: root). */
struct RrtNode {
  Eigen::Vector3d p;
  Eigen::Vector3d n;
  int parent = -1;
};

struct GroundPlaneResult {
  std::optional<Plane> plane;  ///< robot frame, normal up; nullopt: no ground found
  std::vector<RrtNode> nodes;  ///< the tree (RRT-GPD only)
  bool seed_found = false;
  int iterations = 0;           ///< RRT iterations run
  int expansions_rejected = 0;  ///< candidate nodes that failed both tests
  size_t ransac_inliers = 0;
  int trees_grown = 0;       ///< RRT-GPD: trees grown (one per seed tried)
  int trees_refused = 0;     ///< RRT-GPD: trees smaller than min_tree_nodes, never a plane
  double prior_offset = 0;   ///< RRT-GPD: plane height at the robot (x = y = 0), m
  bool wide_search = false;  ///< RRT-GPD: plane from a seed beyond seed_max_elevation
};

/** Local plane of the s x s neighbourhood centred on robot-frame (x, y): one
 *  point per cell (cell mean, or IDW from the window when the cell is empty);
 *  least squares (fitPlane). */
std::optional<Plane> localPlane(const ElevationGrid& g, double x, double y, int s);

/** RRT-GPD, [Garrote17, Alg. 1] with the decisions of docs/design.md, 'Ground plane'. Deterministic
 * for a given params.seed. A tree smaller than min_tree_nodes never gives the plane; among the
 * planes of the accepted trees the one nearest to the robot's floor (z = 0 at the robot) wins.
 * No plane (nullopt) when every tree was refused or no seed exists: the caller falls back to the
 * nominal plane. */
GroundPlaneResult detectGroundRrt(const ElevationGrid& g, const PerceptionParams& p);

/** Baseline: RANSAC over the points themselves (what a PCL SACSegmentation
 *  user runs), on a seeded subsample of at most `max_points` points; no
 *  orientation prior. */
GroundPlaneResult detectGroundRansac(const Cloud& robot_frame, const PerceptionParams& p,
                                     size_t max_points = 20000);

}  // namespace carenav::perception
