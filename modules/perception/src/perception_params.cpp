#include <carenav/common/profile.h>
#include <carenav/perception/perception_params.h>

#include <sstream>

namespace carenav::perception {

namespace {
std::optional<std::vector<double>> parseHeights(const std::string& text) {
  std::vector<double> out;
  std::string t = text;
  for (char& c : t)
    if (c == ',') c = ' ';
  std::istringstream ss(t);
  std::string tok;
  while (ss >> tok) {
    try {
      out.push_back(parseReal(tok));
    } catch (const ParamValueError&) {
      return std::nullopt;
    }
  }
  if (out.empty()) return std::nullopt;
  return out;
}
}  // namespace

std::vector<double> PerceptionParams::kosHeights() const {
  auto h = parseHeights(kos_heights);
  return h ? *h : std::vector<double>{};
}

const ParamTable<PerceptionParams>& PerceptionParams::table() {
  using P = PerceptionParams;
  static const auto t =
      ParamTable<P>()
          .text("sensor", &P::sensor,
                "sensorLabel of the 3D observations to use (empty: every 3D observation)")
          .integer(
              "grid_cells", &P::grid_cells, "", 10, 2000,
              "m_x = m_y: cells per side of the robot-centred local grids ([Garrote17, Table I])")
          .real("resolution", &P::resolution, "m", 0.01, 1, "d_r: cell size ([Garrote17, Table I])")
          .real("outlier_sigma", &P::outlier_sigma, "", 0, 10,
                "per-cell outlier removal: drop elevations farther than this many standard "
                "deviations from the cell mean (0: off)")
          .real("z_min", &P::z_min, "m", -100, 100, "points below (robot frame) are ignored")
          .real("z_max", &P::z_max, "m", -100, 100, "points above (robot frame) are ignored")
          .integer("rrt_iterations", &P::rrt_iterations, "", 1, 100000,
                   "K: RRT-GPD iterations ([Garrote17, Table I])")
          .real("normal_threshold", &P::normal_threshold, "", 0, 1,
                "N_th: similar normals when 1 - |n1.n2| <= N_th ([Garrote17, Table I])")
          .real("elevation_threshold", &P::elevation_threshold, "m", 0, 10,
                "E_th: largest elevation step between connected nodes ([Garrote17, Table I])")
          .integer("window", &P::window, "cells", 3, 31,
                   "s_x = s_y: neighbourhood of plane fits and IDW ([Garrote17, Table I])")
          .real("expansion_distance", &P::expansion_distance, "m", 0.01, 10,
                "d_n: RRT node expansion distance ([Garrote17, Table I])")
          .flag("seed_upright", &P::seed_upright,
                "the RRT seed plane must also pass the normal test against the robot's up axis")
          .integer("seed_attempts", &P::seed_attempts, "", 1, 1000,
                   "RRT-GPD: seeds tried (each at least d_n from the others) while the tree "
                   "stays smaller than min_tree_nodes")
          .integer("min_tree_nodes", &P::min_tree_nodes, "", 1, 100000,
                   "RRT-GPD: a tree needs this many nodes (and its plane this many inliers) to "
                   "give the ground plane; smaller trees are refused")
          .real("prior_height_tolerance", &P::prior_height_tolerance, "m", 0, 10,
                "RRT-GPD: a plane whose height at the robot is within this of z = 0 (the floor "
                "the mounting says the robot stands on) ends the seed attempts; the plane "
                "nearest to z = 0 wins, one farther is reported in summary.json")
          .real("prior_tilt_deg", &P::prior_tilt_deg, "deg", 0, 90,
                "uncertainty of the mounting's pitch and of its roll (each): the steep-ground "
                "rule measures slopes against the ground plane while it is tilted less than "
                "sqrt(2) times this from the robot frame's level, against that level otherwise")
          .flag("mounting_calibrated", &P::mounting_calibrated,
                "the sensor pose is the robot's calibrated mounting (navigation sets it): a "
                "plane more than d_pth below z = 0 at the robot is a lower floor beyond a drop "
                "from the first frame on; otherwise only once a frame found the floor at z = 0 "
                "(the pose of a recorded cloud may be off)")
          .real("seed_max_elevation", &P::seed_max_elevation, "m", 0, 100,
                "the RRT seed must lie within this height of the floor the robot stands on "
                "(robot frame z = 0): the robot pose is the initial guess of [Garrote17, Alg. 1]")
          .integer("ransac_iterations", &P::ransac_iterations, "", 1, 100000,
                   "iterations of the RANSAC plane fits")
          .real("ransac_threshold", &P::ransac_threshold, "m", 0.001, 1,
                "inlier distance of the RANSAC plane fits")
          .integer("seed", &P::seed, "", 0, 2147483647, "random seed")
          .real("d_pth", &P::d_pth, "m", 0, 1,
                "voxels farther than this from the ground plane are obstacles ([Garrote17, Table "
                "I]); "
                "with depth_noise_std the threshold grows to noise_k vertical depth sigmas")
          .real("depth_noise_std", &P::depth_noise_std, "m", 0, 1,
                "depth noise model of the 3D sensor: std of the depth at 1 m range, growing with "
                "the square of the range (sigma(r) = depth_noise_std r^2); 0: no noise model, "
                "fixed d_pth ([Garrote17]). Set it to the sensor's noise_std")
          .real("noise_k", &P::noise_k, "", 0, 20,
                "voxel z+/z- farther than noise_k vertical noise sigmas at the voxel's range "
                "(and means farther than noise_k standard errors) are not noise")
          .real("noise_adapt_max", &P::noise_adapt_max, "", 1, 100,
                "the depth noise measured in each frame (median over the voxels of their "
                "vertical spread against depth_noise_std's prediction) raises the noise model "
                "by up to this factor, never lowers it; 1: depth_noise_std as given")
          .real("mean_step", &P::mean_step, "m", 0, 1,
                "a voxel whose mean elevation lies more than this (plus noise_k standard errors) "
                "off the ground plane is an obstacle: small boxes >= 20 mm ([Puente14, App. Sec. "
                "VI]); "
                "0: off")
          .real("max_slope_deg", &P::max_slope_deg, "deg", 0, 45,
                "off-plane voxels flat within the noise and connected to the ground through "
                "steps no steeper than this slope (plus noise) are traversable (ramps); 0: off")
          .real("mean_k", &P::mean_k, "", 0, 20,
                "ramp rule: differences of voxel means may exceed the max_slope rise by this "
                "many standard errors (noise of the means)")
          .integer("region_min_cells", &P::region_min_cells, "cells", 3, 1000000,
                   "ramps by region: a connected region of voxel means that share one plane "
                   "within the noise is judged by its own plane fit once it holds this many "
                   "cells (smaller ones by the 7 x 7 window of the steep-ground rule)")
          .real("region_tolerance", &P::region_tolerance, "m", 0, 1,
                "ramps by region: a cell joins a region while its mean lies within noise_k "
                "times sqrt(standard error^2 + this^2) of the region's plane (the model error "
                "of a cell mean besides the depth noise)")
          .real("region_trim_k", &P::region_trim_k, "", 0.5, 20,
                "ramps by region: a region's slope is fitted to its cells farther from its "
                "border than this many depth-noise sigmas (the noise smears a kink, a ramp's "
                "foot, over that) plus the distance a max_slope_deg kink stays within the "
                "growth band, refitted 3 times to the cells within this many standard errors "
                "of the previous fit")
          .real("k_g", &P::k_g, "", 0, 0.5, "K_g: ground amplitude gain ([Garrote17, Table I])")
          .real("sigma2", &P::sigma2, "m^2", 1e-6, 10, "sigma^2: ISM Gaussian variance")
          .real("k_n", &P::k_n, "", 0, 10, "K_n: voxel density sample normalisation factor")
          .real("d_min", &P::d_min, "", 0, 1000, "d_min: voxel density minimum number of points")
          .real("k_m", &P::k_m, "", 0, 1, "K_m: voxel density amplitude gain")
          .real("occupied_threshold", &P::occupied_threshold, "", 0.5, 1,
                "cells whose occupancy probability is above count as occupied")
          .real("free_threshold", &P::free_threshold, "", 0, 0.5,
                "cells whose occupancy probability is below count as free")
          .real("logodds_max", &P::logodds_max, "", 0.1, 50,
                "clamp of the fused log-odds (keeps the local grid responsive)")
          .real("band_z_min", &P::band_z_min, "m", -10, 10,
                "height-band baseline: lowest obstacle height ([Rosa17, Sec. 5.3])")
          .real("band_z_max", &P::band_z_max, "m", -10, 10,
                "height-band baseline: highest obstacle height")
          .real("depth_min", &P::depth_min, "m", 0, 100, "shortest valid depth")
          .real("depth_max", &P::depth_max, "m", 0, 100, "longest valid depth")
          .integer("fspf_n_min", &P::fspf_n_min, "", 3, 100000,
                   "FSPF+ nMin: fewest inliers of an accepted plane ([InterbotDepth, Table 3.1])")
          .integer("fspf_omega", &P::fspf_omega, "px", 1, 10000,
                   "FSPF+ Omega: neighbourhood of the second and third samples")
          .real("fspf_window", &P::fspf_window, "m", 0.01, 10,
                "FSPF+ A: plane size in world space of the local window")
          .real("fspf_epsilon", &P::fspf_epsilon, "m", 0.001, 1,
                "FSPF+ epsilon: inlier distance of the local RANSAC")
          .real("fspf_stop_fraction", &P::fspf_stop_fraction, "", 0, 1,
                "FSPF+ stops when this share of the eligible pixels is left (0.01 offline, "
                "0.1 real time)")
          .text("kos_heights", &P::kos_heights,
                "Kinect Obstacle Scan: scan heights in m (robot frame), space separated")
          .real("kos_band", &P::kos_band, "m", 0.001, 10, "KOS: half-height of each slab")
          .real("scan_resolution", &P::scan_resolution, "deg", 0.05, 10,
                "virtual scans: bearing bin width")
          .real("maxrule_height", &P::maxrule_height, "m", -10, 10,
                "max-rule localisation scan: height of the scan plane (robot frame)")
          .real("maxrule_slab", &P::maxrule_slab, "m", 0.001, 10,
                "max-rule localisation scan: slab thickness around the scan plane")
          .check([](const P& p) -> std::optional<std::string> {
            if (p.window % 2 == 0) return "window must be odd";
            return std::nullopt;
          })
          .check([](const P& p) -> std::optional<std::string> {
            if (p.z_min >= p.z_max) return "z_min must be smaller than z_max";
            if (p.band_z_min >= p.band_z_max) return "band_z_min must be smaller than band_z_max";
            if (p.depth_min >= p.depth_max) return "depth_min must be smaller than depth_max";
            return std::nullopt;
          })
          .check([](const P& p) -> std::optional<std::string> {
            if (!parseHeights(p.kos_heights))
              return "kos_heights must list one or more heights in m";
            return std::nullopt;
          });
  return t;
}

void registerProfileSections() {
  ProfileSchemas::instance().add(SectionSchema::of(
      PerceptionParams::table(), "perception",
      "3D point clouds to 2.5D elevation grid, RRT-GPD ground plane and 2D local occupancy "
      "grid; virtual 2D scans from depth"));
}

}  // namespace carenav::perception
