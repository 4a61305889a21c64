// Parameters of `carenav slam`: the profile's [slam] and [icp] sections.
#pragma once

#include <carenav/common/params.h>

#include <string>

namespace carenav::slam {

/** [slam]: how a map is built from a rawlog.
 *  ```ini
 *  [slam]
 *  method = icp-graph
 *  sensor = LASER            ; "" takes the first 2D scan of each entry
 *  grid_resolution = 0.05
 *  ```
 */
struct SlamParams {
  std::string method = "icp-graph";        ///< icp | icp-graph | rbpf
  std::string sensor;                      ///< sensorLabel of the 2D scans to map with ("" any)
  bool use_odometry = true;                ///< false: laser only (odometry ignored)
  double localization_lin_distance = 0.2;  ///< m, robot motion between ICP corrections
  double localization_ang_distance = 5;    ///< deg
  double insertion_lin_distance = 0.5;     ///< m, motion between scans inserted in the map
  double insertion_ang_distance = 20;      ///< deg
  double min_icp_goodness = 0.4;           ///< [0,1] ICP quality to accept a correction
  double grid_resolution = 0.05;           ///< m, cell size of the output occupancy grid
  double scan_range_max = 0;               ///< m, drop longer ranges (0: keep the scan's own)
  // icp-graph only
  double keyframe_distance = 0.5;        ///< m, motion between keyframes (pose-graph nodes)
  double keyframe_angle = 20;            ///< deg
  double loop_search_radius = 4.0;       ///< m, keyframes this close are loop candidates (at least)
  double loop_search_max = 15.0;         ///< m, largest search radius the drift can ask for
  int loop_min_separation = 20;          ///< keyframes between a candidate and the current one
  double loop_min_goodness = 0.8;        ///< [0,1] ICP quality trusted at its covariance
  double loop_min_agreement = 0.9;       ///< [0,1] visibility agreement of a loop closure
  double loop_min_overlap = 0.25;        ///< [0,1] share of both scans' points seen by the other
  double loop_min_distinct = 0.15;       ///< [0,1] overlap lost when the match moves 0.3 m
  double loop_max_correction = 3.0;      ///< m, largest loop-closure correction accepted
  bool loop_consistency = false;         ///< closures enter the graph in pairwise-consistent groups
  double loop_consistency_gate = 11.34;  ///< chi2 (3 dof) of two consistent closures' cycle
  bool loop_robust = false;              ///< dynamic covariance scaling of loop edges
  double loop_robust_phi = 1.0;          ///< DCS Phi: chi2 above it scales a closure down
  // icp-graph with odometry: the motion prior (MotionNoise, motion_prior.h)
  double odom_dist_frac = 0.10;  ///< position std dev, share of the distance driven
  double odom_deg_per_m = 2.0;   ///< deg, heading std dev per m driven
  double odom_turn_frac = 0.05;  ///< heading std dev, share of the turn
  double odom_min_xy = 0.03;     ///< m, floor of the position std dev
  double odom_min_deg = 1.0;     ///< deg, floor of the heading std dev
  // icp-graph laser only: the correlative search (CorrelativeMatcher::Parameters)
  double laser_motion_along = 0.5;    ///< m, std dev of a step's travel along the mid heading
  double laser_motion_across = 0.15;  ///< m, std dev across it
  double laser_motion_deg = 30;       ///< deg, std dev of a step's heading
  double laser_outlier = 0.2;         ///< share of scan points the submap does not explain
  double laser_independence = 0.2;    ///< share of scan points counted as independent
  static const ParamTable<SlamParams>& table();
};

/** [icp]: the scan matcher, with MRPT's CICP::TConfigParams key names so an
 *  icp-slam [ICP] section can be copied over. */
struct IcpParams {
  std::string ICP_algorithm = "icpClassic";  ///< icpClassic | icpLevenbergMarquardt
  int maxIterations = 80;
  double thresholdDist = 0.3;           ///< m, initial pairing distance
  double thresholdAng_DEG = 5;          ///< deg, pairing distance growth with range
  double ALFA = 0.8;                    ///< threshold shrink factor after convergence
  double smallestThresholdDist = 0.05;  ///< m
  bool onlyUniqueRobust = true;
  int corresponding_points_decimation = 5;
  static const ParamTable<IcpParams>& table();
  /** The values as an MRPT [section] that CICP::TConfigParams reads. */
  std::string asMrptIni(const std::string& section) const;
};

/** [rbpf]: the Rao-Blackwellised particle filter of MRPT's
 *  CMetricMapBuilderRBPF (grid maps, gmapping-like optimal proposal). */
struct RbpfParams {
  std::string proposal = "optimal";    ///< standard | optimal | auxiliary-optimal
  int particles = 20;                  ///< sample size (fixed)
  double resample_ess = 0.5;           ///< resample when ESS / N falls below
  double lf_std_hit = 0.2;             ///< m, likelihood-field sigma
  double lf_max_range = 30;            ///< m, ranges used by the likelihood
  double localize_lin_distance = 0.4;  ///< m, motion between filter updates
  double localize_ang_distance = 20;   ///< deg
  static const ParamTable<RbpfParams>& table();
};

/** Registers [slam], [icp] and [rbpf] with the profile schemas. */
void registerProfileSections();

}  // namespace carenav::slam
