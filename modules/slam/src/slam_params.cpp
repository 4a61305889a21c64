#include <carenav/common/profile.h>
#include <carenav/slam/slam_params.h>

namespace carenav::slam {

const ParamTable<SlamParams>& SlamParams::table() {
  static const auto t =
      ParamTable<SlamParams>()
          .choice("method", &SlamParams::method, {"icp", "icp-graph", "rbpf"},
                  "icp: MRPT's ICP map builder; icp-graph: ICP with keyframes, loop closure "
                  "and pose-graph optimisation; rbpf: Rao-Blackwellised particle filter")
          .text("sensor", &SlamParams::sensor,
                "sensorLabel of the 2D scans to map with (empty: the first 2D scan of each "
                "entry)")
          .flag("use_odometry", &SlamParams::use_odometry,
                "use odometry as the motion prior (false: laser only)")
          .real("localization_lin_distance", &SlamParams::localization_lin_distance, "m", 0, 10,
                "robot motion between ICP pose corrections")
          .real("localization_ang_distance", &SlamParams::localization_ang_distance, "deg", 0, 180,
                "robot turn between ICP pose corrections")
          .real("insertion_lin_distance", &SlamParams::insertion_lin_distance, "m", 0, 10,
                "robot motion between scans inserted in the map")
          .real("insertion_ang_distance", &SlamParams::insertion_ang_distance, "deg", 0, 180,
                "robot turn between scans inserted in the map")
          .real("min_icp_goodness", &SlamParams::min_icp_goodness, "", 0, 1,
                "smallest ICP match quality accepted as a correction")
          .real("grid_resolution", &SlamParams::grid_resolution, "m", 0.005, 1,
                "cell size of the output occupancy grid")
          .real("scan_range_max", &SlamParams::scan_range_max, "m", 0, 200,
                "ignore longer ranges (0: the scan's own maximum)")
          .real("keyframe_distance", &SlamParams::keyframe_distance, "m", 0.05, 10,
                "icp-graph: motion between keyframes")
          .real("keyframe_angle", &SlamParams::keyframe_angle, "deg", 1, 180,
                "icp-graph: turn between keyframes")
          .real("loop_search_radius", &SlamParams::loop_search_radius, "m", 0.1, 50,
                "icp-graph: keyframes this close to the current one are loop candidates; "
                "the radius grows to three standard deviations of the drift accumulated "
                "since the last loop closure when that is larger")
          .real("loop_search_max", &SlamParams::loop_search_max, "m", 0.1, 200,
                "icp-graph: largest loop search radius the drift can ask for (bounds the "
                "work of a long run without closures)")
          .integer("loop_min_separation", &SlamParams::loop_min_separation, "", 2, 100000,
                   "icp-graph: keyframes between a loop candidate and the current one")
          .real("loop_min_goodness", &SlamParams::loop_min_goodness, "", 0, 1,
                "icp-graph: ICP quality from which a loop closure's edge takes ICP's "
                "covariance as it is (below it, 5 cm and 1 deg are added: a partial overlap "
                "pins the pose less well); every closure must pass the visibility checks "
                "loop_min_agreement, loop_min_overlap and loop_min_distinct")
          .real("loop_min_agreement", &SlamParams::loop_min_agreement, "", 0, 1,
                "icp-graph: smallest visibility agreement of a loop closure: of the points of "
                "either scan that the other scan saw, the share lying where its beams ended "
                "(the rest lie in space it saw free)")
          .real("loop_min_overlap", &SlamParams::loop_min_overlap, "", 0, 1,
                "icp-graph: smallest share of both scans' points that the other scan saw "
                "where its beams ended (too little overlap proves nothing)")
          .real("loop_min_distinct", &SlamParams::loop_min_distinct, "", 0, 1,
                "icp-graph: smallest share of that overlap lost when the match is moved "
                "0.3 m in any direction (a match that can slide along a corridor is no fix)")
          .real("loop_max_correction", &SlamParams::loop_max_correction, "m", 0.01, 100,
                "icp-graph: largest correction a loop closure may make (or the search radius "
                "when that is larger)")
          .flag("loop_consistency", &SlamParams::loop_consistency,
                "icp-graph: loop closures enter the graph only in groups that agree pair by "
                "pair with the odometry between them (pairwise consistency, the largest "
                "consistent set of the closures of the last 30 keyframes, from at least two "
                "keyframes); false: every closure that passes its own checks enters at once. "
                "Off by default: it did not make the CSAIL or Intel logs better (docs/slam.md)")
          .real("loop_consistency_gate", &SlamParams::loop_consistency_gate, "", 0.1, 1000,
                "icp-graph: two loop closures agree when the squared Mahalanobis distance of "
                "the cycle they close with the odometry is at most this (chi-square, 3 "
                "degrees of freedom: 11.34 is the 99 % quantile)")
          .flag("loop_robust", &SlamParams::loop_robust,
                "icp-graph: optimise the pose graph with dynamic covariance scaling of the "
                "loop closures (carenav's weighted Levenberg-Marquardt; a closure that "
                "disagrees loses weight instead of bending the map); false: MRPT's "
                "Levenberg-Marquardt, every closure at full weight")
          .real("loop_robust_phi", &SlamParams::loop_robust_phi, "", 0.001, 1000,
                "icp-graph: dynamic covariance scaling's Phi: a loop closure whose squared "
                "Mahalanobis residual chi2 exceeds it keeps the share (2 Phi / (Phi + chi2))^2 "
                "of its information")
          .real("odom_dist_frac", &SlamParams::odom_dist_frac, "", 0, 10,
                "icp-graph with odometry: standard deviation of the position of one odometry "
                "step, as a share of its length (the motion prior the scan match is weighed "
                "against; a prior too tight rejects right matches, one too loose lets a "
                "match slide along a corridor)")
          .real("odom_deg_per_m", &SlamParams::odom_deg_per_m, "deg", 0, 90,
                "icp-graph with odometry: standard deviation of the heading of one odometry "
                "step per metre driven")
          .real("odom_turn_frac", &SlamParams::odom_turn_frac, "", 0, 10,
                "icp-graph with odometry: standard deviation of the heading of one odometry "
                "step, as a share of its turn")
          .real("odom_min_xy", &SlamParams::odom_min_xy, "m", 0.001, 10,
                "icp-graph with odometry: smallest position standard deviation of a step")
          .real("odom_min_deg", &SlamParams::odom_min_deg, "deg", 0.01, 90,
                "icp-graph with odometry: smallest heading standard deviation of a step")
          .real("laser_motion_along", &SlamParams::laser_motion_along, "m", 0.01, 10,
                "icp-graph laser only: standard deviation of one step's travel from the last "
                "step's, along the heading halfway through the turn (the motion prior the "
                "scan's likelihood is weighed against in the correlative search)")
          .real("laser_motion_across", &SlamParams::laser_motion_across, "m", 0.01, 10,
                "icp-graph laser only: standard deviation of one step's travel across that "
                "heading (side slip, the arc taken as a straight line; a wheeled robot "
                "does not move sideways)")
          .real("laser_motion_deg", &SlamParams::laser_motion_deg, "deg", 0.1, 180,
                "icp-graph laser only: standard deviation of one step's heading from the "
                "constant-velocity one or the last one, whichever is closer")
          .real("laser_outlier", &SlamParams::laser_outlier, "", 0.001, 0.999,
                "icp-graph laser only: share of a scan's points the submap is expected not "
                "to explain (the floor of a point's likelihood in the correlative search)")
          .real("laser_independence", &SlamParams::laser_independence, "", 0.001, 1,
                "icp-graph laser only: share of the scan points counted as independent "
                "measurements in the correlative search (neighbouring beams err together)");
  return t;
}

const ParamTable<IcpParams>& IcpParams::table() {
  static const auto t =
      ParamTable<IcpParams>()
          .choice("ICP_algorithm", &IcpParams::ICP_algorithm,
                  {"icpClassic", "icpLevenbergMarquardt"}, "MRPT's ICP variant")
          .integer("maxIterations", &IcpParams::maxIterations, "", 1, 10000,
                   "iterations before giving up on convergence")
          .real("thresholdDist", &IcpParams::thresholdDist, "m", 0.001, 10,
                "initial largest distance of a point pair")
          .real("thresholdAng_DEG", &IcpParams::thresholdAng_DEG, "deg", 0, 90,
                "growth of the pairing distance with range")
          .real("ALFA", &IcpParams::ALFA, "", 0.01, 0.999,
                "factor shrinking the thresholds after each convergence")
          .real("smallestThresholdDist", &IcpParams::smallestThresholdDist, "m", 0.001, 10,
                "smallest pairing distance")
          .flag("onlyUniqueRobust", &IcpParams::onlyUniqueRobust,
                "force unique correspondences both ways")
          .integer("corresponding_points_decimation", &IcpParams::corresponding_points_decimation,
                   "", 1, 100, "use every n-th point of the scan");
  return t;
}

const ParamTable<RbpfParams>& RbpfParams::table() {
  static const auto t =
      ParamTable<RbpfParams>()
          .choice("proposal", &RbpfParams::proposal, {"standard", "optimal", "auxiliary-optimal"},
                  "particle proposal: odometry only, or refined by the scan (gmapping-like)")
          .integer("particles", &RbpfParams::particles, "", 1, 5000, "number of particles")
          .real("resample_ess", &RbpfParams::resample_ess, "", 0, 1,
                "resample when the effective sample size ratio falls below")
          .real("lf_std_hit", &RbpfParams::lf_std_hit, "m", 0.005, 5,
                "likelihood-field standard deviation of a hit")
          .real("lf_max_range", &RbpfParams::lf_max_range, "m", 0.5, 200,
                "longest range the likelihood uses")
          .real("localize_lin_distance", &RbpfParams::localize_lin_distance, "m", 0, 10,
                "motion between filter updates")
          .real("localize_ang_distance", &RbpfParams::localize_ang_distance, "deg", 0, 180,
                "turn between filter updates");
  return t;
}

std::string IcpParams::asMrptIni(const std::string& section) const {
  std::string s = "[" + section + "]\n";
  for (const auto& spec : table().specs())
    s += spec.key + " = " + table().get(*this, spec.key) + "\n";
  return s;
}

void registerProfileSections() {
  auto& reg = ProfileSchemas::instance();
  reg.add(SectionSchema::of(SlamParams::table(), "slam", "map building from rawlogs"));
  reg.add(SectionSchema::of(IcpParams::table(), "icp", "ICP scan matcher (MRPT CICP names)"));
  reg.add(SectionSchema::of(RbpfParams::table(), "rbpf", "Rao-Blackwellised particle filter SLAM"));
}

}  // namespace carenav::slam
