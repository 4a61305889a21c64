// optimiseRobust (robust_graph.h) on a simulated pose graph with exact truth:
// a square loop of 80 poses driven twice, odometry edges with a heading bias
// (the chain drifts), correct loop closures between the laps and a few wrong
// ones injected (look-alike places 1.5-2.5 m away). With dynamic covariance
// scaling the optimised poses stay near the truth and the wrong closures are
// dropped; plain least squares with the same pruning is bent by them.
#include <carenav/slam/robust_graph.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "square_laps.h"

using namespace carenav::slam;
using mrpt::poses::CPose2D;
using Graph = mrpt::graphs::CNetworkOfPoses2DInf;

namespace {

using test::edge;
using test::kDeg;

struct Scenario {
  Graph graph;
  std::vector<CPose2D> truth;
  std::vector<std::pair<size_t, size_t>> loops, wrong;
};

/** Two laps of a 10 x 10 m square, a pose every 0.5 m (80 per lap). */
Scenario makeScenario(size_t n_wrong, unsigned seed) {
  Scenario s;
  const size_t lap = test::SquareLaps::kLap;
  std::mt19937 rng(seed);
  std::normal_distribution<double> nxy(0, 0.01), nth(0, 0.2 * kDeg);
  const test::SquareLaps laps = test::squareLaps(rng, nxy, nth);
  s.truth = laps.truth;
  CPose2D p = s.truth[0];
  s.graph.nodes[0] = p;
  for (size_t i = 1; i < s.truth.size(); ++i) {
    s.graph.insertEdge(i - 1, i, edge(laps.odometry[i], 0.03, 1 * kDeg));
    p = p + laps.odometry[i];
    s.graph.nodes[i] = p;
  }
  // Correct closures: the second lap against the first, every 4th pose.
  for (size_t i = lap; i < 2 * lap; i += 4) {
    const size_t j = i - lap;
    const CPose2D t = s.truth[i] - s.truth[j];
    // One draw per statement (argument order is the compiler's; gcc's kept).
    const double ny = nxy(rng), nx = nxy(rng);
    s.graph.insertEdge(j, i, edge(CPose2D(t.x() + nx, t.y() + ny, t.phi()), 0.05, 1 * kDeg));
    s.loops.emplace_back(j, i);
  }
  // Wrong closures: a place of the second lap taken for one of the first lap
  // 1.5-2.5 m from where it is, each more confident than a right one (a
  // look-alike that ICP matched tightly).
  std::uniform_int_distribution<size_t> pick(lap + 2, 2 * lap - 1);
  std::uniform_real_distribution<double> off(1.5, 2.5), ang(-8, 8);
  for (size_t w = 0; w < n_wrong; ++w) {
    const size_t i = pick(rng), j = i - lap + 1;  // not a pair the correct ones use
    const CPose2D t = s.truth[i] - s.truth[j];
    const double a = ang(rng) * kDeg * 20;
    const double dphi = ang(rng), oy = off(rng), ox = off(rng);  // gcc's order, fixed
    const CPose2D z(t.x() + ox * std::cos(a), t.y() + oy * std::sin(a), t.phi() + dphi * kDeg);
    s.graph.insertEdge(j, i, edge(z, 0.01, 0.2 * kDeg));
    s.loops.emplace_back(j, i);
    s.wrong.emplace_back(j, i);
  }
  return s;
}

/** RMS position error of the graph's poses against the truth (same start
 *  pose, fixed as the root: no alignment needed). */
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

}  // namespace

TEST(SlamRobustGraph, CorrectClosuresAloneCloseTheLoop) {
  Scenario s = makeScenario(0, 1);
  const double drift = rmse(s.graph, s.truth);
  auto loops = s.loops;
  RobustGraphOptions opt;
  const auto r = optimiseRobust(s.graph, loops, freeNodes(s.graph), opt);
  EXPECT_GT(drift, 1.0);  // the odometry alone is metres off
  EXPECT_LT(rmse(s.graph, s.truth), 0.2);
  EXPECT_TRUE(r.rejected.empty());
  EXPECT_EQ(loops.size(), s.loops.size());
  EXPECT_GE(r.solves, 2u);  // least squares, then at least one reweighted solve
  for (double w : r.weights) EXPECT_GT(w, 0.5);
}

TEST(SlamRobustGraph, WrongClosuresDoNotBendTheMap) {
  for (unsigned seed : {1u, 2u, 3u, 4u}) {
    Scenario robust = makeScenario(4, seed), plain = makeScenario(4, seed);
    auto lr = robust.loops, lp = plain.loops;
    RobustGraphOptions opt;
    const auto r = optimiseRobust(robust.graph, lr, freeNodes(robust.graph), opt);
    opt.robust = false;
    optimiseRobust(plain.graph, lp, freeNodes(plain.graph), opt);
    const double e_robust = rmse(robust.graph, robust.truth);
    const double e_plain = rmse(plain.graph, plain.truth);
    EXPECT_LT(e_robust, 0.5) << "seed " << seed;
    EXPECT_GT(e_plain, 1.8 * e_robust) << "seed " << seed << " plain " << e_plain;
    // Every wrong closure is dropped, and at most 3 of the 20 right ones.
    for (const auto& w : robust.wrong)
      EXPECT_NE(std::find(r.rejected.begin(), r.rejected.end(), w), r.rejected.end())
          << "seed " << seed << " wrong closure " << w.first << "-" << w.second << " kept";
    EXPECT_LE(r.rejected.size(), robust.wrong.size() + 3) << "seed " << seed;
    EXPECT_EQ(lr.size() + r.rejected.size(), robust.loops.size());
  }
}

TEST(SlamRobustGraph, Chi2OfAnEdge) {
  Graph g;
  g.nodes[0] = CPose2D(0, 0, 0);
  g.nodes[1] = CPose2D(1.1, 0, 0);
  const auto e = edge(CPose2D(1, 0, 0), 0.05, 1 * kDeg);
  EXPECT_NEAR(edgeChi2(g, 0, 1, e), (0.1 / 0.05) * (0.1 / 0.05), 1e-9);
}
