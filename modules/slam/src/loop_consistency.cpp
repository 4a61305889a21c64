#include <carenav/slam/loop_consistency.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace carenav::slam {

using mrpt::math::CMatrixDouble33;
using mrpt::poses::CPose2D;

PoseGaussian::PoseGaussian() { cov.setZero(); }

PoseGaussian::PoseGaussian(const CPose2D& m, const CMatrixDouble33& c) : mean(m), cov(c) {}

PoseGaussian compose(const PoseGaussian& a, const PoseGaussian& b) {
  // Jacobians of a (+) b with respect to a and b (2D pose composition).
  const double c = std::cos(a.mean.phi()), s = std::sin(a.mean.phi());
  const double bx = b.mean.x(), by = b.mean.y();
  CMatrixDouble33 ja, jb;
  ja.setIdentity();
  ja(0, 2) = -s * bx - c * by;
  ja(1, 2) = c * bx - s * by;
  jb.setZero();
  jb(0, 0) = c;
  jb(0, 1) = -s;
  jb(1, 0) = s;
  jb(1, 1) = c;
  jb(2, 2) = 1;
  PoseGaussian r;
  r.mean = a.mean + b.mean;
  r.cov = CMatrixDouble33(ja.asEigen() * a.cov.asEigen() * ja.asEigen().transpose() +
                          jb.asEigen() * b.cov.asEigen() * jb.asEigen().transpose());
  return r;
}

PoseGaussian inverse(const PoseGaussian& a) {
  const double c = std::cos(a.mean.phi()), s = std::sin(a.mean.phi());
  const double x = a.mean.x(), y = a.mean.y();
  // (x, y, t)^-1 = (-c x - s y, s x - c y, -t)
  CMatrixDouble33 j;
  j.setZero();
  j(0, 0) = -c;
  j(0, 1) = -s;
  j(0, 2) = s * x - c * y;
  j(1, 0) = s;
  j(1, 1) = -c;
  j(1, 2) = c * x + s * y;
  j(2, 2) = -1;
  PoseGaussian r;
  r.mean = -a.mean;
  r.cov = CMatrixDouble33(j.asEigen() * a.cov.asEigen() * j.asEigen().transpose());
  return r;
}

PoseGaussian OdometryChain::between(size_t a, size_t b) const {
  if (b < a) return inverse(between(b, a));
  PoseGaussian r;
  for (size_t i = a; i < b && i < steps_.size(); ++i) r = compose(r, steps_[i]);
  return r;
}

double pairwiseChi2(const OdometryChain& chain, const LoopMeasurement& c1,
                    const LoopMeasurement& c2) {
  // c2 predicted from c1: chain c2.from -> c1.from, c1, chain c1.to -> c2.to.
  const PoseGaussian pred =
      compose(compose(chain.between(c2.from, c1.from), c1.z), chain.between(c1.to, c2.to));
  // Error of the cycle pred^-1 (+) z2 (identity when they agree).
  const PoseGaussian err = compose(inverse(pred), c2.z);
  Eigen::Vector3d e(err.mean.x(), err.mean.y(), err.mean.phi());
  Eigen::Matrix3d cov = err.cov.asEigen();
  cov += 1e-9 * Eigen::Matrix3d::Identity();
  return e.dot(cov.ldlt().solve(e));
}

namespace {

struct CliqueSearch {
  const std::vector<std::vector<char>>& adj;
  std::vector<size_t> best, current;
  size_t expansions = 0;
  static constexpr size_t kMaxExpansions = 200000;  // then the best found so far

  void expand(std::vector<size_t>& cand) {
    if (cand.empty()) {
      if (current.size() > best.size()) best = current;
      return;
    }
    while (!cand.empty()) {
      if (current.size() + cand.size() <= best.size()) return;
      if (++expansions > kMaxExpansions) return;
      const size_t v = cand.front();
      cand.erase(cand.begin());
      std::vector<size_t> next;
      for (size_t u : cand)
        if (adj[v][u]) next.push_back(u);
      current.push_back(v);
      expand(next);
      current.pop_back();
    }
    if (current.size() > best.size()) best = current;
  }
};

}  // namespace

std::vector<size_t> maximumClique(const std::vector<std::vector<char>>& adj) {
  const size_t n = adj.size();
  // Most connected vertices first: the first branch is then usually the
  // answer and the bound prunes the rest.
  std::vector<size_t> order(n);
  std::vector<size_t> degree(n, 0);
  for (size_t i = 0; i < n; ++i) {
    order[i] = i;
    for (size_t j = 0; j < n; ++j) degree[i] += (i != j && adj[i][j]);
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return degree[a] > degree[b]; });
  CliqueSearch s{adj, {}, {}, 0};
  s.expand(order);
  std::sort(s.best.begin(), s.best.end());
  return s.best;
}

std::vector<size_t> largestConsistentSet(const OdometryChain& chain,
                                         const std::vector<LoopMeasurement>& loops, double gate) {
  const size_t n = loops.size();
  std::vector<std::vector<char>> adj(n, std::vector<char>(n, 0));
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j)
      adj[i][j] = adj[j][i] = pairwiseChi2(chain, loops[i], loops[j]) <= gate;
  return maximumClique(adj);
}

}  // namespace carenav::slam
