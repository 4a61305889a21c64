// Point-to-line ICP [Censi08] with the motion prior in the same least
// squares: each scan point is pulled onto the line through its nearest
// reference point (the line fitted to that point's neighbours), not onto the
// point itself, so a wall sampled at other angles than the scan gives no
// false pull along it; and the odometry's prediction is one more Gaussian
// term, so what the scan does not pin down (the length of a corridor, an
// open hall) follows odometry by its covariance instead of sliding
// ([Olson09csm]: the match is the posterior's mode, the prior included). The
// covariance of the result is the inverse of the final information matrix:
// large along a corridor without the prior, as wide as odometry's with it.
#pragma once

#include <carenav/slam/loop_consistency.h>

#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/poses/CPose2D.h>

#include <vector>

namespace carenav::slam {

class LineIcp {
 public:
  struct Parameters {
    size_t normal_neighbours = 6;  ///< reference points a line is fitted to
    double normal_radius = 0.3;    ///< m, neighbours farther than this are not used
    /** m, rms distance of the neighbours to their line above which the
     *  reference point is no line (a corner, clutter) and pairs nothing. */
    double max_line_rms = 0.03;
    double pair_first = 0.5;  ///< m, largest pairing distance of the first iterations
    double pair_last = 0.1;   ///< m, the pairing distance it shrinks to
    int iterations = 40;      ///< at most
    /** m, standard deviation of a point's distance to its line (range noise
     *  and the reference map's blur): weighs the scan against the prior. */
    double sigma = 0.05;
    /** Share of the points allowed to weigh as if independent: neighbouring
     *  beams hit the same surface with correlated errors, so n points carry
     *  less than n independent measurements' information. */
    double independence = 0.2;
    double huber = 2.0;  ///< residuals beyond huber * sigma weigh as Huber's M-estimator
  };

  struct Result {
    mrpt::poses::CPose2D pose;
    mrpt::math::CMatrixDouble33 cov;  ///< of pose (with the prior when one was given)
    double inliers = 0;               ///< share of the scan points paired at the end
    size_t pairs = 0;
  };

  /** The line at a reference point: its unit normal and a point of it (the
   *  neighbours' mean); a zero normal: no line there (a corner, clutter). */
  struct Line {
    float nx = 0, ny = 0;
    float mx = 0, my = 0;
    bool valid() const { return nx != 0 || ny != 0; }
    /** The line in the frame where `frame` is the pose of its own frame. */
    Line transformed(const mrpt::poses::CPose2D& frame) const;
  };

  explicit LineIcp(const Parameters& p) : p_(p) {}
  /** The lines of a point set, one per point (e.g. one scan's, fitted once in
   *  its own frame and moved with it). */
  static std::vector<Line> fitLines(const mrpt::maps::CSimplePointsMap& pts, const Parameters& p);

  /** The reference points (world frame); fits their lines. */
  void setReference(const mrpt::maps::CSimplePointsMap& ref);
  /** The reference points and their lines, fitted before (same order). */
  void setReference(const mrpt::maps::CSimplePointsMap& ref, std::vector<Line> lines);
  size_t lines() const { return lines_; }
  /** Aligns the scan (robot frame) from `start`; with `prior` (the pose's
   *  Gaussian prior, world frame) the result is the posterior's mode. */
  Result align(const mrpt::maps::CSimplePointsMap& scan, const mrpt::poses::CPose2D& start,
               const PoseGaussian* prior = nullptr) const;

 private:
  static Line fitLine(const mrpt::maps::CSimplePointsMap& pts, float x, float y,
                      const Parameters& p);

  Parameters p_;
  mrpt::maps::CSimplePointsMap ref_;
  std::vector<Line> line_;
  size_t lines_ = 0;
};

}  // namespace carenav::slam
