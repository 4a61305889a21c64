#include <carenav/slam/robust_graph.h>

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <cmath>
#include <map>

namespace carenav::slam {

namespace {

using mrpt::poses::CPose2D;
using Graph = mrpt::graphs::CNetworkOfPoses2DInf;

/** Residual of a measured relative pose at the graph's poses: the estimated
 *  relative pose seen from the measured one (x, y, yaw). */
mrpt::math::CVectorFixedDouble<3> residual(const Graph& g, size_t from, size_t to,
                                           const CPose2D& z) {
  const CPose2D est = g.nodes.at(to) - g.nodes.at(from);
  const CPose2D r = est - z;
  mrpt::math::CVectorFixedDouble<3> v;
  v[0] = r.x();
  v[1] = r.y();
  v[2] = r.phi();
  return v;
}

/** Weighted squared error of all edges at the graph's poses. */
double totalChi2(const Graph& g) {
  double c = 0;
  for (const auto& [ids, e] : g.edges) c += edgeChi2(g, ids.first, ids.second, e);
  return c;
}

/** Sparse Levenberg-Marquardt over the free nodes: minimises the sum of the
 *  edges' squared Mahalanobis errors e^T Omega e, with e = t2v(Z^-1 (Xi^-1
 *  Xj)) and the Jacobians of Grisetti, Kuemmerle, Stachniss, Burgard, "A
 *  tutorial on graph-based SLAM", IEEE ITS Magazine 2010, sec. IV-A. MRPT's
 *  optimize_graph_spa_levmarq accepts a step when the *unweighted* sum of
 *  squared errors drops, so it ignores a change of the information matrices
 *  (the reweighting below would have no effect). */
void solveLevenbergMarquardt(Graph& g, const std::set<mrpt::graphs::TNodeID>& free,
                             int max_iterations) {
  std::map<mrpt::graphs::TNodeID, int> index;
  for (auto id : free)
    if (g.nodes.count(id)) index.emplace(id, static_cast<int>(index.size()));
  const int n = 3 * static_cast<int>(index.size());
  if (n == 0) return;
  double lambda = 1e-4, chi2 = totalChi2(g);
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver;
  for (int it = 0; it < max_iterations; ++it) {
    std::vector<Eigen::Triplet<double>> trip;
    Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
    for (const auto& [ids, e] : g.edges) {
      const auto ii = index.find(ids.first), jj = index.find(ids.second);
      if (ii == index.end() && jj == index.end()) continue;
      const CPose2D& xi = g.nodes.at(ids.first);
      const CPose2D& xj = g.nodes.at(ids.second);
      const auto r = residual(g, ids.first, ids.second, e.mean);
      const Eigen::Vector3d err(r[0], r[1], r[2]);
      const double ci = std::cos(xi.phi()), si = std::sin(xi.phi());
      const double cz = std::cos(e.mean.phi()), sz = std::sin(e.mean.phi());
      Eigen::Matrix2d Ri, Rz, dRi;
      Ri << ci, -si, si, ci;
      Rz << cz, -sz, sz, cz;
      dRi << -si, ci, -ci, -si;  // d(Ri^T)/d theta_i
      const Eigen::Vector2d dt(xj.x() - xi.x(), xj.y() - xi.y());
      Eigen::Matrix3d A = Eigen::Matrix3d::Zero(), B = Eigen::Matrix3d::Zero();
      A.block<2, 2>(0, 0) = -Rz.transpose() * Ri.transpose();
      A.block<2, 1>(0, 2) = Rz.transpose() * dRi * dt;
      A(2, 2) = -1;
      B.block<2, 2>(0, 0) = Rz.transpose() * Ri.transpose();
      B(2, 2) = 1;
      const Eigen::Matrix3d W = e.cov_inv.asEigen();
      auto add = [&](int r0, int c0, const Eigen::Matrix3d& m) {
        for (int a = 0; a < 3; ++a)
          for (int c = 0; c < 3; ++c)
            if (m(a, c) != 0) trip.emplace_back(r0 + a, c0 + c, m(a, c));
      };
      if (ii != index.end()) {
        const int a = 3 * ii->second;
        add(a, a, A.transpose() * W * A);
        b.segment<3>(a) += A.transpose() * W * err;
      }
      if (jj != index.end()) {
        const int c = 3 * jj->second;
        add(c, c, B.transpose() * W * B);
        b.segment<3>(c) += B.transpose() * W * err;
      }
      if (ii != index.end() && jj != index.end()) {
        const int a = 3 * ii->second, c = 3 * jj->second;
        add(a, c, A.transpose() * W * B);
        add(c, a, B.transpose() * W * A);
      }
    }
    Eigen::SparseMatrix<double> H(n, n);
    H.setFromTriplets(trip.begin(), trip.end());
    bool improved = false;
    for (int tries = 0; tries < 10 && !improved; ++tries) {
      Eigen::SparseMatrix<double> Hl = H;
      for (int d = 0; d < n; ++d) Hl.coeffRef(d, d) += lambda * (1 + H.coeff(d, d));
      solver.compute(Hl);
      if (solver.info() != Eigen::Success) {
        lambda *= 10;
        continue;
      }
      const Eigen::VectorXd dx = solver.solve(-b);
      const auto saved = g.nodes;
      for (const auto& [id, k] : index) {
        CPose2D& p = g.nodes[id];
        p = CPose2D(p.x() + dx[3 * k], p.y() + dx[3 * k + 1], p.phi() + dx[3 * k + 2]);
      }
      const double c = totalChi2(g);
      if (c < chi2) {
        improved = true;
        const double gain = chi2 - c;
        chi2 = c;
        lambda = std::max(1e-9, lambda / 10);
        if (gain < 1e-6 * (1 + chi2) || dx.lpNorm<Eigen::Infinity>() < 1e-7) return;
      } else {
        g.nodes = saved;
        lambda *= 10;
      }
    }
    if (!improved) return;
  }
}

}  // namespace

double edgeChi2(const Graph& graph, size_t from, size_t to,
                const mrpt::poses::CPosePDFGaussianInf& z) {
  const auto r = residual(graph, from, to, z.mean);
  double c = 0;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) c += r[a] * z.cov_inv(a, b) * r[b];
  return c;
}

RobustGraphResult optimiseRobust(Graph& graph, std::vector<std::pair<size_t, size_t>>& loops,
                                 const std::set<mrpt::graphs::TNodeID>& free,
                                 const RobustGraphOptions& opt) {
  RobustGraphResult res;
  if (free.empty()) return res;
  const auto start = graph.nodes;
  auto solve = [&] {
    solveLevenbergMarquardt(graph, free, opt.lm_iterations);
    ++res.solves;
  };
  // One robust solution from the starting poses; returns the loop edges
  // with their DCS weights.
  using EdgeIt = Graph::edges_map_t::iterator;
  auto robustSolve = [&](std::vector<std::pair<EdgeIt, double>>& out) {
    graph.nodes = start;
    // The loop edges and their own information, to scale and restore.
    std::vector<std::pair<EdgeIt, mrpt::math::CMatrixDouble33>> edges;
    // Each pair once: equal_range already yields every edge of a pair, and
    // an edge listed twice would be erased twice below.
    const std::set<std::pair<size_t, size_t>> pairs(loops.begin(), loops.end());
    for (const auto& [j, k] : pairs) {
      auto range = graph.edges.equal_range({j, k});
      for (auto e = range.first; e != range.second; ++e) edges.emplace_back(e, e->second.cov_inv);
    }
    std::vector<double> s(edges.size(), 1.0);
    solve();  // least squares, every closure at full weight
    if (opt.robust) {
      // IRLS with the DCS scaling: s = min(1, 2 Phi / (Phi + chi2)), chi2
      // evaluated with the edge's own information at the current solution,
      // and the information scaled by s^2 (Agarwal et al. 2013, sec. III,
      // the closed form of the switch variable of Suenderhauf and Protzel's
      // switchable constraints, IROS 2012). The first solve above gives every
      // closure its say, so closures that agree with the majority end near
      // their solution and keep full weight while a wrong one is left with a
      // large chi2 and loses it.
      for (int it = 0; it < opt.reweight_rounds; ++it) {
        double change = 0;
        for (size_t i = 0; i < edges.size(); ++i) {
          auto& [e, info0] = edges[i];
          e->second.cov_inv = info0;
          const double chi2 = edgeChi2(graph, e->first.first, e->first.second, e->second);
          const double si = std::min(1.0, 2 * opt.phi / (opt.phi + chi2));
          change = std::max(change, std::abs(si - s[i]));
          s[i] = si;
          e->second.cov_inv = info0;
          e->second.cov_inv *= si * si;
        }
        if (change < 0.01 && it > 0) break;
        solve();
      }
      for (auto& [e, info0] : edges) e->second.cov_inv = info0;
    }
    out.clear();
    for (size_t i = 0; i < edges.size(); ++i) out.emplace_back(edges[i].first, s[i]);
  };
  std::vector<std::pair<EdgeIt, double>> edges;
  const int rounds = std::max(1, opt.prune_rounds);
  for (int round = 0; round < rounds; ++round) {
    robustSolve(edges);
    // Drop the closures the solution disagrees with.
    bool removed = false;
    std::vector<std::pair<size_t, size_t>> kept;
    res.weights.clear();
    for (const auto& [e, w] : edges) {
      const size_t j = e->first.first, k = e->first.second;
      const CPose2D r = (graph.nodes.at(k) - graph.nodes.at(j)) - e->second.mean;
      if (r.norm() > opt.prune_xy || std::abs(r.phi()) > opt.prune_deg * M_PI / 180) {
        graph.edges.erase(e);
        res.rejected.emplace_back(j, k);
        removed = true;
      } else {
        kept.emplace_back(j, k);
        res.weights.push_back(w);
      }
    }
    loops = kept;
    if (!removed) break;
    if (round + 1 == rounds) {
      // The last round dropped closures: solve once more without them.
      robustSolve(edges);
      res.weights.clear();
      for (const auto& ew : edges) res.weights.push_back(ew.second);
    }
  }
  return res;
}

}  // namespace carenav::slam
