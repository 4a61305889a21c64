// Pairwise consistency of loop closures (loop_consistency.h) on a simulated
// pose graph with exact truth: two laps of a square, odometry with a heading
// bias, right closures between the laps and wrong ones (look-alike places
// 1.5-2.5 m away), some of them agreeing with each other (the same
// look-alike matched from consecutive poses). Plain least squares with all
// closures is bent by the wrong ones even after pruning the worst residuals;
// the largest pairwise-consistent set holds exactly the right closures, and
// the graph optimised with it stays near the truth.
#include <carenav/slam/loop_consistency.h>
#include <carenav/slam/robust_graph.h>
#include <Eigen/Dense>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "square_laps.h"

using namespace carenav::slam;
using mrpt::poses::CPose2D;
using Graph = mrpt::graphs::CNetworkOfPoses2DInf;

namespace {

using test::diag;
using test::edge;
using test::kDeg;

struct Scenario {
  Graph graph;
  OdometryChain chain;
  std::vector<CPose2D> truth;
  std::vector<LoopMeasurement> loops;
  std::vector<bool> right;  // per loop
};

void addLoop(Scenario& s, size_t j, size_t i, const CPose2D& z, double sxy, double sth,
             bool right) {
  s.graph.insertEdge(j, i, edge(z, sxy, sth));
  s.loops.push_back({j, i, PoseGaussian(z, diag(sxy, sth))});
  s.right.push_back(right);
}

/** Two laps of a 10 x 10 m square, a pose every 0.5 m (80 per lap); the
 *  wrong closures come in groups of `group` consecutive poses that all take
 *  the same look-alike place (so each group is self-consistent). */
Scenario makeScenario(size_t n_groups, size_t group, unsigned seed) {
  Scenario s;
  const size_t lap = test::SquareLaps::kLap;
  std::mt19937 rng(seed);
  std::normal_distribution<double> nxy(0, 0.01), nth(0, 0.2 * kDeg);
  const test::SquareLaps laps = test::squareLaps(rng, nxy, nth);
  s.truth = laps.truth;
  CPose2D p = s.truth[0];
  s.graph.nodes[0] = p;
  for (size_t i = 1; i < s.truth.size(); ++i) {
    const CPose2D& z = laps.odometry[i];
    s.graph.insertEdge(i - 1, i, edge(z, 0.03, 1 * kDeg));
    s.chain.add(PoseGaussian(z, diag(0.03, 1 * kDeg)));
    p = p + z;
    s.graph.nodes[i] = p;
  }
  for (size_t i = lap; i < 2 * lap; i += 4) {
    const CPose2D t = s.truth[i] - s.truth[i - lap];
    const double dy = nxy(rng), dx = nxy(rng);  // gcc's order, fixed (see square_laps.h)
    addLoop(s, i - lap, i, CPose2D(t.x() + dx, t.y() + dy, t.phi()), 0.05, 1 * kDeg, true);
  }
  std::uniform_int_distribution<size_t> pick(lap + 2, 2 * lap - 1 - group);
  std::uniform_real_distribution<double> off(1.5, 2.5), ang(-180, 180), dth(-8, 8);
  for (size_t w = 0; w < n_groups; ++w) {
    const size_t i0 = pick(rng);
    // The look-alike: the true place of the old pose moved by `shift`.
    const double r = off(rng), a = ang(rng) * kDeg, th = dth(rng) * kDeg;
    const CPose2D shift(r * std::cos(a), r * std::sin(a), th);
    for (size_t g = 0; g < group; ++g) {
      const size_t i = i0 + g, j = i - lap + 1;  // not a pair the right ones use
      const CPose2D t = s.truth[i] - (s.truth[j] + shift);
      addLoop(s, j, i, t, 0.01, 0.2 * kDeg, false);
    }
  }
  return s;
}

double rmse(const Graph& g, const std::vector<CPose2D>& truth) {
  double sum = 0;
  for (size_t i = 0; i < truth.size(); ++i) {
    const CPose2D d = g.nodes.at(i) - truth[i];
    sum += d.x() * d.x() + d.y() * d.y();
  }
  return std::sqrt(sum / truth.size());
}

std::set<mrpt::graphs::TNodeID> freeNodes(const Graph& g) {
  std::set<mrpt::graphs::TNodeID> f;
  for (const auto& [id, p] : g.nodes)
    if (id != g.root) f.insert(id);
  return f;
}

std::vector<std::pair<size_t, size_t>> pairs(const std::vector<LoopMeasurement>& l) {
  std::vector<std::pair<size_t, size_t>> v;
  for (const auto& m : l) v.emplace_back(m.from, m.to);
  return v;
}

constexpr double kGate = 11.34;  // chi-square, 3 degrees of freedom, 99 %

}  // namespace

TEST(SlamLoopConsistency, ComposeAndInverse) {
  const PoseGaussian a(CPose2D(1, 2, 0.5), diag(0.1, 0.05));
  const PoseGaussian b(CPose2D(-0.5, 0.3, -0.2), diag(0.2, 0.1));
  const PoseGaussian ab = compose(a, b);
  const CPose2D m = a.mean + b.mean;
  EXPECT_NEAR(ab.mean.x(), m.x(), 1e-12);
  EXPECT_NEAR(ab.mean.phi(), m.phi(), 1e-12);
  // Headings add: their variances add.
  EXPECT_NEAR(ab.cov(2, 2), 0.05 * 0.05 + 0.1 * 0.1, 1e-12);
  // a's heading uncertainty swings b's position: the x-y spread grows.
  EXPECT_GT(ab.cov(0, 0) + ab.cov(1, 1), 2 * (0.1 * 0.1 + 0.2 * 0.2));
  const PoseGaussian aa = inverse(inverse(a));
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(aa.cov(r, c), a.cov(r, c), 1e-12);
  const PoseGaussian id = compose(a, inverse(a));
  EXPECT_NEAR(id.mean.norm(), 0, 1e-12);
}

TEST(SlamLoopConsistency, ChainBetweenNodes) {
  OdometryChain c;
  for (int i = 0; i < 4; ++i) c.add(PoseGaussian(CPose2D(1, 0, M_PI / 2), diag(0.01, 0.01)));
  const PoseGaussian around = c.between(0, 4);  // a unit square: back at the start
  EXPECT_NEAR(around.mean.norm(), 0, 1e-9);
  const PoseGaussian back = c.between(3, 1);
  const PoseGaussian fwd = c.between(1, 3);
  EXPECT_NEAR((back.mean + fwd.mean).norm(), 0, 1e-9);
  EXPECT_GT(c.between(0, 4).cov(0, 0), c.between(0, 1).cov(0, 0));
}

TEST(SlamLoopConsistency, MaximumClique) {
  // Two cliques {0,1,2,3} and {4,5,6} with a few cross edges.
  std::vector<std::vector<char>> adj(7, std::vector<char>(7, 0));
  auto link = [&](size_t a, size_t b) { adj[a][b] = adj[b][a] = 1; };
  for (size_t a = 0; a < 4; ++a)
    for (size_t b = a + 1; b < 4; ++b) link(a, b);
  for (size_t a = 4; a < 7; ++a)
    for (size_t b = a + 1; b < 7; ++b) link(a, b);
  link(4, 0);
  link(5, 0);
  link(6, 1);
  EXPECT_EQ(maximumClique(adj), (std::vector<size_t>{0, 1, 2, 3}));
  adj[1][3] = adj[3][1] = 0;  // {0,1,2} and {0,2,3} are left: 3
  link(6, 0);                 // {0,4,5,6}: 4
  EXPECT_EQ(maximumClique(adj), (std::vector<size_t>{0, 4, 5, 6}));
}

TEST(SlamLoopConsistency, RightClosuresAgreeWrongOnesDoNot) {
  Scenario s = makeScenario(1, 1, 7);
  const auto& l = s.loops;
  const size_t wrong = l.size() - 1;
  // Right closures agree with each other (the odometry bias is the same on
  // both laps), in either order.
  size_t right_pairs = 0, right_agree = 0;
  for (size_t a = 0; a < wrong; ++a)
    for (size_t b = 0; b < wrong; ++b) {
      if (a == b) continue;
      ++right_pairs;
      right_agree += pairwiseChi2(s.chain, l[a], l[b]) <= kGate;
    }
  EXPECT_GE(right_agree, right_pairs * 95 / 100);
  // The wrong one disagrees with the right ones near it (a short odometry
  // chain between them pins the cycle down); far ones can agree by chance
  // (a lap of drift hides 2 m).
  size_t near = 0;
  for (size_t i = 0; i < wrong; ++i) {
    if (std::abs(static_cast<long>(l[i].to) - static_cast<long>(l[wrong].to)) > 12) continue;
    ++near;
    EXPECT_GT(pairwiseChi2(s.chain, l[i], l[wrong]), kGate) << l[i].from << "-" << l[i].to;
    EXPECT_GT(pairwiseChi2(s.chain, l[wrong], l[i]), kGate) << l[i].from << "-" << l[i].to;
  }
  EXPECT_GE(near, 5u);
}

TEST(SlamLoopConsistency, LargestConsistentSetKeepsTheRightClosures) {
  for (unsigned seed : {1u, 2u, 3u, 4u}) {
    // Four look-alike places, each matched from 3 consecutive poses.
    Scenario s = makeScenario(4, 3, seed);
    Graph plain = s.graph, checked = s.graph;
    auto lp = pairs(s.loops);
    RobustGraphOptions opt;
    opt.robust = false;  // least squares, then drop the worst residuals
    optimiseRobust(plain, lp, freeNodes(plain), opt);

    const auto keep = largestConsistentSet(s.chain, s.loops, kGate);
    size_t right_kept = 0;
    for (size_t i : keep) {
      EXPECT_TRUE(s.right[i]) << "seed " << seed << " wrong closure " << s.loops[i].from << "-"
                              << s.loops[i].to << " kept";
      right_kept += s.right[i];
    }
    EXPECT_GE(right_kept, 18u) << "seed " << seed;  // of 20
    // Only the kept closures go into the graph.
    for (size_t i = 0; i < s.loops.size(); ++i)
      if (std::find(keep.begin(), keep.end(), i) == keep.end())
        checked.edges.erase({s.loops[i].from, s.loops[i].to});
    std::vector<std::pair<size_t, size_t>> lc;
    for (size_t i : keep) lc.emplace_back(s.loops[i].from, s.loops[i].to);
    optimiseRobust(checked, lc, freeNodes(checked), opt);
    // The same with exactly the right closures, for reference.
    Graph ideal = s.graph;
    std::vector<std::pair<size_t, size_t>> li;
    for (size_t i = 0; i < s.loops.size(); ++i)
      if (s.right[i])
        li.emplace_back(s.loops[i].from, s.loops[i].to);
      else
        ideal.edges.erase({s.loops[i].from, s.loops[i].to});
    optimiseRobust(ideal, li, freeNodes(ideal), opt);
    const double e_plain = rmse(plain, s.truth), e_checked = rmse(checked, s.truth);
    const double e_ideal = rmse(ideal, s.truth);
    // As good as knowing which closures are right; all closures with the
    // pruning of large residuals are far worse (seeds 1-4: 0.46-2.1 m
    // against 0.17-0.31 m).
    EXPECT_LT(e_checked, e_ideal + 0.02) << "seed " << seed;
    EXPECT_GT(e_plain, 1.5 * e_checked + 0.1) << "seed " << seed << " plain " << e_plain;
  }
}
