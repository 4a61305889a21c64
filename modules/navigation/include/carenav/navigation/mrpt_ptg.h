// The mrpt-ptg local planner: MRPT's TP-space reactive navigation (mrpt::nav
// PTGs and a holonomic method, the parts CReactiveNavigationSystem is made
// of) behind carenav's LocalPlanner interface, so that the dynamic
// window can be compared with MRPT's own method on the same scenarios.
#pragma once

#include <carenav/common/params.h>
#include <carenav/navigation/local_planner.h>

#include <memory>
#include <string>

namespace carenav {
class Profile;
}

namespace carenav::navigation {

/** [nav.mrpt_ptg]: parameters of the mrpt-ptg plugin. The robot's limits
 *  (v_max, w_max) and its footprint (the PTGs' polygonal shape) come from
 *  [robot]; the goal tolerances from [navigation].
 *  ```ini
 *  [nav.mrpt_ptg]
 *  ptgs = c+alpha        ; c | alpha | c+alpha
 *  num_paths = 121
 *  ref_distance = 3.0    ; m
 *  holonomic = full-eval ; full-eval | nd
 *  ```
 */
struct MrptPtgParams {
  /** Path families: "c" (CPTG_DiffDrive_C, circular arcs), "alpha"
   *  (CPTG_DiffDrive_alpha, turns first, then drives), or both, one chosen
   *  per cycle. */
  std::string ptgs = "c+alpha";
  int num_paths = 121;        ///< discrete paths (alpha values) per PTG
  double ref_distance = 3.0;  ///< m, obstacles are seen this far along each path (D_max)
  double resolution = 0.05;   ///< m, cell size of the PTGs' collision look-up grid
  /** m, the PTGs' robot shape is the footprint grown by [navigation]
   *  footprint_padding plus this (obstacles are cell centres, and the PTGs'
   *  collision look-up grid is approximate to its resolution). */
  double shape_margin = 0.05;
  double cte_a0_deg = 45;               ///< deg, alpha PTG: width of its velocity profiles
  std::string holonomic = "full-eval";  ///< TP-space method: full-eval (CHolonomicFullEval) | nd
  /** Feed the clearance diagram to the holonomic method; full-eval needs it
   *  (false is only valid with nd). */
  bool evaluate_clearance = true;
  /** Normalised free distance [0, 1] along the chosen path at and below
   *  which the speed is 0, and above secure_end at which it is full (a
   *  ramp in between, as CAbstractPTGBasedReactive's secure distance). */
  double secure_start = 0.05;
  double secure_end = 0.15;
  /** m, the target is this far along the route (the final goal when
   *  nearer); farther than [navigation] lookahead, so that the holonomic
   *  method sees an obstacle on the route while there is room to avoid it. */
  double lookahead = 2.5;
  double goal_turn_gain = 1.5;  ///< 1/s, w = gain * heading error when turning at the goal
  static const ParamTable<MrptPtgParams>& table();
};

/** The mrpt-ptg planner with explicit parameters. Builds the PTGs' look-up
 *  tables (a fraction of a second). Throws InputError for a footprint or
 *  limits MRPT cannot use. */
std::unique_ptr<LocalPlanner> makeMrptPtg(const NavigationParams& p, const RobotParams& r,
                                          const MrptPtgParams& ptg);

/** One line for `--help` and the registry's list. */
const char* mrptPtgDescription();

/** Re-registers "mrpt-ptg" in the PlannerRegistry with the profile's
 *  [nav.mrpt_ptg] values (defaults for absent keys), so that planners the
 *  registry creates afterwards use them. Throws InputError for a bad value. */
void configureMrptPtg(const Profile& profile);

}  // namespace carenav::navigation
