#include <carenav/common/profile.h>
#include <carenav/localization/localization_params.h>

namespace carenav::localization {

const ParamTable<LocalizationParams>& LocalizationParams::table() {
  using P = LocalizationParams;
  static const auto t =
      ParamTable<P>()
          .text("sensor", &P::sensor,
                "sensorLabel of the 2D scans to localise with (empty: the first 2D scan of "
                "each entry)")
          .integer("particles_min", &P::particles_min, "", 1, 1000000, "KLD: smallest sample size")
          .integer("particles_max", &P::particles_max, "", 1, 1000000, "KLD: largest sample size")
          .integer("global_particles", &P::global_particles, "", 1, 1000000,
                   "particles spread over the free space for --global (at most particles_max)")
          .real("kld_bin_xy", &P::kld_bin_xy, "m", 0.005, 10, "KLD: bin size in x and y")
          .real("kld_bin_phi", &P::kld_bin_phi, "deg", 0.1, 180, "KLD: bin size in heading")
          .real("kld_delta", &P::kld_delta, "", 1e-6, 0.5,
                "KLD: probability that the sample size bound is exceeded")
          .real("kld_epsilon", &P::kld_epsilon, "", 1e-6, 1,
                "KLD: largest divergence between sample and true posterior")
          .real("resample_ess", &P::resample_ess, "", 0, 1,
                "resample when the effective sample size ratio falls below")
          .real("temper_ess", &P::temper_ess, "", 0, 1,
                "while not converged: the scan likelihood is raised to the largest power <= 1 "
                "that keeps the effective sample size at least this share of its value before "
                "the scan (0: no tempering)")
          .real("temper_beta_min", &P::temper_beta_min, "", 1e-9, 1,
                "smallest power of the tempered likelihood")
          .real("global_keep", &P::global_keep, "", 0, 1,
                "while not converged: KLD lower bound as a share of the global start's particles "
                "(0: particles_min)")
          .real("global_min_std_xy", &P::global_min_std_xy, "m", 0, 10,
                "while not converged: smallest translation noise of a motion (roughening)")
          .real("global_min_std_phi", &P::global_min_std_phi, "deg", 0, 180,
                "while not converged: smallest heading noise of a motion (roughening)")
          .real("lf_sigma", &P::lf_sigma, "m", 0.005, 5,
                "likelihood field: standard deviation of a hit")
          .real("lf_max_corr_dist", &P::lf_max_corr_dist, "m", 0.01, 10,
                "likelihood field: distance to the nearest obstacle is capped here")
          .real("lf_z_hit", &P::lf_z_hit, "", 0, 1, "likelihood field: weight of the hit term")
          .real("lf_z_random", &P::lf_z_random, "", 0, 1,
                "likelihood field: weight of the random term")
          .real("lf_max_range", &P::lf_max_range, "m", 0.5, 500,
                "likelihood field: longer ranges are ignored")
          .integer("lf_decimation", &P::lf_decimation, "", 1, 1000, "use every n-th beam")
          .real("update_min_d", &P::update_min_d, "m", 0, 10,
                "travel between filter updates (0 with update_min_a 0: every scan)")
          .real("update_min_a", &P::update_min_a, "deg", 0, 180, "turn between filter updates")
          .real("odom_a1", &P::odom_a1, "m/m", 0, 10, "odometry: translation noise per metre")
          .real("odom_a2", &P::odom_a2, "m/deg", 0, 10,
                "odometry: translation noise per degree turned")
          .real("odom_a3", &P::odom_a3, "deg/m", 0, 100, "odometry: heading noise per metre")
          .real("odom_a4", &P::odom_a4, "deg/deg", 0, 10,
                "odometry: heading noise per degree turned")
          .real("odom_min_std_xy", &P::odom_min_std_xy, "m", 0, 10,
                "odometry: noise added to every motion")
          .real("odom_min_std_phi", &P::odom_min_std_phi, "deg", 0, 180,
                "odometry: heading noise added to every motion")
          .flag("recovery", &P::recovery,
                "augmented MCL: inject random particles when the likelihood drops")
          .real("alpha_slow", &P::alpha_slow, "", 0, 1,
                "augmented MCL: decay rate of the long-term likelihood average")
          .real("alpha_fast", &P::alpha_fast, "", 0, 1,
                "augmented MCL: decay rate of the short-term likelihood average")
          .real("max_inject_fraction", &P::max_inject_fraction, "", 0, 1,
                "augmented MCL: largest share of particles replaced in one update")
          .real("recovery_ratio", &P::recovery_ratio, "", 0, 1,
                "recovery guard: an update whose w_fast/w_slow is below this counts as low")
          .integer("recovery_patience", &P::recovery_patience, "", 1, 1000,
                   "recovery guard: consecutive updates a converged estimate is contradicted by "
                   "the map or has a low likelihood before it is challenged (challenge) or "
                   "given random particles; also the updates a challenger must explain the "
                   "scans better before it takes over")
          .real("consistent_beams", &P::consistent_beams, "", 0, 1,
                "recovery guard: a converged estimate that sees at least this share of beams "
                "not passing through a mapped obstacle is consistent with the map; one that is "
                "not, recovery_patience updates in a row, is challenged (challenge false: "
                "lost, a global search replaces it) (0: no consistency rule)")
          .flag("challenge", &P::challenge,
                "recovery guard: a contradicted converged estimate is challenged by a global "
                "search run beside it, and lost only when that search converges elsewhere and "
                "explains the scans better; never random particles in a converged cloud "
                "(false: the earlier guard, restart and augmented MCL injections)")
          .integer("min_returns", &P::min_returns, "", 0, 100000,
                   "a scan with fewer returns in range is not weighed: the estimate follows "
                   "odometry alone (dead reckoning) until a scan with enough returns (0: weigh "
                   "every scan)")
          .real("lost_inject_fraction", &P::lost_inject_fraction, "", 0, 1,
                "at a loss: random particles added, as a share of the global start's sample size")
          .real("converged_spread", &P::converged_spread, "m", 0.001, 100,
                "converged when the position spread sqrt(var x + var y) falls below")
          .real("lost_spread", &P::lost_spread, "m", 0.001, 1000,
                "a converged filter counts as lost when the spread, or the jump of the estimate "
                "beyond odometry in one update, exceeds")
          .real("free_threshold", &P::free_threshold, "", 0.5, 1,
                "cells whose free probability is above are free space")
          .flag("rotate_request", &P::rotate_request,
                "ask the navigation layer to rotate in place when the filter stays unconverged "
                "and the robot is not turning")
          .integer("rotate_after_updates", &P::rotate_after_updates, "", 1, 100000,
                   "filter updates without convergence before a rotate-in-place request")
          .real("rotate_turn", &P::rotate_turn, "deg", 1, 3600,
                "turned while unconverged: the robot is already turning (no request); turned "
                "since a request: the request ends")
          .integer("seed", &P::seed, "", 0, 2147483647, "random seed")
          .check([](const P& p) -> std::optional<std::string> {
            if (p.particles_min > p.particles_max)
              return "particles_min must not exceed particles_max";
            return std::nullopt;
          })
          .check([](const P& p) -> std::optional<std::string> {
            if (p.recovery && p.alpha_slow >= p.alpha_fast)
              return "alpha_slow must be smaller than alpha_fast";
            return std::nullopt;
          })
          .check([](const P& p) -> std::optional<std::string> {
            if (p.converged_spread >= p.lost_spread)
              return "converged_spread must be smaller than lost_spread";
            return std::nullopt;
          });
  return t;
}

void registerProfileSections() {
  ProfileSchemas::instance().add(SectionSchema::of(LocalizationParams::table(), "localization",
                                                   "Monte Carlo localisation on a known map"));
}

}  // namespace carenav::localization
