// Pose-graph optimisation that wrong loop closures cannot wreck: the loop
// edges are weighted by Dynamic Covariance Scaling (Agarwal, Tipaldi,
// Spinello, Stachniss, Burgard, "Robust map optimization using dynamic
// covariance scaling", ICRA 2013) in iteratively reweighted least squares
// around MRPT's sparse Levenberg-Marquardt, then the closures the robust
// solution still disagrees with are dropped and the graph solved again.
#pragma once

#include <mrpt/graphs/CNetworkOfPoses.h>

#include <cstddef>
#include <set>
#include <utility>
#include <vector>

namespace carenav::slam {

struct RobustGraphOptions {
  /** Dynamic covariance scaling on the loop edges; false: plain least
   *  squares (every closure at full weight), then the pruning below. */
  bool robust = true;
  /** DCS's Phi: a closure whose squared Mahalanobis residual chi2 (with its
   *  own information) exceeds Phi gets its information scaled by
   *  s^2 = (2 Phi / (Phi + chi2))^2 < 1. */
  double phi = 1.0;
  int reweight_rounds = 8;  ///< IRLS rounds at most (stops when weights settle)
  int prune_rounds = 3;     ///< drop-and-solve-again rounds at most
  double prune_xy = 0.3;    ///< m, a closure with a larger residual is dropped
  double prune_deg = 5;     ///< deg
  int lm_iterations = 100;  ///< Levenberg-Marquardt iterations per solve
};

struct RobustGraphResult {
  size_t solves = 0;  ///< Levenberg-Marquardt runs
  /** Loop edges dropped (removed from the graph and from `loops`). */
  std::vector<std::pair<size_t, size_t>> rejected;
  /** DCS weight s of each remaining loop edge (order of `loops`) at the end. */
  std::vector<double> weights;
};

/** Optimises the poses of `free` nodes of `graph`; `loops` lists the (from,
 *  to) pairs of its loop-closure edges (every other edge is trusted as it
 *  is). Every solve starts from the poses the graph has on entry. Loop edges
 *  whose residual after the robust solution exceeds prune_xy or prune_deg are
 *  erased from the graph and from `loops`, and the graph is solved again. */
RobustGraphResult optimiseRobust(mrpt::graphs::CNetworkOfPoses2DInf& graph,
                                 std::vector<std::pair<size_t, size_t>>& loops,
                                 const std::set<mrpt::graphs::TNodeID>& free,
                                 const RobustGraphOptions& opt);

/** Squared Mahalanobis residual of an edge (from -> to, measured `z` with
 *  information `info`) at the poses of the graph. */
double edgeChi2(const mrpt::graphs::CNetworkOfPoses2DInf& graph, size_t from, size_t to,
                const mrpt::poses::CPosePDFGaussianInf& z);

}  // namespace carenav::slam
