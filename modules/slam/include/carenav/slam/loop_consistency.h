// Pairwise consistency of loop closures ([Olson09]; [Mangelson18, Eqs. 6-7],
// docs/references.md): two closures i -> j and k -> l agree
// when the cycle "odometry a -> i, closure i -> j, odometry j -> l, closure
// l -> k reversed" predicts the second closure from the first within their
// joint uncertainty (squared Mahalanobis distance of the cycle error under a
// chi-square gate). A wrong closure (a look-alike place) seldom agrees with
// the right closures of the same revisit, nor with other wrong ones that
// point elsewhere; the closures kept are the largest mutually consistent set.
#pragma once

#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/poses/CPose2D.h>

#include <cstddef>
#include <vector>

namespace carenav::slam {

/** A relative pose with its covariance (x, y, yaw). */
struct PoseGaussian {
  mrpt::poses::CPose2D mean;
  mrpt::math::CMatrixDouble33 cov;  ///< zero on construction
  PoseGaussian();
  PoseGaussian(const mrpt::poses::CPose2D& m, const mrpt::math::CMatrixDouble33& c);
};

/** a (+) b with first-order covariance propagation (a and b independent). */
PoseGaussian compose(const PoseGaussian& a, const PoseGaussian& b);
/** The inverse pose with first-order covariance propagation. */
PoseGaussian inverse(const PoseGaussian& a);

/** The sequential (odometry) chain of a pose graph: step i goes from node
 *  i - 1 to node i. between(a, b) composes the steps from a to b (inverted
 *  when b < a). */
class OdometryChain {
 public:
  /** Appends the step from the last node to a new one. */
  void add(const PoseGaussian& step) { steps_.push_back(step); }
  size_t nodes() const { return steps_.size() + 1; }
  /** Node b in node a's frame, with covariance. */
  PoseGaussian between(size_t a, size_t b) const;

 private:
  std::vector<PoseGaussian> steps_;  // steps_[i] : node i -> node i + 1
};

/** A loop closure: node `to` measured in node `from`'s frame. */
struct LoopMeasurement {
  size_t from = 0, to = 0;
  PoseGaussian z;
};

/** Squared Mahalanobis distance of the cycle closure c1, chain c1.to ->
 *  c2.to, closure c2 reversed, chain c2.from -> c1.from: zero when the two
 *  closures agree exactly with the chain. */
double pairwiseChi2(const OdometryChain& chain, const LoopMeasurement& c1,
                    const LoopMeasurement& c2);

/** Indices of the largest set of closures that are pairwise consistent
 *  (pairwiseChi2 <= gate for every pair): the maximum clique of the
 *  consistency graph (exact branch and bound; Mangelson et al. 2018, sec.
 *  IV). Ties go to the set found first (earlier closures). */
std::vector<size_t> largestConsistentSet(const OdometryChain& chain,
                                         const std::vector<LoopMeasurement>& loops, double gate);

/** Maximum clique of an undirected graph given as an adjacency matrix
 *  (adj[i][j] != 0: i and j adjacent), sorted indices. */
std::vector<size_t> maximumClique(const std::vector<std::vector<char>>& adj);

}  // namespace carenav::slam
