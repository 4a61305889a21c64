// mrpt-ptg: MRPT's TP-space reactive navigation behind the LocalPlanner
// interface. Each cycle does what CAbstractPTGBasedReactive does in one
// navigation step (Blanco, Gonzalez and Fernandez-Madrigal, "Extending
// obstacle avoidance methods through multiple parameter-space
// transformations", Autonomous Robots 24(1), 2008), on carenav's local cost
// map instead of MRPT's robot interface, and without its timing and threads:
//  1. the occupied cells of the cost map within reach become obstacle points
//     in the robot frame;
//  2. per PTG, every point becomes the collision-free distance of each path
//     (updateTPObstacle), and the target (the route's look-ahead point or the
//     goal) a point of TP-space (inverseMap_WS2TP);
//  3. the holonomic method (CHolonomicFullEval or CHolonomicND) picks a
//     direction and a speed in that space;
//  4. of the PTGs' candidates the one whose path ends nearest to the target
//     wins; its path index becomes (v, w) (directionToMotionCommand), scaled
//     by the holonomic speed and by a ramp on the free distance ahead.
// MRPT's reactive navigator does not align the heading at the goal: within
// the goal tolerance this plugin turns on the spot like goal-dwa does.
#include <carenav/common/errors.h>
#include <carenav/common/profile.h>
#include <carenav/navigation/mrpt_ptg.h>

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/kinematics/CVehicleVelCmd_DiffDriven.h>
#include <mrpt/nav/holonomic/CHolonomicFullEval.h>
#include <mrpt/nav/holonomic/CHolonomicND.h>
#include <mrpt/nav/holonomic/ClearanceDiagram.h>
#include <mrpt/nav/tpspace/CPTG_DiffDrive_C.h>
#include <mrpt/nav/tpspace/CPTG_DiffDrive_alpha.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <optional>

namespace carenav::navigation {

namespace {

/** Where MRPT's PTG collision-grid cache goes: $XDG_CACHE_HOME/carenav,
 *  ~/.cache/carenav, else the temporary folder; named by the PTG and a hash
 *  of the robot's shape and the grid's parameters, so that each robot keeps
 *  its own grid (MRPT rebuilds a grid whose parameters do not match). */
std::string ptgCacheFile(const std::string& description, const std::string& key) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::path dir;
  if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x)
    dir = fs::path(x) / "carenav";
  else if (const char* h = std::getenv("HOME"); h && *h)
    dir = fs::path(h) / ".cache" / "carenav";
  if (dir.empty() || (fs::create_directories(dir, ec), ec) || !fs::is_directory(dir))
    dir = fs::temp_directory_path(ec);
  std::string name;
  for (const char c : description) name += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  const std::size_t h = std::hash<std::string>{}(key);
  return (dir / ("ptg_" + name.substr(0, 60) + "_" + std::to_string(h) + ".bin.gz")).string();
}

/** The polygon offset outwards by `d` (mitred corners): each vertex moves
 *  along the sum of its two edges' outward unit normals n1, n2 by
 *  d / (1 + n1 . n2), which keeps every edge parallel at distance d. */
std::vector<Point2> grow(const std::vector<Point2>& poly, double d) {
  const size_t n = poly.size();
  double area2 = 0;
  for (size_t i = 0; i < n; ++i) {
    const auto& a = poly[i];
    const auto& b = poly[(i + 1) % n];
    area2 += a.x * b.y - b.x * a.y;
  }
  const double orient = area2 >= 0 ? 1.0 : -1.0;  // counter-clockwise: outward = (dy, -dx)
  auto normal = [&](const Point2& a, const Point2& b) {
    const double dx = b.x - a.x, dy = b.y - a.y, l = std::hypot(dx, dy);
    return l > 0 ? Point2{orient * dy / l, -orient * dx / l} : Point2{0, 0};
  };
  std::vector<Point2> out(n);
  for (size_t i = 0; i < n; ++i) {
    const Point2 n1 = normal(poly[(i + n - 1) % n], poly[i]);
    const Point2 n2 = normal(poly[i], poly[(i + 1) % n]);
    const double k = d / std::max(1 + n1.x * n2.x + n1.y * n2.y, 0.1);
    out[i] = {poly[i].x + k * (n1.x + n2.x), poly[i].y + k * (n1.y + n2.y)};
  }
  return out;
}

/** One path family with its holonomic method (the method keeps state between
 *  cycles, e.g. hysteresis, so each PTG has its own). */
struct Family {
  std::unique_ptr<mrpt::nav::CParameterizedTrajectoryGenerator> ptg;
  std::unique_ptr<mrpt::nav::CAbstractHolonomicReactiveMethod> holo;
  std::vector<double> tp_obstacles;  // m, then normalised by the reference distance
  mrpt::nav::ClearanceDiagram clearance;
};

class MrptPtg final : public LocalPlanner {
 public:
  MrptPtg(const NavigationParams& p, const RobotParams& r, const MrptPtgParams& q)
      : p_(p), r_(r), q_(q) {
    if (r.footprint.size() < 3) throw InputError("mrpt-ptg: [robot] footprint needs 3 vertices");
    if (!(r.v_max > 0) || !(r.w_max > 0))
      throw InputError("mrpt-ptg: [robot] v_max and w_max must be positive");
    if (!(q.secure_end > q.secure_start))
      throw InputError("[nav.mrpt_ptg] secure_end must be larger than secure_start");
    if (q.holonomic == "full-eval" && !q.evaluate_clearance)
      throw InputError("[nav.mrpt_ptg] evaluate_clearance = false needs holonomic = nd");
    const bool c = q.ptgs == "c" || q.ptgs == "c+alpha";
    const bool alpha = q.ptgs == "alpha" || q.ptgs == "c+alpha";
    if (!c && !alpha) throw InputError("[nav.mrpt_ptg] ptgs: unknown value '" + q.ptgs + "'");
    if (c) families_.push_back(makeFamily("C"));
    if (alpha) families_.push_back(makeFamily("alpha"));
  }

  std::string name() const override { return "mrpt-ptg"; }
  bool needsUserIntent() const override { return false; }

  PlannerOutput plan(const PlannerInput& in) override {
    PlannerOutput out;
    const auto route = routeAhead(in);
    if (!route) {
      out.mark(PlanStatus::NoRoute);
      return out;
    }
    const std::vector<TPoint2D>& path = route->path;
    const TPoint2D last = path.back();
    if (in.goal && route->to_end < p_.goal_tolerance) return alignAtGoal(in);

    const TPoint2D target = lookaheadPoint(path, in.pose.x, in.pose.y, q_.lookahead);
    const double c = std::cos(in.pose.phi), s = std::sin(in.pose.phi);
    const double tdx = target.x - in.pose.x, tdy = target.y - in.pose.y;
    Aim aim;
    aim.rel_target = {c * tdx + s * tdy, -s * tdx + c * tdy};
    aim.is_goal = in.goal && std::hypot(target.x - last.x, target.y - last.y) < 1e-6;
    aim.obstacles = obstaclePoints(*in.map, in.pose);
    aim.current = in.current;

    Candidate best;
    bool found = false;
    for (size_t f = 0; f < families_.size(); ++f) {
      const auto cand = evaluateFamily(f, aim, out);
      if (cand && cand->score > best.score) {
        best = *cand;
        found = true;
      }
    }
    if (!found || !command(best, out)) {
      out.mark(PlanStatus::NoAdmissible);
      return out;
    }
    out.trajectories.push_back(
        rollout(*in.map, in.pose, out.cmd, p_.sim_time, p_.sim_step, p_.clearance_influence, 0));
    return out;
  }

 private:
  /** Where the robot aims this cycle, in its own frame, and what it sees. */
  struct Aim {
    mrpt::math::TPoint2D rel_target;
    bool is_goal = false;  ///< the target is the goal itself (slow down towards it)
    std::vector<mrpt::math::TPoint2D> obstacles;
    Twist current;  ///< the measured velocity
  };
  /** The path one family's holonomic method picks, with its score. */
  struct Candidate {
    size_t family = 0;
    uint16_t k = 0;
    double speed = 0, free = 0, score = -std::numeric_limits<double>::infinity();
  };

  /** Family f's TP-space obstacles and holonomic choice; nothing when it
   *  offers no path with a secure start. Counts the paths into `out`. */
  std::optional<Candidate> evaluateFamily(size_t f, const Aim& aim, PlannerOutput& out) {
    const mrpt::math::TPoint2D& rel_target = aim.rel_target;
    const bool target_is_goal = aim.is_goal;
    const auto& obstacles = aim.obstacles;
    Family& fam = families_[f];
    auto& ptg = *fam.ptg;
    const double ref = ptg.getRefDistance();
    mrpt::nav::CParameterizedTrajectoryGenerator::TNavDynamicState dyn;
    dyn.curVelLocal = {aim.current.v, 0, aim.current.w};
    dyn.relTarget = {rel_target.x, rel_target.y, 0};
    dyn.targetRelSpeed = 0;
    ptg.updateNavDynamicState(dyn);

    ptg.initTPObstacles(fam.tp_obstacles);
    if (q_.evaluate_clearance) ptg.initClearanceDiagram(fam.clearance);
    for (const auto& o : obstacles) {
      ptg.updateTPObstacle(o.x, o.y, fam.tp_obstacles);
      if (q_.evaluate_clearance) ptg.updateClearance(o.x, o.y, fam.clearance);
    }
    if (q_.evaluate_clearance) ptg.updateClearancePost(fam.clearance, fam.tp_obstacles);
    // Normalised free distances, each shortened by the robot's safe
    // distance (the supervisor stops the robot that far before a contact
    // along its path, so a path is only free up to there).
    const double margin = r_.safe_distance / ref;
    for (double& d : fam.tp_obstacles)
      d = d >= ref * (1 - 1e-9) ? 1.0 : std::clamp(d / ref - margin, 0.0, 1.0);
    out.evaluated += fam.tp_obstacles.size();
    for (double d : fam.tp_obstacles) out.admissible += d > q_.secure_start;

    int tk = 0;
    double td = 0;
    ptg.inverseMap_WS2TP(rel_target.x, rel_target.y, tk, td);
    td = std::clamp(td, 0.0, 1.0);
    const double talpha = ptg.index2alpha(static_cast<uint16_t>(tk));

    mrpt::nav::CAbstractHolonomicReactiveMethod::NavInput ni;
    ni.obstacles = fam.tp_obstacles;
    ni.targets = {{std::cos(talpha) * td, std::sin(talpha) * td}};
    ni.maxRobotSpeed = 1.0;
    ni.maxObstacleDist = 1.0;
    ni.clearance = q_.evaluate_clearance ? &fam.clearance : nullptr;
    mrpt::nav::CAbstractHolonomicReactiveMethod::NavOutput no;
    fam.holo->enableApproachTargetSlowDown(target_is_goal);
    fam.holo->navigate(ni, no);
    if (!(no.desiredSpeed > 0)) return std::nullopt;

    Candidate cand;
    cand.family = f;
    cand.k = ptg.alpha2index(no.desiredDirection);
    cand.free = fam.tp_obstacles[cand.k];
    if (cand.free <= q_.secure_start) return std::nullopt;
    cand.speed = std::min(1.0, no.desiredSpeed);
    // Score: how near to the target the robot gets along the chosen path
    // before its first obstacle (or at the target's distance), as the
    // "euclidean_nearness" and "collision_free_distance" terms of MRPT's
    // example configuration of CMultiObjMotionOpt_Scalarization.
    const double along = std::min(cand.free, td) * ref;
    uint32_t step = 0;
    mrpt::math::TPose2D end{0, 0, 0};
    if (ptg.getPathStepForDist(cand.k, along, step)) end = ptg.getPathPose(cand.k, step);
    const double e = std::hypot(end.x - rel_target.x, end.y - rel_target.y);
    cand.score = ptg.getScorePriority() *
                 (1.0 / (1.0 + e * e) + 0.5 * std::min(1.0, cand.free / std::max(td, 1e-3)));
    return cand;
  }

  /** The velocity command along the best candidate's path into `out`;
   *  false when it comes to no motion. */
  bool command(const Candidate& best, PlannerOutput& out) {
    const Family& fam = families_[best.family];
    const auto cmd = fam.ptg->directionToMotionCommand(best.k);
    const auto* dd = dynamic_cast<const mrpt::kinematics::CVehicleVelCmd_DiffDriven*>(cmd.get());
    if (!dd) return false;
    // Secure-distance ramp on the free distance of the chosen path.
    const double ramp =
        std::clamp((best.free - q_.secure_start) / (q_.secure_end - q_.secure_start), 0.0, 1.0);
    // And slow enough to brake within that free distance (v^2 / 2 a <= d).
    const double brake =
        std::min(1.0, std::sqrt(2 * r_.acc_v * best.free * fam.ptg->getRefDistance()) / r_.v_max);
    const double scale = best.speed * std::min(ramp, brake);
    out.cmd = {std::clamp(dd->lin_vel * scale, r_.v_min, r_.v_max),
               std::clamp(dd->ang_vel * scale, -r_.w_max, r_.w_max)};
    // Speeds below a millimetre (or milliradian) per second are no motion:
    // the alpha paths' speed profile falls off as exp(-alpha^2) and would
    // otherwise leave a crawl of 1e-8 m/s on its sharp turns.
    if (std::abs(out.cmd.v) < 1e-3) out.cmd.v = 0;
    if (std::abs(out.cmd.w) < 1e-3) out.cmd.w = 0;
    out.ok = out.cmd.v != 0 || out.cmd.w != 0;
    if (!out.ok) return false;
    // Turning on the spot towards a target behind: the paths to its left
    // and to its right score alike and the pick would flip from cycle to
    // cycle; keep turning the way the previous cycle turned.
    const bool spot = std::abs(out.cmd.v) < 0.2 * r_.v_max;
    if (spot && last_spot_ && out.cmd.w * last_w_ < 0) {
      // The mirror path (alpha -> -alpha) must be free as well.
      const uint16_t mirror = fam.ptg->alpha2index(-fam.ptg->index2alpha(best.k));
      if (fam.tp_obstacles[mirror] > q_.secure_start) out.cmd.w = -out.cmd.w;
    }
    last_spot_ = spot;
    last_w_ = out.cmd.w;
    out.note = fam.ptg->getDescription();
    return true;
  }

  Family makeFamily(const std::string& kind) {
    mrpt::config::CConfigFileMemory cfg;
    const std::string sec = "ptg";
    cfg.write(sec, "num_paths", q_.num_paths);
    cfg.write(sec, "refDistance", q_.ref_distance);
    cfg.write(sec, "score_priority", 1.0);
    cfg.write(sec, "resolution", q_.resolution);
    cfg.write(sec, "v_max_mps", r_.v_max);
    cfg.write(sec, "w_max_dps", mrpt::RAD2DEG(r_.w_max));
    cfg.write(sec, "turningRadiusReference", 0.1);
    // The footprint grown by what the cost map counts as contact (its
    // padding) and a margin for the cells' size and the PTGs' look-up grid.
    const auto shape = grow(r_.footprint, p_.footprint_padding + q_.shape_margin);
    for (size_t i = 0; i < shape.size(); ++i) {
      cfg.write(sec, "shape_x" + std::to_string(i), shape[i].x);
      cfg.write(sec, "shape_y" + std::to_string(i), shape[i].y);
    }
    Family f;
    if (kind == "C") {
      cfg.write(sec, "K", 1.0);
      f.ptg = std::make_unique<mrpt::nav::CPTG_DiffDrive_C>();
    } else {
      cfg.write(sec, "cte_a0v_deg", q_.cte_a0_deg);
      cfg.write(sec, "cte_a0w_deg", q_.cte_a0_deg);
      f.ptg = std::make_unique<mrpt::nav::CPTG_DiffDrive_alpha>();
    }
    f.ptg->loadFromConfigFile(cfg, sec);
    // MRPT caches each PTG's collision grid in a file; with no name given it
    // writes "cache_<ptg>.bin.gz" into the working directory. Keep it in the
    // user's cache folder instead (or the temporary one).
    std::string key = f.ptg->getDescription();
    for (const auto& v : shape) key += "," + std::to_string(v.x) + "," + std::to_string(v.y);
    key += "," + std::to_string(q_.ref_distance) + "," + std::to_string(q_.resolution) + "," +
           std::to_string(q_.num_paths);
    f.ptg->initialize(ptgCacheFile(f.ptg->getDescription(), key), false);
    if (q_.holonomic == "nd")
      f.holo = std::make_unique<mrpt::nav::CHolonomicND>();
    else if (q_.holonomic == "full-eval")
      f.holo = std::make_unique<mrpt::nav::CHolonomicFullEval>();
    else
      throw InputError("[nav.mrpt_ptg] holonomic: unknown value '" + q_.holonomic + "'");
    f.holo->setAssociatedPTG(f.ptg.get());
    return f;
  }

  /** Occupied cells of the cost map that a path of `ref_distance` could
   *  reach, in the robot frame. */
  std::vector<mrpt::math::TPoint2D> obstaclePoints(const LocalCostmap& map,
                                                   const TPose2D& pose) const {
    std::vector<mrpt::math::TPoint2D> pts;
    const double res = map.resolution();
    const double reach = q_.ref_distance + map.footprint().circumscribed + res;
    const TPoint2D o = map.origin();
    const int n = map.size();
    const int ix0 = std::max(0, static_cast<int>(std::floor((pose.x - reach - o.x) / res)));
    const int ix1 = std::min(n - 1, static_cast<int>(std::floor((pose.x + reach - o.x) / res)));
    const int iy0 = std::max(0, static_cast<int>(std::floor((pose.y - reach - o.y) / res)));
    const int iy1 = std::min(n - 1, static_cast<int>(std::floor((pose.y + reach - o.y) / res)));
    const double c = std::cos(pose.phi), s = std::sin(pose.phi);
    for (int iy = iy0; iy <= iy1; ++iy)
      for (int ix = ix0; ix <= ix1; ++ix) {
        const double x = o.x + (ix + 0.5) * res, y = o.y + (iy + 0.5) * res;
        if (map.distance(x, y) > res * 0.5) continue;  // not an obstacle cell
        const double dx = x - pose.x, dy = y - pose.y;
        if (dx * dx + dy * dy > reach * reach) continue;
        pts.push_back({c * dx + s * dy, -s * dx + c * dy});
      }
    return pts;
  }

  /** Within the goal tolerance: turn on the spot to the goal's heading. */
  PlannerOutput alignAtGoal(const PlannerInput& in) {
    PlannerOutput out;
    const double err = angleDiff(in.goal->phi, in.pose.phi);
    if (std::abs(err) < mrpt::DEG2RAD(p_.goal_tolerance_deg)) {
      out.ok = true;
      out.mark(PlanStatus::GoalReached);
      return out;
    }
    double w = std::clamp(q_.goal_turn_gain * err, -r_.w_max, r_.w_max);
    // Not slower than needed to get there in reasonable time near the end.
    if (std::abs(w) < 0.1) w = std::copysign(std::min(0.1, r_.w_max), err);
    out.cmd = {0, w};
    out.ok = true;
    out.mark(PlanStatus::TurnInPlace);
    out.evaluated = out.admissible = 1;
    out.trajectories.push_back(
        rollout(*in.map, in.pose, out.cmd, p_.sim_time, p_.sim_step, p_.clearance_influence, 0));
    return out;
  }

  NavigationParams p_;
  RobotParams r_;
  MrptPtgParams q_;
  std::vector<Family> families_;
  bool last_spot_ = false;  // the previous command turned (nearly) on the spot
  double last_w_ = 0;
};

}  // namespace

std::unique_ptr<LocalPlanner> makeMrptPtg(const NavigationParams& p, const RobotParams& r,
                                          const MrptPtgParams& ptg) {
  return std::make_unique<MrptPtg>(p, r, ptg);
}

std::unique_ptr<LocalPlanner> makeMrptPtg(const NavigationParams& p, const RobotParams& r) {
  return makeMrptPtg(p, r, MrptPtgParams{});
}

const char* mrptPtgDescription() {
  return "MRPT's TP-space reactive navigation (PTGs + holonomic method) towards the route";
}

void configureMrptPtg(const Profile& profile) {
  const auto q = profile.section<MrptPtgParams>("nav.mrpt_ptg");
  PlannerRegistry::instance().add(
      "mrpt-ptg", mrptPtgDescription(),
      [q](const NavigationParams& p, const RobotParams& r) { return makeMrptPtg(p, r, q); });
}

}  // namespace carenav::navigation
