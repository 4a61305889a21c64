// Brute-force correlative scan matching (after [Olson09csm],
// docs/references.md): scores every pose of a search window by how
// many scan points land near reference points, coarse then fine. Finds the
// right basin where ICP from a poor guess slides or turns into a wrong one
// (laser-only logs with metre-long steps between scans).
#pragma once

#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/poses/CPose2D.h>

#include <cmath>
#include <vector>

namespace carenav::slam {

class CorrelativeMatcher {
 public:
  struct Parameters {
    double cell = 0.05;          ///< m, lookup-table cell
    double sigma = 0.10;         ///< m, how far a point still counts as "near"
    double window_xy = 1.0;      ///< m, search half-width around the prior
    double window_yaw = 35;      ///< deg, search half-width around the prior
    double coarse_xy = 0.10;     ///< m, coarse step
    double coarse_yaw = 2;       ///< deg, coarse step
    size_t coarse_points = 120;  ///< scan points used by the coarse pass
    /** Share of a scan's points the reference is expected not to explain
     *  (parts of the view it never saw, people): the floor of a point's
     *  likelihood, so one unexplained point costs a bounded amount. */
    double outlier = 0.2;
    /** Share of the points that weigh as independent measurements
     *  (neighbouring beams err together), as in LineIcp. */
    double independence = 0.2;
    /** Standard deviations of the motion prior, a wheeled robot's
     *  ([Thrun05, Sec. 5.4]: it travels along its heading halfway through
     *  the turn): m along that direction (how much one step's travel may
     *  differ from the prediction), m across it (side slip, and the arc
     *  taken as a straight line), deg of heading. In corridors and halls
     *  many positions explain the scan alike, and the prior decides between
     *  them in the same units (log-likelihood); walls pin the heading nearly
     *  everywhere, so its prior is loose. */
    double prior_along = 0.5;
    double prior_across = 0.15;
    double prior_yaw = 30;
  };

  /** The motion prior from the last pose `from`: the travel `advance` (m)
   *  along the heading halfway between `from`'s and the new one, nothing
   *  across it, and a heading that is one of `yaws` (a max-mixture of
   *  Gaussians, [Olson13maxmix]: the closest component counts), e.g. the
   *  constant-velocity heading and the last one (a robot that stops
   *  turning). */
  struct Prior {
    mrpt::poses::CPose2D from;
    double advance = 0;
    std::vector<double> yaws;  ///< rad
    /** Around `p`: no travel, its heading. */
    static Prior at(const mrpt::poses::CPose2D& p) { return {p, 0.0, {p.phi()}}; }
  };

  /** A match: the pose of the posterior's mode in the window and the mean
   *  closeness of the scan points there (in [0, 1]: 1 = every point on a
   *  reference point). */
  struct Result {
    mrpt::poses::CPose2D pose;
    double closeness = 0;
  };

  explicit CorrelativeMatcher(const Parameters& p) : p_(p) {}
  const Parameters& parameters() const { return p_; }
  /** Builds the lookup table of the reference points (world frame). */
  void setReference(const mrpt::maps::CSimplePointsMap& ref);
  /** The pose of the scan (points in the robot frame) that maximises the
   *  posterior, the scan's log-likelihood in the lookup table plus the log
   *  of `prior`, over the windows around each pose of `centres`.
   *  `widen_xy`, `widen_yaw` > 1 multiply the window's half-widths (yaw at
   *  most 180 deg) and the prior's standard deviations (a prior that failed
   *  is worth less). */
  Result match(const mrpt::maps::CSimplePointsMap& scan,
               const std::vector<mrpt::poses::CPose2D>& centres, const Prior& prior,
               double widen_xy = 1, double widen_yaw = 1) const;
  /** match() around one prior; `score`: the mean closeness there. */
  mrpt::poses::CPose2D match(const mrpt::maps::CSimplePointsMap& scan,
                             const mrpt::poses::CPose2D& prior, double* score = nullptr,
                             double widen_xy = 1, double widen_yaw = 1) const;

 private:
  /** The log prior of a pose (up to a constant): minus half its squared
   *  Mahalanobis distance to the prior's travel and to its closest heading.
   *  `sa`, `sc`: m along and across the travel; `syaw`: rad. */
  static double logPrior(const Prior& prior, double x, double y, double yaw, double sa, double sc,
                         double syaw) {
    const double mid = travelDirection(prior, yaw);
    return logPriorXY(prior, x, y, std::cos(mid), std::sin(mid), sa, sc) +
           logPriorYaw(prior, yaw, syaw);
  }
  /** The heading halfway between the prior's and `yaw`. */
  static double travelDirection(const Prior& prior, double yaw) {
    return prior.from.phi() + 0.5 * std::remainder(yaw - prior.from.phi(), 2 * M_PI);
  }
  /** The position part, (c, s) the travel direction's unit vector. */
  static double logPriorXY(const Prior& prior, double x, double y, double c, double s, double sa,
                           double sc) {
    const double dx = x - prior.from.x(), dy = y - prior.from.y();
    const double along = (c * dx + s * dy - prior.advance) / sa;
    const double across = (-s * dx + c * dy) / sc;
    return -0.5 * (along * along + across * across);
  }
  static double logPriorYaw(const Prior& prior, double yaw, double syaw);
  /** Mean closeness of the scan at a pose (the table's log-likelihood
   *  ratios turned back into closeness). */
  double closeness(const std::vector<float>& xs, const std::vector<float>& ys, double x, double y,
                   double yaw) const;
  /** One search: the motion prior, its standard deviations (m, m, rad),
   *  the window's half-widths in coarse steps, and the weight of a point's
   *  log-likelihood ratio. */
  struct Search {
    const Prior& motion;
    double sa = 0, sc = 0, syaw = 0;
    int nxy = 0, nyaw = 0;
    double weight = 0;
  };
  /** The best pose of the coarse grid over the windows around `centres`
   *  (the scan's subset cx, cy). */
  mrpt::poses::CPose2D coarsePass(const Search& q, const std::vector<float>& cx,
                                  const std::vector<float>& cy,
                                  const std::vector<mrpt::poses::CPose2D>& centres) const;
  /** The best pose of the fine grid around `start` (all points). */
  Result finePass(const Search& q, const std::vector<float>& xs, const std::vector<float>& ys,
                  const mrpt::poses::CPose2D& start) const;
  double lookup(double x, double y) const;
  /** sums[(j + nxy) (2 nxy + 1) + (i + nxy)]: the table summed over the
   *  cells (gx[k] + i step, gy[k] + j step) of every point k inside it, for
   *  i, j in [-nxy, nxy]. */
  void windowSums(const std::vector<int>& gx, const std::vector<int>& gy, int nxy, int step,
                  std::vector<double>& sums) const;
  double score(const std::vector<float>& xs, const std::vector<float>& ys, double x, double y,
               double yaw) const;

  Parameters p_;
  double x0_ = 0, y0_ = 0;
  int w_ = 0, h_ = 0;
  /** Per cell: ln(1 + g (1 - outlier) / outlier), g the Gaussian closeness
   *  to the nearest reference point: a point's log-likelihood ratio against
   *  an unexplained one. */
  std::vector<float> table_;
};

}  // namespace carenav::slam
