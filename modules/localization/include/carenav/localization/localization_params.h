// Parameters of `carenav localize` and of Localizer: the profile's
// [localization] section.
#pragma once

#include <carenav/common/params.h>

#include <string>

namespace carenav::localization {

/** [localization]: Monte Carlo localisation on a known grid map (MRPT's
 *  CMonteCarloLocalization2D, KLD-adaptive sample size, likelihood field),
 *  with augmented-MCL recovery.
 *  ```ini
 *  [localization]
 *  particles_max = 500
 *  update_min_d = 0.25      ; m
 *  update_min_a = 11.46     ; deg (0.2 rad)
 *  ```
 */
struct LocalizationParams {
  std::string sensor;  ///< sensorLabel of the 2D scans ("" any)
  // KLD-adaptive sample size (Fox 2003)
  int particles_min = 150;       ///< KLD lower bound on the sample size
  int particles_max = 40000;     ///< KLD upper bound on the sample size
  int global_particles = 40000;  ///< particles of a global start (capped by particles_max)
  double kld_bin_xy = 0.10;      ///< m, KLD histogram bin size in x and y
  double kld_bin_phi = 10;       ///< deg, KLD histogram bin size in heading
  double kld_delta = 0.01;       ///< KLD: probability that the bound is wrong
  double kld_epsilon = 0.01;     ///< KLD: largest KL divergence allowed
  double resample_ess = 0.5;     ///< resample when the effective sample size ratio falls below
  /** Tempering while the filter has not converged: each scan's likelihood is
   *  raised to the largest power beta <= 1 that keeps the effective sample
   *  size at least this share of what it was before the scan (0: off). */
  double temper_ess = 0.5;
  double temper_beta_min = 1e-4;  ///< smallest tempering exponent
  /** KLD lower bound while the filter has not converged (global phase), as a
   *  share of the global start's sample size (0: particles_min only). */
  double global_keep = 0.5;
  /** While not converged, the motion noise is at least this (m, deg): the
   *  copies a resampling makes of a hypothesis spread around it and climb to
   *  the likelihood's peak (roughening, Gordon, Salmond, Smith 1993). */
  double global_min_std_xy = 0.10;
  double global_min_std_phi = 3;  ///< deg, see global_min_std_xy
  // likelihood field (MRPT's LF_Thrun)
  double lf_sigma = 0.20;         ///< m, standard deviation of a hit around the nearest obstacle
  double lf_max_corr_dist = 0.3;  ///< m, distances to the nearest obstacle are capped here
  double lf_z_hit = 0.95;         ///< weight of the hit term
  double lf_z_random = 0.05;      ///< weight of the random term
  double lf_max_range = 80;       ///< m, longer ranges are not used
  int lf_decimation = 20;         ///< use every n-th beam of a scan
  // when to run the filter
  double update_min_d = 0;  ///< m, travel between filter updates (0: every scan)
  double update_min_a = 0;  ///< deg, turn between filter updates (0: every scan)
  // odometry noise (MRPT's Gaussian motion model)
  double odom_a1 = 0.05;          ///< m/m, translation noise per metre travelled
  double odom_a2 = 0.001;         ///< m/deg, translation noise per degree turned
  double odom_a3 = 1.0;           ///< deg/m, heading noise per metre travelled
  double odom_a4 = 0.05;          ///< deg/deg, heading noise per degree turned
  double odom_min_std_xy = 0.02;  ///< m, noise added to every motion
  double odom_min_std_phi = 0.5;  ///< deg, noise added to every motion
  // augmented MCL recovery (Thrun, Burgard, Fox, Probabilistic Robotics 8.3.5)
  bool recovery = true;              ///< inject random particles when the likelihood drops
  double alpha_slow = 0.05;          ///< decay of the long-term likelihood average
  double alpha_fast = 0.5;           ///< decay of the short-term likelihood average
  double max_inject_fraction = 0.3;  ///< largest share of particles replaced in one update
  // recovery guard: augmented MCL reacts to one noisy update; on real, low-rate
  // logs that scatters random particles that take over a right estimate.
  /** An update is "low" when w_fast/w_slow falls below this; augmented MCL
   *  itself injects below 1. */
  double recovery_ratio = 0.5;
  /** Consecutive updates of a converged estimate that the map contradicts
   *  (consistent_beams) or whose likelihood is low (recovery_ratio) before it
   *  is challenged (see challenge); also the updates a converged challenger
   *  must explain the scans better before it takes over. 1 with
   *  recovery_ratio 1, consistent_beams 0 and challenge false: plain
   *  augmented MCL. */
  int recovery_patience = 3;
  /** A converged estimate is consistent with the map when at least this
   *  share of the scan's beams (all of them, not decimated), cast from it, do
   *  not pass through a mapped obstacle (checked from lf_max_corr_dist after
   *  the sensor to lf_max_corr_dist before the end point; a beam cut short by
   *  something not on the map, a person, never contradicts the map: the
   *  beam model's short readings, [Thrun05, Sec. 6.3]). An estimate that is
   *  not consistent for recovery_patience updates in a row is challenged (or,
   *  with challenge false, lost: a global search replaces it). 0: no
   *  consistency rule. */
  double consistent_beams = 0.7;
  /** How a converged filter recovers (with recovery on). true: no random
   *  particle ever joins a converged cloud; when the map contradicts its
   *  estimate recovery_patience updates in a row (or its likelihood was low
   *  that long and the map contradicts it now), a challenger (a global
   *  search, global_particles random poses, the global phase's tempering and
   *  roughening) runs beside it on the same scans. A loss is declared only
   *  when the challenger is one place (spread at most lost_spread) more than
   *  lost_spread away and explains the scans better (a larger mean
   *  observation likelihood, summed over recovery_patience updates: a Bayes
   *  factor) than the estimate; it then takes the estimate's place. A
   *  challenger that converges on the estimate, or loses that comparison, is
   *  dropped, as is one still searching once the estimate has been
   *  consistent for recovery_patience updates. false: the earlier guard
   *  (a tight cloud that disagrees is replaced by a global search; augmented
   *  MCL injects into it after recovery_patience low updates). */
  bool challenge = true;
  /** A scan with fewer returns in range than this (an open hall, a sensor
   *  blinded) is not weighed against the map: the estimate follows odometry
   *  alone until a scan with enough returns comes (0: weigh every scan). */
  int min_returns = 10;
  /** At a loss, random particles over the free space join the set: this share
   *  of the global start's sample size (a global search restarts). */
  double lost_inject_fraction = 0.5;
  // reporting
  double converged_spread = 0.3;  ///< m, converged when sqrt(var x + var y) falls below
  double lost_spread =
      1.0;  ///< m, a converged filter is lost when the spread or a jump of the estimate exceeds
  double free_threshold = 0.7;  ///< cells with p_free above are free (global start, injection)
  // "rotate in place to relocalise" (HOBBIT, [Puente14, App. Fig. 8]): a request to the navigation
  // layer
  bool rotate_request = false;    ///< raise the request at all
  int rotate_after_updates = 20;  ///< filter updates without convergence before a request
  double rotate_turn = 360;       ///< deg: turned while not converged, the robot counts as turning;
                                  ///< turned since the request, the request ends
  int seed = 1;  ///< seeds MRPT's global random generator when a Localizer is built
  static const ParamTable<LocalizationParams>& table();
};

/** Registers [localization] with the profile schemas. */
void registerProfileSections();

}  // namespace carenav::localization
