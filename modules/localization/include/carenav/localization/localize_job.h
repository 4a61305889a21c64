// `carenav localize`: a rawlog replayed through the Localizer on a known map,
// with the track, its covariance, a picture and a summary written out.
#pragma once

#include <carenav/io/trajectory.h>
#include <carenav/localization/localizer.h>

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace carenav::localization {

/** An initial pose guess: mean and standard deviations. */
struct InitialPose {
  double x = 0, y = 0, yaw = 0;          ///< m, m, rad
  double std_x = 0.5, std_y = 0.5;       ///< m
  double std_yaw = mrpt::DEG2RAD(10.0);  ///< rad
};

/** Parses "x,y,deg[,sx,sy,sdeg]". Throws InputError. */
InitialPose parseInitialPose(const std::string& text);

struct LocalizeJobOptions {
  std::string map, rawlog;
  std::string out_dir;  ///< empty: nothing is written (the result alone)
  std::string ref;      ///< optional reference trajectory (TUM) for ATE
  LocalizationParams params;
  std::optional<InitialPose> init;  ///< exactly one of init, global and region
  bool global = false;
  /** Global start restricted to a region (a room): its name for messages and
   *  the summary, and the point-in-region test. */
  struct Region {
    std::string name;
    std::function<bool(double x, double y)> inside;
  };
  std::optional<Region> region;
  double map_resolution = 0.05;  ///< m, cell size of a grid built from a .simplemap
  bool progress = true;
};

/** One filter update, for the summary's time series. */
struct UpdateRecord {
  double t = 0;
  size_t particles = 0;
  double spread = 0, likelihood_ratio = 1, seconds = 0;
  size_t injected = 0;
  double beta = 1;         ///< power of the tempered likelihood
  bool resampled = false;  ///< a new set was drawn (KLD) at this update
  double agreement = 1;    ///< StepResult::agreement
  /** m, StepResult::challenger_spread: the spread of the challenger running
   *  after this update (0: none). */
  double challenger_spread = 0;
};

struct LocalizeJobResult {
  size_t scans = 0, updates = 0, injections = 0;
  size_t challenges = 0, challenges_won = 0;  ///< Localizer::challenges(), challengesWon()
  /** Scans that were due an update but held fewer than min_returns returns
   *  in range: the estimate followed odometry alone there. */
  size_t dead_reckoning_scans = 0;
  io::Trajectory2D track;
  std::vector<mrpt::math::CMatrixDouble33> covs;  ///< one per track pose
  std::vector<UpdateRecord> records;
  std::vector<LocalizationEvent> events;
  std::vector<RotateRequest> rotate_requests;
  bool rotate_enabled = false;
  /** s since the first scan; empty when it never converged, or when scans
   *  up to convergence repeat the timestamp of the scan before (a log stamped
   *  in whole seconds or not at all): the time is not measurable then, the
   *  update and scan counts below are. */
  std::optional<double> convergence_time;
  /** Filter updates and scans until the spread fell below converged_spread
   *  (empty: never converged). */
  std::optional<size_t> convergence_updates, convergence_scans;
  size_t repeated_times = 0;  ///< scans whose timestamp repeats the one before
  bool converged_at_end = false;
  double final_spread = 0;                  ///< m, particle spread after the last scan
  double seconds = 0;                       ///< wall time (map loading excluded)
  bool index_times = false;                 ///< the rawlog had no timestamps: t is the scan index
  std::optional<double> ate_rmse, ate_max;  ///< m, with a reference
  size_t ate_pairs = 0;
  std::vector<std::string> outputs;
  std::optional<std::string> rawlog_error;
  std::string summaryJson(const LocalizeJobOptions& o) const;
};

/** Runs the job and, unless out_dir is empty, writes DIR/{track.tum, track_cov.csv, map.png,
 *  summary.json}. Throws InputError for a bad map, rawlog, initial pose or
 *  reference, and when the rawlog has no usable 2D scan. A rawlog that breaks
 *  part way keeps what was read (result.rawlog_error). */
LocalizeJobResult runLocalize(const LocalizeJobOptions& o);

}  // namespace carenav::localization
