// "icp-graph": ICP scan-to-submap odometry, keyframes, loop closure by
// proximity and scan-match quality, and a pose graph optimised with MRPT's
// sparse Levenberg-Marquardt (optimize_graph_spa_levmarq, header-only use).
// The map is rebuilt from the optimised keyframes, so the loop closes in the
// map as well as in the trajectory; MRPT's icp-slam cannot do that.
#include <carenav/slam/correlative_matcher.h>
#include <carenav/slam/line_icp.h>
#include <carenav/slam/loop_consistency.h>
#include <carenav/slam/mapper.h>
#include <carenav/slam/motion_prior.h>
#include <carenav/slam/robust_graph.h>

#include <mrpt/graphslam/levmarq.h>

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/graphs/CNetworkOfPoses.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPoint2D.h>
#include <mrpt/poses/CPose3DPDFGaussian.h>
#include <mrpt/poses/CPosePDFGaussian.h>
#include <mrpt/poses/CPosePDFGaussianInf.h>
#include <mrpt/slam/CICP.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>

namespace carenav::slam {

namespace {

using mrpt::maps::CSimplePointsMap;
using mrpt::poses::CPose2D;

constexpr double kDeg = M_PI / 180;
constexpr size_t kSubmapKeyframes = 10;  // keyframes the scan-to-submap ICP uses
constexpr size_t kLoopNeighbours = 2;    // keyframes each side in a loop candidate's submap
constexpr size_t kLoopTries = 3;         // nearest candidates tried per keyframe
// Visibility agreement a match of the front end's wide search needs with the
// last keyframes' scans (CSAIL log: two look-alikes agreed 0.51 and 0.68; the
// front end's right matches agree 0.82 and more, a few right after a failure
// less, and those are not wide-search matches).
constexpr double kWideMinAgreement = 0.8;
// Squared Mahalanobis distance (3 dof) beyond which two pose estimates
// disagree (a scan match and the odometry's prediction; a loop closure and
// the current graph): the chi-square 99.9 % quantile.
constexpr double kPriorGate = 16.27;

struct Keyframe {
  CPose2D pose;  // current estimate, world frame
  mrpt::obs::CObservation2DRangeScan::Ptr scan;
  std::shared_ptr<CSimplePointsMap> points;                 // in the keyframe's frame
  bool fixed = false;                                       // from a resumed map: not optimised
  std::shared_ptr<const std::vector<LineIcp::Line>> lines;  // of `points`, same frame
};

/** The points and lines of keyframes [from, to] in one frame. */
struct LineSet {
  CSimplePointsMap points;
  std::vector<LineIcp::Line> lines;
};

struct ScanRecord {
  double time;
  size_t keyframe;  // the keyframe the scan is expressed against
  CPose2D rel;      // scan pose in that keyframe's frame
};

mrpt::poses::CPosePDFGaussianInf edge(const CPose2D& rel, double sxy, double sth) {
  mrpt::poses::CPosePDFGaussianInf e;
  e.mean = rel;
  e.cov_inv.setZero();
  e.cov_inv(0, 0) = e.cov_inv(1, 1) = 1 / (sxy * sxy);
  e.cov_inv(2, 2) = 1 / (sth * sth);
  return e;
}

/** An ICP covariance floored at 3 cm and 1 deg. */
mrpt::math::CMatrixDouble33 flooredCov(const mrpt::math::CMatrixDouble33& cov) {
  mrpt::math::CMatrixDouble33 c = cov;
  c(0, 0) += 0.03 * 0.03;
  c(1, 1) += 0.03 * 0.03;
  c(2, 2) += (1.0 * kDeg) * (1.0 * kDeg);
  return c;
}

mrpt::math::CMatrixDouble33 diagCov(double sxy, double sth) {
  mrpt::math::CMatrixDouble33 c;
  c.setZero();
  c(0, 0) = c(1, 1) = sxy * sxy;
  c(2, 2) = sth * sth;
  return c;
}

/** An edge whose information is the ICP covariance (floored at 3 cm and
 *  1 deg): a match that slides along a corridor is trusted across it, not
 *  along it. */
mrpt::poses::CPosePDFGaussianInf edgeFromCov(const CPose2D& rel,
                                             const mrpt::math::CMatrixDouble33& cov) {
  mrpt::poses::CPosePDFGaussianInf e;
  e.mean = rel;
  e.cov_inv = flooredCov(cov).inverse_LLt();
  return e;
}

/** Largest standard deviation of the x-y block of a covariance. */
double maxStdXY(const mrpt::math::CMatrixDouble33& c) {
  const double a = c(0, 0), b = c(0, 1), d = c(1, 1);
  const double l = 0.5 * (a + d) + std::sqrt(0.25 * (a - d) * (a - d) + b * b);
  return std::sqrt(std::max(0.0, l));
}

/** Agreement of points with what a scan saw (a visibility check): each point
 *  (robot frame of the scan's keyframe) is cast along the beam of the scan
 *  that points at it. It agrees when it lies where that beam (or a neighbour)
 *  ended, `tol` either side; it conflicts when the beams went on through it
 *  (it sits in space the scan saw free); behind the hit, outside the field of
 *  view or on a beam without return nothing is known. `agree` and `conflict`
 *  are per point and accumulate over several scans. */
void scanVisibility(const CSimplePointsMap& pts, const CPose2D& pts_in_scan_robot,
                    const mrpt::obs::CObservation2DRangeScan& scan, double tol,
                    std::vector<char>& agree, std::vector<char>& conflict) {
  const size_t n = scan.getScanSize();
  if (n < 2 || scan.aperture <= 0) return;
  const CPose2D sensor(scan.sensorPose);
  const CPose2D to_sensor = (-sensor) + pts_in_scan_robot;
  const double c = std::cos(to_sensor.phi()), s = std::sin(to_sensor.phi());
  const double step = scan.aperture / (n - 1);
  const auto& xs = pts.getPointsBufferRef_x();
  const auto& ys = pts.getPointsBufferRef_y();
  for (size_t i = 0; i < xs.size(); ++i) {
    if (agree[i]) continue;
    const double x = to_sensor.x() + c * xs[i] - s * ys[i];
    const double y = to_sensor.y() + s * xs[i] + c * ys[i];
    const double d = std::hypot(x, y);
    double a =
        std::atan2(y, x) + 0.5 * scan.aperture;  // from the first beam of a right-to-left scan
    if (!scan.rightToLeft) a = scan.aperture - a;
    const long b = std::lround(a / step);
    if (b < 0 || b >= static_cast<long>(n)) continue;
    double lo = 1e9, hi = -1;
    for (long q = std::max(0L, b - 1); q <= std::min<long>(n - 1, b + 1); ++q) {
      if (!scan.getScanRangeValidity(q)) continue;
      lo = std::min<double>(lo, scan.getScanRange(q));
      hi = std::max<double>(hi, scan.getScanRange(q));
    }
    if (hi < 0) continue;
    if (d >= lo - tol && d <= hi + tol)
      agree[i] = 1;
    else if (d < lo - tol)
      conflict[i] = 1;
  }
}

/** The correlative search's parameters from the profile's [slam] keys. */
CorrelativeMatcher::Parameters correlativeParameters(const SlamParams& s) {
  CorrelativeMatcher::Parameters p;
  p.prior_along = s.laser_motion_along;
  p.prior_across = s.laser_motion_across;
  p.prior_yaw = s.laser_motion_deg;
  p.outlier = s.laser_outlier;
  p.independence = s.laser_independence;
  return p;
}

class GraphMapper : public Mapper {
 public:
  explicit GraphMapper(const MapperConfig& cfg) : cfg_(cfg) {
    mrpt::config::CConfigFileMemory icp(cfg.mrpt_ini ? std::string() : cfg.icp.asMrptIni("ICP"));
    icp_.options.loadFromConfigFile(cfg.mrpt_ini ? *cfg.mrpt_ini : icp, "ICP");
    icp_.options.skip_cov_calculation = false;
    insert_opts_.minDistBetweenLaserPoints = 0.05f;
    insert_opts_.isPlanarMap = true;
    if (cfg.resume_map) resume(*cfg.resume_map);
    if (cfg.start_pose) pose_ = *cfg.start_pose;
  }

  void process(const io::ScanStep& step) override {
    ++stats_.scans;
    auto scan = clipScan(step.scan, cfg_.slam.scan_range_max);
    auto local = std::make_shared<CSimplePointsMap>();
    local->insertionOptions = insert_opts_;
    local->insertObservation(*scan);
    current_points_ = local;
    current_scan_ = scan;

    if (step.odometry && step.index > 0) have_odometry_ = true;
    const bool with_odometry = cfg_.slam.use_odometry && step.odometry.has_value();
    const CPose2D guess = with_odometry ? *step.odometry : last_increment_;
    const CPose2D before = pose_;
    bool matched = false;
    if (keyframes_.empty()) {
      // first scan: the start pose
    } else if (local->size() < 10) {
      pose_ = pose_ + guess;  // nothing to match: dead reckoning
    } else {
      matched = with_odometry ? stepWithOdometry(guess) : stepLaserOnly(guess);
    }
    if (!keyframes_.empty()) last_increment_ = pose_ - before;
    if (needKeyframe()) addKeyframe(scan, local, matched);
    const size_t k = keyframes_.size() - 1;
    records_.push_back({step.time, k, pose_ - keyframes_[k].pose});
  }

  void finish() override {
    if (cfg_.slam.loop_consistency && !keyframes_.empty())
      resolveClosures(keyframes_.size() - 1, true);
    if (stats_.loop_closures > 0) optimise();
  }

  CPose2D pose() const override { return pose_; }
  mrpt::math::CMatrixDouble33 covariance() const override { return last_cov_; }

  mrpt::maps::CSimpleMap simpleMap() const override {
    mrpt::maps::CSimpleMap m;
    for (const auto& kf : keyframes_) {
      auto sf = std::make_shared<mrpt::obs::CSensoryFrame>();
      sf->insert(kf.scan);
      auto pdf = std::make_shared<mrpt::poses::CPose3DPDFGaussian>(mrpt::poses::CPose3D(kf.pose));
      m.insert(pdf, sf);
    }
    return m;
  }

  io::Trajectory2D trajectory() const override {
    io::Trajectory2D t;
    t.reserve(records_.size());
    for (const auto& r : records_) {
      const CPose2D p = keyframes_[r.keyframe].pose + r.rel;
      t.push_back({r.time, p.x(), p.y(), p.phi()});
    }
    return t;
  }

  MapperStats stats() const override {
    MapperStats s = stats_;
    s.keyframes = keyframes_.size();
    s.inserted = keyframes_.size();
    return s;
  }

 private:
  struct Match {
    CPose2D pose;
    double goodness = 0;
    mrpt::math::CMatrixDouble33 cov;
    bool consistent = true;  ///< within the motion prior's gate
    CPose2D start;           ///< the correlative search's pose ICP started from
  };

  /** The laser-only match of the current scan against the submap, from the
   *  constant-velocity prediction `predicted`: a correlative search, then
   *  ICP (the comments below say how the search is made). */
  Match matchToSubmap(const CPose2D& predicted) {
    // Without odometry the prediction (constant velocity) can be a metre
    // and tens of degrees off: real logs turn 20-60 deg between scans (the
    // Intel and CSAIL CARMEN logs). A correlative search over a window
    // around it finds the basin; ICP refines.
    // The search maximises scan likelihood times the motion prior: the last
    // step's travel again, along the heading halfway through the turn, and a
    // heading that is either the constant-velocity one or the last one (a
    // robot that stops turning would otherwise be spun on by its own
    // prediction). The window is searched around the prediction and around
    // "no motion" (a robot that stops).
    // After failed matches the robot went on moving unseen (e.g. turning
    // 30 deg per scan at a corridor's end, Intel log): the window around
    // "no motion" widens with every failure in a row (x2, x3: +-70 deg and
    // +-2 m, then +-105 deg and +-3 m), else a robot that kept turning is
    // never found again.
    if (lost_ > 0) {
      double sc = 0;
      const double widen = 1.0 + std::min<size_t>(lost_, 2);
      const CPose2D start = correlative_.match(*current_points_, pose_, &sc, widen, widen);
      return refine(start, sc);
    }
    const double advance = std::copysign(last_increment_.norm(), last_increment_.x());
    const CorrelativeMatcher::Prior prior{pose_, advance, {predicted.phi(), pose_.phi()}};
    const CorrelativeMatcher::Result c =
        correlative_.match(*current_points_, {predicted, pose_}, prior);
    Match best = refine(c.pose, c.closeness);
    if (best.goodness < cfg_.slam.min_icp_goodness) {
      // A weak match: the robot may have turned more than the window (CSAIL
      // log: 65 deg between two scans). Search three times the heading window
      // (+-105 deg, as three sectors of +-35 deg centred 0 and +-70 deg off)
      // and twice the distance window (+-2 m: the robot also moved) around
      // both priors before giving up. The wide window also holds look-alikes
      // metres away, and the single best of it can be one that hides the
      // right basin (CSAIL scans 52 and 61: 1.5 m backwards at the right
      // heading, +50 deg for -50 deg, both sound ICP matches): each sector
      // gives its best, and a match is kept only if it is sound and agrees
      // with what the last keyframes saw (recentAgreement at least
      // kWideMinAgreement; those two agreed 0.68 and 0.51). The best such
      // match wins.
      for (const CPose2D& prior : {pose_, predicted})
        for (const double off : {0.0, -70.0, 70.0}) {
          double sc = 0;
          const CPose2D centre(prior.x(), prior.y(), prior.phi() + off * kDeg);
          const CPose2D c = correlative_.match(*current_points_, centre, &sc, 2.0, 1.0);
          const Match wide = refine(c, sc);
          if (wide.goodness < cfg_.slam.min_icp_goodness || wide.goodness <= best.goodness)
            continue;
          if (recentAgreement(wide.pose) >= kWideMinAgreement) best = wide;
        }
    }
    return best;
  }

  /** With odometry: ICP from the odometry's prediction, weighed against it.
   *  A match the prior's uncertainty explains (squared Mahalanobis distance
   *  of the two within kPriorGate) is fused with it (information form): a
   *  match that slides along a corridor is held by odometry along it. A match
   *  farther off is a wrong basin (a look-alike doorway, an open hall with
   *  few returns): the step is dead-reckoned (goodness 0). */
  Match matchWithPrior(const CPose2D& inc) {
    const CPose2D predicted = pose_ + inc;
    const PoseGaussian prior(predicted, toWorld(incrementCovariance(inc, motion_), pose_));
    const LineIcp::Result r = line_icp_.align(*current_points_, predicted, &prior);
    Match m;
    m.pose = r.pose;
    m.cov = r.cov;
    m.goodness = r.inliers;
    m.consistent = mahalanobis2(m.pose, predicted, prior.cov) <= kPriorGate;
    return m;
  }

  /** One step with odometry: the posterior's mode (matchWithPrior), or dead
   *  reckoning when scan and odometry disagree. Returns whether matched. */
  bool stepWithOdometry(const CPose2D& inc) {
    const Match m = matchWithPrior(inc);
    if (!m.consistent) {
      pose_ = pose_ + inc;
      ++stats_.prior_rejected;
      ++stats_.icp_rejected;
      return false;
    }
    pose_ = m.pose;
    last_cov_ = m.cov;
    ++stats_.icp_accepted;
    return true;
  }

  /** One step without odometry: the wide search of matchToSubmap from the
   *  constant-velocity prediction. Returns whether matched. */
  bool stepLaserOnly(const CPose2D& guess) {
    const Match m = matchToSubmap(pose_ + guess);
    if (m.goodness >= cfg_.slam.min_icp_goodness) {
      const Match r = refineOnLines(m);
      pose_ = r.pose;
      last_cov_ = r.cov;
      ++stats_.icp_accepted;
      lost_ = 0;
      return true;
    }
    // A failed match must not extrapolate the last motion (a runaway spin):
    // assume the robot stood still, unless the match is weak rather than
    // wrong (at least half the goodness asked for: a scan that sees mostly
    // what the submap lacks). Then its pose is kept, as the best guess there
    // is (a robot turning 30 deg per scan is lost for good if it is held
    // still), but linked to the graph only loosely (not matched).
    if (m.goodness >= 0.5 * cfg_.slam.min_icp_goodness) pose_ = m.pose;
    ++stats_.icp_rejected;
    ++lost_;
    return false;
  }

  /** The laser-only match refined as with odometry: point-to-line ICP
   *  ([Censi08]) from the point-to-point result, under a prior around the
   *  correlative search's pose (the posterior's mode with the motion prior,
   *  known to a coarse step of the search), so that what the walls fix is
   *  refined and what they do not (along a corridor) stays where the search
   *  put it instead of sliding. Kept when it moves the match less than a
   *  coarse step and pairs at least kLineMinInliers of the points. */
  Match refineOnLines(const Match& m) const {
    constexpr double kLineMinInliers = 0.3;
    if (line_icp_.lines() == 0) return m;
    const auto& cp = correlative_.parameters();
    const PoseGaussian prior(m.start, diagCov(cp.coarse_xy, cp.coarse_yaw * kDeg));
    const LineIcp::Result r = line_icp_.align(*current_points_, m.pose, &prior);
    if (r.inliers < kLineMinInliers || (r.pose - m.pose).norm() > cp.coarse_xy ||
        std::abs(std::remainder(r.pose.phi() - m.pose.phi(), 2 * M_PI)) > cp.coarse_yaw * kDeg)
      return m;
    Match out = m;
    out.pose = r.pose;
    out.cov = r.cov;
    return out;
  }

  /** Visibility agreement (scanVisibility) of the current scan placed at
   *  `pose` with the last kAgreementKeyframes keyframes, both ways: the share
   *  of the points that agree among those that agree or conflict (lie in
   *  space the other scan saw free). */
  double recentAgreement(const CPose2D& pose) const {
    constexpr size_t kAgreementKeyframes = 3;
    constexpr double kTol = 0.15;  // m
    size_t agree = 0, conflict = 0;
    const auto& pc = *current_points_;
    std::vector<char> a(pc.size(), 0), c(pc.size(), 0);
    const size_t n = keyframes_.size();
    for (size_t i = n > kAgreementKeyframes ? n - kAgreementKeyframes : 0; i < n; ++i) {
      const Keyframe& kf = keyframes_[i];
      scanVisibility(pc, pose - kf.pose, *kf.scan, kTol, a, c);
      std::vector<char> ak(kf.points->size(), 0), ck(kf.points->size(), 0);
      scanVisibility(*kf.points, kf.pose - pose, *current_scan_, kTol, ak, ck);
      for (size_t q = 0; q < ak.size(); ++q) {
        agree += ak[q] != 0;
        conflict += ak[q] == 0 && ck[q] != 0;
      }
    }
    for (size_t q = 0; q < a.size(); ++q) {
      agree += a[q] != 0;
      conflict += a[q] == 0 && c[q] != 0;
    }
    return agree + conflict > 0 ? static_cast<double>(agree) / (agree + conflict) : 0.0;
  }

  /** ICP from `start`, a correlative match of score `start_score`. */
  Match refine(const CPose2D& start, double start_score) {
    Match best;
    best.start = start;
    mrpt::slam::CICP::TReturnInfo info;
    auto pdf = icp_.Align(&submap_, current_points_.get(), start, info);
    best.goodness = info.goodness;
    best.pose = pdf->getMeanVal();
    pdf->getCovariance(best.cov);
    if (best.goodness < cfg_.slam.min_icp_goodness && start_score >= 0.5) {
      // ICP lost its pairs (thresholds too tight for this scan) but the
      // correlative match is sound: keep it, with its coarse uncertainty.
      best.pose = start;
      best.goodness = start_score;
      best.cov.setZero();
      best.cov(0, 0) = best.cov(1, 1) = 0.05 * 0.05;
      best.cov(2, 2) = (1.0 * kDeg) * (1.0 * kDeg);
    }
    return best;
  }

  bool needKeyframe() const {
    if (keyframes_.empty()) return true;
    const CPose2D d = pose_ - keyframes_.back().pose;
    return d.norm() >= cfg_.slam.keyframe_distance ||
           std::abs(d.phi()) >= cfg_.slam.keyframe_angle * kDeg;
  }

  void addKeyframe(const mrpt::obs::CObservation2DRangeScan::Ptr& scan,
                   const std::shared_ptr<CSimplePointsMap>& pts, bool matched) {
    const size_t id = keyframes_.size();
    keyframes_.push_back({pose_, scan, pts, false, linesOf(*pts)});
    graph_.nodes[id] = pose_;
    if (id > 0) {
      const Keyframe& prev = keyframes_[id - 1];
      // Scan-matched links are tight; dead-reckoned ones loose.
      graph_.insertEdge(id - 1, id,
                        matched ? edgeFromCov(pose_ - prev.pose, last_cov_)
                                : edge(pose_ - prev.pose, 0.3, 5.0 * kDeg));
      const PoseGaussian step(pose_ - prev.pose,
                              matched ? flooredCov(last_cov_) : diagCov(0.3, 5.0 * kDeg));
      chain_.add(step);
      drift_ = compose(drift_, step);
      const bool found = tryLoopClosures(id);
      if (cfg_.slam.loop_consistency ? resolveClosures(id, false) : found) optimise();
    }
    rebuildSubmap();
  }

  std::shared_ptr<const std::vector<LineIcp::Line>> linesOf(const CSimplePointsMap& pts) const {
    if (!cfg_.slam.use_odometry) return nullptr;
    return std::make_shared<const std::vector<LineIcp::Line>>(
        LineIcp::fitLines(pts, LineIcp::Parameters{}));
  }

  /** Points and lines of keyframes [from, to] in the frame whose pose is
   *  `frame` (world frame: CPose2D()). */
  LineSet linesAround(const CPose2D& frame, size_t from, size_t to) const {
    LineSet set;
    for (size_t i = from; i <= to && i < keyframes_.size(); ++i) {
      const Keyframe& kf = keyframes_[i];
      if (!kf.lines) continue;
      const CPose2D t = kf.pose - frame;
      const auto& xs = kf.points->getPointsBufferRef_x();
      const auto& ys = kf.points->getPointsBufferRef_y();
      for (size_t q = 0; q < xs.size(); ++q) {
        const auto w = t + mrpt::poses::CPoint2D(xs[q], ys[q]);
        set.points.insertPointFast(static_cast<float>(w.x()), static_cast<float>(w.y()), 0);
        set.lines.push_back((*kf.lines)[q].transformed(t));
      }
    }
    set.points.mark_as_modified();
    return set;
  }

  /** Points of keyframes [from, to] in the frame of keyframe `ref`. */
  CSimplePointsMap pointsAround(size_t ref, size_t from, size_t to) const {
    CSimplePointsMap m;
    m.insertionOptions = insert_opts_;
    for (size_t i = from; i <= to && i < keyframes_.size(); ++i) {
      CSimplePointsMap p = *keyframes_[i].points;
      p.changeCoordinatesReference(mrpt::poses::CPose3D(keyframes_[i].pose - keyframes_[ref].pose));
      m.insertAnotherMap(&p, mrpt::poses::CPose3D());
    }
    return m;
  }

  /** How far a loop closure is searched: three standard deviations of the
   *  position drift accumulated since the last closure (the chain of
   *  keyframe steps with their covariances), at least loop_search_radius, at
   *  most loop_search_max. */
  double loopSearchRadius() const {
    const auto& s = cfg_.slam;
    return std::clamp(3 * maxStdXY(drift_.cov), s.loop_search_radius,
                      std::max(s.loop_search_radius, s.loop_search_max));
  }

  /** What a loop closure with keyframe j is matched against: the points of
   *  keyframes [from, j + kLoopNeighbours] in j's frame (for ICP) and their
   *  lines (for the point-to-line refinement), with their search trees.
   *  Consecutive keyframes along an old path try the same j's: each is built
   *  once and kept until an optimisation moves the keyframes. */
  struct LoopReference {
    CSimplePointsMap points;
    LineIcp line{LineIcp::Parameters{}};
  };
  const LoopReference& loopReference(size_t j, size_t from) {
    constexpr size_t kMaxCached = 64;
    auto it = loop_refs_.find(j);
    if (it != loop_refs_.end()) return *it->second;
    if (loop_refs_.size() >= kMaxCached) loop_refs_.clear();
    auto ref = std::make_unique<LoopReference>();
    ref->points = pointsAround(j, from, j + kLoopNeighbours);
    LineSet lines = linesAround(keyframes_[j].pose, from, j + kLoopNeighbours);
    ref->line.setReference(lines.points, std::move(lines.lines));
    return *loop_refs_.emplace(j, std::move(ref)).first->second;
  }

  bool tryLoopClosures(size_t k) {
    const auto& s = cfg_.slam;
    const double radius = loopSearchRadius();
    std::vector<std::pair<double, size_t>> cands;
    for (size_t j = 0; j + static_cast<size_t>(s.loop_min_separation) < k; ++j) {
      const double d = (keyframes_[j].pose - keyframes_[k].pose).norm();
      if (d <= radius) cands.emplace_back(d, j);
    }
    std::sort(cands.begin(), cands.end());
    if (cands.size() > kLoopTries) cands.resize(kLoopTries);
    bool any = false;
    mrpt::slam::CICP loop_icp = icp_;
    // Drift makes the first guess poorer than in odometry: start wider.
    loop_icp.options.thresholdDist = std::max(icp_.options.thresholdDist, 1.0);
    loop_icp.options.maxIterations = std::max(icp_.options.maxIterations, 100u);
    for (const auto& [dist, j] : cands) {
      ++stats_.loop_candidates;
      const size_t from = j >= kLoopNeighbours ? j - kLoopNeighbours : 0;
      const LoopReference& ref = loopReference(j, from);
      const CPose2D guess = keyframes_[k].pose - keyframes_[j].pose;
      mrpt::slam::CICP::TReturnInfo info;
      auto pdf = loop_icp.Align(&ref.points, keyframes_[k].points.get(), guess, info);
      CPose2D rel = pdf->getMeanVal();
      if (info.goodness < s.min_icp_goodness) continue;
      // Point-to-point ICP found the basin from the drifted guess; point to
      // line pins it down without the pull along walls sampled differently.
      const LineIcp::Result refined = ref.line.align(*keyframes_[k].points, rel);
      if ((refined.pose - rel).norm() < 0.2 && refined.inliers >= 0.3) rel = refined.pose;
      if ((rel - guess).norm() > std::max(s.loop_max_correction, radius)) continue;
      // ICP's goodness counts the scan's points that found a partner; a
      // keyframe seen again from another heading shares only part of its
      // view with the old one, so a right match can score 0.6 (the simulated
      // SENA loop).
      const bool icp_sure = info.goodness >= s.loop_min_goodness;
      mrpt::math::CMatrixDouble33 cov;
      pdf->getCovariance(cov);
      if (maxStdXY(cov) > 0.1) continue;  // slides along a corridor: no fix
      // Every closure must pass the visibility checks, whatever its ICP
      // goodness: a match along a corridor pairs nearly every point (goodness
      // 0.9 and more) and ICP's covariance can claim a few cm along it, yet it
      // fixes nothing there. Seen through a short-range scanner (10 m) such
      // closures locked a drifted estimate in and bent the CSAIL map by
      // metres; the distinctness check of seenAlike() tells them apart.
      if (!seenAlike(k, j, from, j + kLoopNeighbours, rel)) continue;
      if (!icp_sure) {
        // A partial-overlap match pins the pose less well than its ICP
        // covariance claims: hundreds of such edges, each a few cm and a
        // degree off, bend a large map (Intel log) when trusted as tightly.
        cov(0, 0) += 0.05 * 0.05;
        cov(1, 1) += 0.05 * 0.05;
        cov(2, 2) += (1.0 * kDeg) * (1.0 * kDeg);
      }
      if (cfg_.slam.loop_consistency) {
        any = true;
        candidates_.push_back(
            {next_candidate_id_++, {j, k, PoseGaussian(rel, flooredCov(cov))}, false});
        continue;
      }
      // A closure the current estimate already agrees with (within the
      // chi-square 99.9 % quantile of its covariance) would move the graph by
      // less than its own uncertainty: its edge waits for the next
      // optimisation instead of causing one.
      const CPose2D now = keyframes_[k].pose - keyframes_[j].pose;
      any |= mahalanobis2(now, rel, flooredCov(cov)) > kPriorGate;
      graph_.insertEdge(j, k, edgeFromCov(rel, cov));
      loop_edges_.emplace_back(j, k);
      ++stats_.loop_closures;
      drift_ = PoseGaussian();  // anchored to the old map again
    }
    return any;
  }

  /** A loop closure that passed the checks of one match, waiting for
   *  support from others (or in the graph already). */
  struct Candidate {
    size_t id;
    LoopMeasurement m;
    bool in_graph;
  };

  /** Pairwise consistency of loop closures (loop_consistency.h, [Olson09],
   *  [Mangelson18]): the closures found in the last
   *  kConsistencyWindow keyframes (those in the graph and those waiting) are
   *  tested pair by pair against the odometry chain; the largest mutually
   *  consistent set wins. Waiting closures in it enter the graph once it
   *  holds closures from at least two keyframes (a single match, however
   *  good, can be a look-alike place); waiting closures that leave the
   *  window without such support are dropped. `final`: the log has ended,
   *  no more support will come. Returns whether closures entered the graph. */
  bool resolveClosures(size_t k, bool final) {
    constexpr size_t kConsistencyWindow = 30;
    // Forget closures that left the window; the waiting ones are dropped.
    for (auto it = candidates_.begin(); it != candidates_.end();) {
      if (it->m.to + kConsistencyWindow < k) {
        if (!it->in_graph) ++stats_.loop_rejected;
        it = candidates_.erase(it);
      } else {
        ++it;
      }
    }
    bool waiting = false;
    for (const auto& c : candidates_) waiting |= !c.in_graph;
    if (!waiting) return false;
    const size_t n = candidates_.size();
    std::vector<std::vector<char>> adj(n, std::vector<char>(n, 0));
    for (size_t a = 0; a < n; ++a)
      for (size_t b = a + 1; b < n; ++b) {
        const auto key = std::make_pair(candidates_[a].id, candidates_[b].id);
        auto f = consistent_.find(key);
        if (f == consistent_.end())
          f = consistent_
                  .emplace(key, pairwiseChi2(chain_, candidates_[a].m, candidates_[b].m) <=
                                    cfg_.slam.loop_consistency_gate)
                  .first;
        adj[a][b] = adj[b][a] = f->second;
      }
    const std::vector<size_t> best = maximumClique(adj);
    std::set<size_t> keyframes_seen;
    for (size_t i : best) keyframes_seen.insert(candidates_[i].m.to);
    bool any = false;
    if (keyframes_seen.size() >= 2) {
      for (size_t i : best) {
        Candidate& c = candidates_[i];
        if (c.in_graph) continue;
        mrpt::poses::CPosePDFGaussianInf e;
        e.mean = c.m.z.mean;
        e.cov_inv = c.m.z.cov.inverse_LLt();
        graph_.insertEdge(c.m.from, c.m.to, e);
        loop_edges_.emplace_back(c.m.from, c.m.to);
        ++stats_.loop_closures;
        drift_ = PoseGaussian();
        c.in_graph = true;
        any = true;
      }
    }
    if (final)
      for (const auto& c : candidates_)
        if (!c.in_graph) ++stats_.loop_rejected;
    // Pairs of closures that left the window are not asked for again.
    if (consistent_.size() > 100000) consistent_.clear();
    return any;
  }

  struct Visibility {
    double agreement = 0;  // agreeing / (agreeing + conflicting) points
    double overlap = 0;    // agreeing / all points
  };

  /** Both ways: the points of keyframe k placed at `rel` in keyframe j's frame
   *  against the scans of keyframes [from, to], and the points of j against
   *  the scan of k. */
  Visibility loopVisibility(size_t k, size_t j, size_t from, size_t to, const CPose2D& rel) const {
    constexpr double kTol = 0.15;  // m
    size_t agree = 0, conflict = 0, total = 0;
    auto tally = [&](const std::vector<char>& a, const std::vector<char>& c) {
      for (size_t i = 0; i < a.size(); ++i) {
        agree += a[i] != 0;
        conflict += a[i] == 0 && c[i] != 0;
      }
      total += a.size();
    };
    {
      const auto& pk = *keyframes_[k].points;
      std::vector<char> a(pk.size(), 0), c(pk.size(), 0);
      for (size_t i = from; i <= to && i < keyframes_.size(); ++i) {
        if (i + static_cast<size_t>(cfg_.slam.loop_min_separation) >= k) break;
        const CPose2D ti = keyframes_[i].pose - keyframes_[j].pose;
        scanVisibility(pk, (-ti) + rel, *keyframes_[i].scan, kTol, a, c);
      }
      tally(a, c);
    }
    {
      const auto& pj = *keyframes_[j].points;
      std::vector<char> a(pj.size(), 0), c(pj.size(), 0);
      scanVisibility(pj, -rel, *keyframes_[k].scan, kTol, a, c);
      tally(a, c);
    }
    Visibility v;
    if (agree + conflict > 0) v.agreement = static_cast<double>(agree) / (agree + conflict);
    if (total > 0) v.overlap = static_cast<double>(agree) / total;
    return v;
  }

  /** Whether keyframe k at `rel` in keyframe j's frame is a loop closure by
   *  the visibility checks: the scans agree (few points of one lie in space
   *  the other saw free), overlap enough, and the overlap is distinct: moving
   *  the match 0.3 m in any of 8 directions loses at least loop_min_distinct
   *  of it (a match that slides along a corridor pins nothing down). */
  bool seenAlike(size_t k, size_t j, size_t from, size_t to, const CPose2D& rel) const {
    const auto& s = cfg_.slam;
    const Visibility vis = loopVisibility(k, j, from, to, rel);
    if (vis.agreement < s.loop_min_agreement || vis.overlap < s.loop_min_overlap) return false;
    double worst = 0;
    for (int q = 0; q < 8; ++q) {
      const double a = q * M_PI / 4;
      const CPose2D shifted(rel.x() + 0.3 * std::cos(a), rel.y() + 0.3 * std::sin(a), rel.phi());
      worst = std::max(worst, loopVisibility(k, j, from, to, shifted).overlap);
    }
    return 1 - worst / vis.overlap >= s.loop_min_distinct;
  }

  /** Optimises the graph robustly (robust_graph.h: loop edges under dynamic
   *  covariance scaling, so a wrong match that survived the checks cannot
   *  bend the map), then drops the loop closures the solution disagrees with
   *  (residual over 0.3 m or 5 deg) and optimises again, a few rounds at
   *  most. */
  void optimise() {
    if (!cfg_.slam.loop_robust) return optimisePlain();
    std::set<mrpt::graphs::TNodeID> free;
    for (size_t i = 0; i < keyframes_.size(); ++i)
      if (!keyframes_[i].fixed && i != graph_.root) free.insert(i);
    if (free.empty()) return;
    RobustGraphOptions opt;
    opt.robust = cfg_.slam.loop_robust;
    opt.phi = cfg_.slam.loop_robust_phi;
    const auto r = optimiseRobust(graph_, loop_edges_, free, opt);
    stats_.optimisations += r.solves;
    stats_.loop_closures -= r.rejected.size();
    stats_.loop_rejected += r.rejected.size();
    const CPose2D last_before = keyframes_.back().pose;
    for (size_t i = 0; i < keyframes_.size(); ++i) keyframes_[i].pose = graph_.nodes[i];
    loop_refs_.clear();
    // The robot moves with its last keyframe.
    pose_ = keyframes_.back().pose + (pose_ - last_before);
  }

  /** Optimises the graph, then drops loop closures the solution disagrees
   *  with (residual over 0.3 m or 5 deg: a wrong match that survived the
   *  checks) and optimises again, a few rounds at most. */
  void optimisePlain() {
    std::set<mrpt::graphs::TNodeID> free;
    for (size_t i = 0; i < keyframes_.size(); ++i)
      if (!keyframes_[i].fixed && i != graph_.root) free.insert(i);
    if (free.empty()) return;
    const auto before = graph_.nodes;
    for (int round = 0; round < 3; ++round) {
      graph_.nodes = before;
      mrpt::graphslam::TResultInfoSpaLevMarq info;
      mrpt::containers::yaml params = mrpt::containers::yaml::Map();
      params["max_iterations"] = 100;
      mrpt::graphslam::optimize_graph_spa_levmarq(graph_, info, &free, params);
      ++stats_.optimisations;
      if (!pruneLoopEdges()) break;
    }
    const CPose2D last_before = keyframes_.back().pose;
    for (size_t i = 0; i < keyframes_.size(); ++i) keyframes_[i].pose = graph_.nodes[i];
    loop_refs_.clear();
    // The robot moves with its last keyframe.
    pose_ = keyframes_.back().pose + (pose_ - last_before);
  }

  bool pruneLoopEdges() {
    bool removed = false;
    for (auto it = loop_edges_.begin(); it != loop_edges_.end();) {
      const auto [j, k] = *it;
      auto range = graph_.edges.equal_range({j, k});
      bool bad = false;
      for (auto e = range.first; e != range.second;) {
        const CPose2D est = graph_.nodes[k] - graph_.nodes[j];
        const CPose2D res = est - e->second.mean;
        if (res.norm() > 0.3 || std::abs(res.phi()) > 5 * kDeg) {
          e = graph_.edges.erase(e);
          bad = true;
        } else {
          ++e;
        }
      }
      if (bad) {
        it = loop_edges_.erase(it);
        --stats_.loop_closures;
        ++stats_.loop_rejected;
        removed = true;
      } else {
        ++it;
      }
    }
    return removed;
  }

  void rebuildSubmap() {
    const size_t n = keyframes_.size();
    const size_t from = n > kSubmapKeyframes ? n - kSubmapKeyframes : 0;
    submap_ = CSimplePointsMap();
    submap_.insertionOptions = insert_opts_;
    for (size_t i = from; i < n; ++i) {
      CSimplePointsMap p = *keyframes_[i].points;
      p.changeCoordinatesReference(mrpt::poses::CPose3D(keyframes_[i].pose));
      submap_.insertAnotherMap(&p, mrpt::poses::CPose3D());
    }
    if (!cfg_.slam.use_odometry || !have_odometry_) correlative_.setReference(submap_);
    if (cfg_.slam.use_odometry) {
      LineSet set = linesAround(CPose2D(), from, n - 1);
      line_icp_.setReference(set.points, std::move(set.lines));
    }
  }

  void resume(const mrpt::maps::CSimpleMap& map) {
    for (size_t i = 0; i < map.size(); ++i) {
      const auto& [pdf, sf] = map.get(i);
      if (!pdf || !sf) continue;
      auto scan = sf->getObservationByClass<mrpt::obs::CObservation2DRangeScan>();
      if (!scan) continue;
      auto pts = std::make_shared<CSimplePointsMap>();
      pts->insertionOptions = insert_opts_;
      pts->insertObservation(*scan);
      const CPose2D p(pdf->getMeanVal());
      const size_t id = keyframes_.size();
      keyframes_.push_back({p, scan, pts, true, linesOf(*pts)});
      graph_.nodes[id] = p;
      if (id > 0) {
        graph_.insertEdge(id - 1, id, edge(p - keyframes_[id - 1].pose, 0.01, 0.2 * kDeg));
        chain_.add(PoseGaussian(p - keyframes_[id - 1].pose, diagCov(0.01, 0.2 * kDeg)));
      }
      pose_ = p;
    }
    rebuildSubmap();
  }

  MapperConfig cfg_;
  mrpt::slam::CICP icp_;
  CSimplePointsMap::TInsertionOptions insert_opts_;
  std::vector<Keyframe> keyframes_;
  std::vector<ScanRecord> records_;
  mrpt::graphs::CNetworkOfPoses2DInf graph_;
  CSimplePointsMap submap_;
  std::shared_ptr<CSimplePointsMap> current_points_;
  mrpt::obs::CObservation2DRangeScan::Ptr current_scan_;
  std::vector<std::pair<size_t, size_t>> loop_edges_;
  std::map<size_t, std::unique_ptr<LoopReference>> loop_refs_;  // by keyframe j (loopReference)
  OdometryChain chain_;                // keyframe to keyframe, as first matched
  PoseGaussian drift_;                 // the chain since the last loop closure
  std::vector<Candidate> candidates_;  // closures of the last keyframes
  size_t next_candidate_id_ = 0;
  std::map<std::pair<size_t, size_t>, bool> consistent_;  // by candidate ids
  CorrelativeMatcher correlative_{correlativeParameters(cfg_.slam)};
  LineIcp line_icp_{LineIcp::Parameters{}};
  MotionNoise motion_{cfg_.slam.odom_dist_frac, cfg_.slam.odom_deg_per_m, cfg_.slam.odom_turn_frac,
                      cfg_.slam.odom_min_xy, cfg_.slam.odom_min_deg};
  bool have_odometry_ = false;  // the log has shown odometry
  size_t lost_ = 0;             // laser only: scan matches failed in a row
  CPose2D pose_, last_increment_;
  mrpt::math::CMatrixDouble33 last_cov_ = [] {
    mrpt::math::CMatrixDouble33 c;
    c.setDiagonal(3, 1e-4);
    return c;
  }();
  MapperStats stats_;
};

}  // namespace

std::unique_ptr<Mapper> makeIcpGraphMapper(const MapperConfig& cfg) {
  return std::make_unique<GraphMapper>(cfg);
}

}  // namespace carenav::slam
