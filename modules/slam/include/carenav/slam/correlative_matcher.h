// Brute-force correlative scan matching (after [Olson09csm],
// docs/references.md): scores every pose of a search window by how
// many scan points land near reference points, coarse then fine. Finds the
// right basin where ICP from a poor guess slides or turns into a wrong one
// (laser-only logs with metre-long steps between scans).
#pragma once

#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/poses/CPose2D.h>

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
    /** Score lost per metre (and per 10 deg) away from the prior: in
     *  corridors many poses score alike, the motion prior decides. */
    double prior_weight = 0.03;
  };

  explicit CorrelativeMatcher(const Parameters& p) : p_(p) {}
  /** Builds the lookup table of the reference points (world frame). */
  void setReference(const mrpt::maps::CSimplePointsMap& ref);
  /** Best pose of the scan (points in the robot frame) near `prior`, and its
   *  score: the mean closeness of the scan points, in [0, 1]. `widen_xy`,
   *  `widen_yaw` > 1 multiply the window's half-widths (yaw at most 180 deg)
   *  and divide the prior's distance and heading penalties by the same
   *  factors (a prior that failed is worth less). */
  mrpt::poses::CPose2D match(const mrpt::maps::CSimplePointsMap& scan,
                             const mrpt::poses::CPose2D& prior, double* score = nullptr,
                             double widen_xy = 1, double widen_yaw = 1) const;

 private:
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
  std::vector<float> table_;
};

}  // namespace carenav::slam
