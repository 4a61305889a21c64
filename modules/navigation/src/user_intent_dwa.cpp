// user-intent-dwa: [Rosa17]'s shared control for the ISR-AIWALKER walker.
#include <carenav/navigation/local_planner.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace carenav::navigation {

namespace {

class UserIntentDwa final : public LocalPlanner {
 public:
  /** `deadband`: user commands below it mean stop ([nav.safety] intent_deadband). */
  UserIntentDwa(const DwaParams& d, const UserIntentDwaParams& k, double deadband,
                const RobotParams& r)
      : d_(d), k_(k), deadband_(deadband), r_(r), v_scale_(std::max({r.v_max, -r.v_min, 1e-6})) {}
  std::string name() const override { return "user-intent-dwa"; }
  bool needsUserIntent() const override { return true; }

  PlannerOutput plan(const PlannerInput& in) override {
    PlannerOutput out;
    if (!in.user || !in.map) {
      out.mark(PlanStatus::NoUserCommand);
      return out;
    }
    const Twist u = *in.user;
    // The user lets go: stop (braking is always reachable).
    if (std::abs(u.v) < deadband_ && std::abs(u.w) < deadband_) {
      out.ok = true;
      out.mark(PlanStatus::UserStopped);
      return out;
    }
    const Window win = dynamicWindow(in.current, r_, d_);
    // The user's own command is a candidate, so that on a free path it
    // passes unchanged.
    const auto samples = sampleWindow(win, d_, {u});
    // Where the user's command would take the walker (d_p of Eq. 4.10).
    const TPose2D intended = integrateArc(in.pose, u.v, u.w, d_.sim_time);
    const double cap = d_.clearance_influence;
    double best = std::numeric_limits<double>::infinity();
    for (const Twist& s : samples) {
      Trajectory tr =
          rollout(*in.map, in.pose, s, d_.sim_time, d_.sim_step, cap, d_.obstacle_distance_cap);
      ++out.evaluated;
      // Admissible (Eq. 4.1): the walker can brake safe_distance before the
      // first contact (the margin the safety supervisor enforces, so that
      // what is chosen here passes it).
      if (!tr.leaves_map && canBrake(s, tr.time_to_collision, r_, r_.safe_distance,
                                     in.map->footprint().circumscribed)) {
        ++out.admissible;
        // Eq. 4.10: C = |(v - v_u, w - w_u)| + k_s C_occ + k_0 / C_obs
        //               + k_1 [direction differs] + k_2 * pose term.
        // C_obs is dist(v, w) of Eq. 4.1, the free distance along the arc
        // (checked at least obstacle_distance_cap far, even for slow arcs),
        // capped there: farther obstacles do not matter, so a free path
        // costs only the mismatch. The pose term as printed, k_2 / (1 + d_p),
        // would reward ending far from where the user wants to go; we use
        // the increasing k_2 d_p / (1 + d_p), which keeps its range and its
        // scale.
        // The mismatch mixes m/s and rad/s; each is taken relative to the
        // robot's limit (v_max, w_max) so that slowing down is not cheaper
        // than steering around an obstacle merely because of the units.
        const double mismatch =
            std::hypot((s.v - u.v) / v_scale_, (s.w - u.w) / std::max(r_.w_max, 1e-6));
        const double c_obs = std::max(std::min(tr.free_distance, d_.obstacle_distance_cap), 1e-3);
        // "Direction differs from the user's": driving backwards while the
        // user pushes forwards, or the reverse.
        const bool reversed = (s.v > 1e-6 && u.v < -1e-6) || (s.v < -1e-6 && u.v > 1e-6);
        const double d_p = std::hypot(tr.end.x - intended.x, tr.end.y - intended.y);
        tr.cost = mismatch + k_.k_s * tr.occupancy + k_.k_0 / c_obs + (reversed ? k_.k_1 : 0.0) +
                  k_.k_2 * d_p / (1 + d_p);
        if (tr.cost < best - 1e-12) {
          best = tr.cost;
          out.cmd = s;
          out.ok = true;
        }
      }
      out.trajectories.push_back(tr);
    }
    if (!out.ok) out.mark(PlanStatus::NoAdmissible);
    return out;
  }

 private:
  DwaParams d_;
  UserIntentDwaParams k_;
  double deadband_;
  RobotParams r_;
  double v_scale_;
};

}  // namespace

std::unique_ptr<LocalPlanner> makeUserIntentDwa(const NavigationParams& p, const RobotParams& r) {
  return std::make_unique<UserIntentDwa>(p, p, p.intent_deadband, r);
}

}  // namespace carenav::navigation
