// Monte Carlo localisation on a known occupancy grid, fed one scan at a time:
// the library core of `carenav localize` and of live navigation.
#pragma once

#include <carenav/localization/kld_sampling.h>
#include <carenav/localization/likelihood_field.h>
#include <carenav/localization/localization_params.h>
#include <carenav/localization/rotate_request.h>

#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/slam/CMonteCarloLocalization2D.h>

#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace carenav::localization {

struct MotionSampler;

/** A loss of localisation or a recovery from one. */
struct LocalizationEvent {
  enum class Kind { Loss, Recovery };
  Kind kind = Kind::Loss;
  double t = 0;       ///< time of the scan that showed it
  double spread = 0;  ///< m, particle spread at that time
  const char* name() const { return kind == Kind::Loss ? "loss" : "recovery"; }
};

/** What one step did. */
struct StepResult {
  bool updated = false;             ///< the filter ran (motion thresholds reached)
  mrpt::poses::CPose2D pose;        ///< estimate after the step (mean, odometry since added)
  mrpt::math::CMatrixDouble33 cov;  ///< covariance of x, y, yaw (m², rad²)
  size_t particles = 0;             ///< sample size after the step
  double spread = 0;                ///< m, sqrt(var x + var y)
  double likelihood_ratio = 1;      ///< w_fast / w_slow after the update
  /** Share of the scan's beams that, cast from the estimate after the update,
   *  do not pass through a mapped obstacle (Localizer::scanAgreement). */
  double agreement = 1;
  size_t injected = 0;           ///< random particles added by recovery
  double beta = 1;               ///< power the scan likelihood was raised to (tempering)
  bool resampled = false;        ///< the update drew a new set (KLD) before weighing
  bool rotate_in_place = false;  ///< a rotate-in-place request is open after the step
  /** An update was due but the scan held fewer than min_returns returns in
   *  range: it was not weighed, the estimate is odometry since the last update. */
  bool dead_reckoning = false;
  /** A challenger (a global search beside the estimate, see
   *  LocalizationParams::challenge) is running after the step. */
  bool challenge = false;
  double challenger_spread = 0;  ///< m, its spread (0 without one)
  double seconds = 0;            ///< CPU time of the filter update
};

/** Monte Carlo localisation as MRPT's CMonteCarloLocalization2D runs it
 *  (standard proposal, KLD-adaptive sample size, the grid's likelihood field
 *  lmLikelihoodField_Thrun; the same random draws, so a seed gives the same
 *  particles), with the likelihood field tabled once for the whole map and the
 *  particles moved and drawn in 2D (the particle set itself and its mean and
 *  covariance stay MRPT's), plus recovery. While not converged: augmented
 *  MCL (short- and long-term averages of the mean observation likelihood,
 *  w_fast and w_slow; a share max(0, 1 - w_fast/w_slow) of the particles, at
 *  most max_inject_fraction, replaced by random poses over the free cells).
 *  While converged (challenge on): no random particle joins the cloud; an
 *  estimate the map contradicts (consistent_beams) for recovery_patience
 *  updates is challenged by a global search run beside it, and lost only when
 *  that search explains the scans better (a Bayes factor over
 *  recovery_patience updates) from more than lost_spread away; it then
 *  takes over. challenge off: the earlier guard (see LocalizationParams).
 *  A new set is drawn (KLD) only when the effective sample size ratio fell
 *  below resample_ess; until the filter has converged the scan likelihood is
 *  tempered (temper_ess) and the sample size kept at global_keep of the
 *  global start's. Not thread-safe; one instance per robot. */
class Localizer {
 public:
  /** Copies the map. Throws InputError when it has no free cell. */
  Localizer(const mrpt::maps::COccupancyGridMap2D& map, const LocalizationParams& params);
  ~Localizer();
  Localizer(const Localizer&) = delete;
  Localizer& operator=(const Localizer&) = delete;

  /** Particles drawn around a pose (Gaussian, std in m, m, rad), particles_max
   *  of them. Throws InputError when the pose is outside the map or on an
   *  occupied cell. */
  void initPose(const mrpt::poses::CPose2D& pose, double std_x, double std_y, double std_phi);
  /** Particles uniformly over the free cells, any heading; global_particles
   *  of them, at most particles_max. */
  void initGlobal();
  /** Particles uniformly over the free cells whose centres satisfy
   *  `inside(x, y)` (a room of the places file, say), any heading;
   *  global_particles of them, at most particles_max. Recovery still injects
   *  over the whole map. Throws InputError naming `what` when no free cell
   *  is inside. */
  void initInRegion(const std::function<bool(double x, double y)>& inside, const std::string& what);

  /** One scan and the odometry increment since the previous scan (robot
   *  frame of the previous scan). The filter runs on the first scan and then
   *  whenever the motion since the last update reaches update_min_d or
   *  update_min_a; in between the estimate follows odometry. `t` (seconds)
   *  only stamps events. Throws std::logic_error before an init*(). */
  StepResult step(const mrpt::poses::CPose2D& odometry,
                  const mrpt::obs::CObservation2DRangeScan::Ptr& scan, double t);

  mrpt::poses::CPose2D pose() const;
  mrpt::math::CMatrixDouble33 covariance() const { return cov_; }
  size_t particleCount() const;
  /** The particle set (poses and log weights). */
  const mrpt::poses::CPosePDFParticles& particles() const { return mcl_; }
  /** log p(scan | pose) under the grid's likelihood field, the value every
   *  particle is weighed with: MRPT's lmLikelihoodField_Thrun model with the
   *  lf_* parameters (see COccupancyGridMap2D::computeObservationLikelihood),
   *  from a table built once for the whole map. */
  double scanLogLikelihood(const mrpt::obs::CObservation2DRangeScan& scan,
                           const mrpt::poses::CPose2D& pose) const;
  /** Share of the scan's points (every point of its points map, not
   *  decimated) whose beam, seen from pose, does not pass through an occupied
   *  cell of the map between lf_max_corr_dist from the sensor and
   *  lf_max_corr_dist before its end point: 1 for a scan the map explains,
   *  also when an unmapped obstacle cuts beams short; low for a scan taken
   *  elsewhere. 1 when the scan has no point. */
  double scanAgreement(const mrpt::obs::CObservation2DRangeScan& scan,
                       const mrpt::poses::CPose2D& pose) const;
  double spread() const { return spread_; }
  bool converged() const { return converged_; }
  /** Converging (after an init, not yet converged), Tracking (converged) or
   *  Lost (converged once, then the spread exceeded lost_spread). */
  enum class State { Converging, Tracking, Lost };
  State state() const;
  /** True while a rotate-in-place request is open (rotate_request on): the
   *  filter has not converged for rotate_after_updates updates and the robot
   *  had not turned rotate_turn meanwhile. Navigation should stop and turn in
   *  place until it goes false (converged, or rotate_turn turned). */
  bool needsRotateInPlace() const { return rotate_.open(); }
  /** Every rotate-in-place request so far, the open one last. */
  const std::vector<RotateRequest>& rotateRequests() const { return rotate_.requests(); }
  /** Time of the first update whose spread fell below converged_spread. */
  std::optional<double> convergenceTime() const { return convergence_time_; }
  const std::vector<LocalizationEvent>& events() const { return events_; }
  size_t updates() const { return updates_; }
  /** Random particle sets added: augmented-MCL injections, global searches
   *  after a loss and challengers. */
  size_t injections() const { return injections_; }
  /** Challengers started, and those that took over (each a loss and a
   *  recovery in events()). */
  size_t challenges() const { return challenges_; }
  size_t challengesWon() const { return challenges_won_; }
  const mrpt::maps::COccupancyGridMap2D& map() const { return *map_; }
  const LocalizationParams& params() const { return p_; }

 private:
  mrpt::math::TPose2D randomFreePose() const { return randomPoseIn(free_cells_); }
  mrpt::math::TPose2D randomPoseIn(const std::vector<size_t>& cells) const;
  void initUniform(const std::vector<size_t>& cells);
  void refreshEstimate();
  size_t inject(double fraction);
  size_t globalCount() const;
  void resetTracking();
  // The steps of a filter update, in order.
  MotionSampler odometryMotion() const;
  void predict(const MotionSampler& motion, bool resample);
  bool predictOwn(const MotionSampler& motion);
  void weighScan(const mrpt::obs::CObservation2DRangeScan& scan);
  double updateWeights(StepResult& r);
  void updateAverages(double log_w_avg);
  bool updateConvergence(double jump, double t);
  void recover(bool lost_now, StepResult& r);
  void recoverTight(bool lost_now, StepResult& r);
  double guardedFraction(const StepResult& r);
  size_t restartSearch();
  // The challenger (LocalizationParams::challenge).
  void recoverChallenged(bool lost_now, StepResult& r);
  void countContradictions(const StepResult& r);
  size_t openChallenge();
  void updateChallenger(double tracker_log_w_avg);
  void weighEvidence(double challenger_log_w_avg, double tracker_log_w_avg);
  void judgeChallenge();
  void adoptChallenger();
  void closeChallenge();
  void weighParticles();
  double agreementOf(const std::vector<float>& xs, const std::vector<float>& ys, double sx,
                     double sy, const mrpt::poses::CPose2D& pose) const;
  bool crossesObstacle(double x0, double y0, double x1, double y1) const;
  void filterUpdate(const mrpt::obs::CObservation2DRangeScan& scan, double t, StepResult& r);
  double effectiveSampleRatio() const;
  void normalizeWeights();

  LocalizationParams p_;
  std::shared_ptr<mrpt::maps::COccupancyGridMap2D> map_;
  std::vector<size_t> free_cells_;  // cell indices (x + y * size_x) of free space
  mrpt::slam::CMonteCarloLocalization2D mcl_;
  bool initialised_ = false, first_update_done_ = false;
  mrpt::poses::CPose2D pending_;  // odometry since the last update
  mrpt::poses::CPose2D mean_;
  mrpt::math::CMatrixDouble33 cov_;
  double spread_ = 0;
  bool averages_set_ = false;
  double log_w_slow_ = 0, log_w_fast_ = 0;
  bool converged_ = false;
  std::optional<double> convergence_time_;
  std::vector<LocalizationEvent> events_;
  size_t updates_ = 0, injections_ = 0;
  int low_updates_ = 0, disagree_updates_ = 0;  // recovery guard: consecutive updates
  // The challenger: a global search beside a contradicted estimate.
  struct Challenger {
    bool open = false, converged = false;
    mrpt::poses::CPosePDFParticles::CParticleList particles;
    mrpt::poses::CPose2D mean;
    double spread = 0;
    double t_open = 0;  // time of the update that opened it
    int away = 0;       // consecutive updates with its mean lost_spread away from the estimate
    // log Bayes factors (its log mean likelihood minus the estimate's) of the
    // latest of those updates, at most recovery_patience of them
    std::deque<double> log_factors;
    bool averages_set = false;  // its own augmented-MCL averages
    double log_w_slow = 0, log_w_fast = 0;
  } challenger_;
  int consistent_updates_ = 0;  // consecutive updates the estimate was consistent
  size_t challenges_ = 0, challenges_won_ = 0;
  // The estimate's own generator while a challenger runs (predictOwn).
  std::mt19937 own_rng_;
  bool scan_planar_ = true;             // the latest scan is planar (else every particle gets -10)
  double sensor_x_ = 0, sensor_y_ = 0;  // scan origin in the robot frame
  bool ever_converged_ = false;
  size_t global_n_ = 0;  // sample size of the last global start (0: none)
  RotateRequestTracker rotate_;
  double last_t_ = 0;  // time of the latest step
  LikelihoodField field_;
  KldSampler kld_;
  // scratch reused by every update
  std::vector<float> pts_x_, pts_y_;  // the points the likelihood field weighs
  std::vector<float> all_x_, all_y_;  // every point, for the scan agreement
  std::vector<double> prior_, ll_;
};

}  // namespace carenav::localization
