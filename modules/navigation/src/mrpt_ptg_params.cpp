// [nav.mrpt_ptg]: the parameters of the mrpt-ptg local planner.
#include <carenav/navigation/mrpt_ptg.h>

namespace carenav::navigation {

const ParamTable<MrptPtgParams>& MrptPtgParams::table() {
  using P = MrptPtgParams;
  static const auto t =
      ParamTable<P>()
          .choice("ptgs", &P::ptgs, {"c", "alpha", "c+alpha"},
                  "path families: c (circular arcs, CPTG_DiffDrive_C), alpha (turn first, "
                  "CPTG_DiffDrive_alpha) or both, the better one chosen each cycle")
          .integer("num_paths", &P::num_paths, "", 11, 721,
                   "discrete paths (alpha values) per path family")
          .real("ref_distance", &P::ref_distance, "m", 0.5, 20,
                "obstacles are seen this far along each path (D_max); keep it below half of "
                "[navigation] local_size")
          .real("resolution", &P::resolution, "m", 0.01, 0.5,
                "cell size of the path families' collision look-up grid")
          .real("shape_margin", &P::shape_margin, "m", 0, 1,
                "the paths' robot shape is the footprint grown by [navigation] "
                "footprint_padding plus this (cell size, look-up grid error)")
          .real("cte_a0_deg", &P::cte_a0_deg, "deg", 1, 180,
                "alpha paths: width of their speed and turn-rate profiles")
          .choice("holonomic", &P::holonomic, {"full-eval", "nd"},
                  "method in TP-space: full-eval (CHolonomicFullEval) or nd (nearness "
                  "diagram, CHolonomicND)")
          .flag("evaluate_clearance", &P::evaluate_clearance,
                "give the holonomic method the clearance along each path (slower)")
          .real("secure_start", &P::secure_start, "", 0, 1,
                "normalised free distance on the chosen path at which the speed is 0")
          .real("secure_end", &P::secure_end, "", 0, 1,
                "normalised free distance from which the speed is full (ramp from secure_start)")
          .real("lookahead", &P::lookahead, "m", 0.1, 20,
                "the target is this far along the route (the goal when nearer)")
          .real("goal_turn_gain", &P::goal_turn_gain, "1/s", 0.01, 100,
                "at the goal: turn rate per radian of heading error (turn in place)")
          .check([](const P& q) -> std::optional<std::string> {
            if (q.secure_end <= q.secure_start) return "secure_end must exceed secure_start";
            // CHolonomicFullEval scores each path's clearance and asserts it is given.
            if (q.holonomic == "full-eval" && !q.evaluate_clearance)
              return "evaluate_clearance = false needs holonomic = nd (full-eval scores the "
                     "clearance of every path)";
            return std::nullopt;
          });
  return t;
}

}  // namespace carenav::navigation
