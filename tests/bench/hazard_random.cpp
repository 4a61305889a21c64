// Randomised hazard benchmark (issue 17 item 5; docs/BENCHMARKS.md
// "Perception: randomised hazard scenes").
//
// Seeded random scenes seen by a depth camera with a random mounting, through
// the pipeline the navigation session and `carenav perceive` run (rrt-gpd:
// 2.5D grid + RRT-GPD + ISM, the profile's [perception] parameters):
//   - mounting (the profile's camera model: 512 x 424, 70.6 x 60 deg,
//     0.5-4.5 m): height 0.5-1.2 m, pitch 15-45 deg down, roll +-5 deg; the
//     true mounting differs from the one the pipeline is given by up to
//     +-3 deg in pitch and in roll (calibration error);
//   - depth noise: 1-3 times the profile's (std f * depth_noise_std * t^2 on
//     the depth t; the pipeline keeps the profile's model), 1 % of the pixels
//     dropped;
//   - scenes (one type per scene, in turn): flat floor, stairs down (at 0-60
//     deg to the view), curbs down 5-20 cm, holes and gutters 5-30 cm wide and
//     deep, steps up 2-10 cm, ramps 3-15 deg, thresholds, tables, people.
// The camera rays are cast here against convex prisms and cylinders (no
// simulator world: stairs at any angle, ramps and people need no grid).
//
// Scored on the local grid (5 cm) against the primitives:
//   - recall: occupied share of the hazard cells holding a return;
//   - false obstacles: occupied share of the traversable cells holding a
//     return (floor farther than --margin from any hazard, ramps up to
//     max_slope_deg and their landing);
//   - corridor verdict: "blocked" when an occupied cell lies in the walker's
//     corridor (|y| <= half its width) between its front and 0.1 m beyond
//     the hazard's nearest cell in the corridor, "clear" otherwise; on flat
//     floor and traversable ramps "blocked" is a false stop (from the front
//     to --clear-range ahead).
// A scene is "in range" when the noise model says the hazard is separable
// from the floor at its distance (docs/perceive.md "Range per hazard size").
//
//   hazard_random [--profile ini/isr-aiwalker.ini] [--scenes 550] [--seed 1]
//                 [--decimation 1] [--margin 0.2] [--set section.key=value]...
//                 [--calib-error 3] [--noise-max 3] [--roll 5] [--list-clear]
//                 [--only TYPE] [--dump N] [--slope-bands] [--approach STEP]
// --slope-bands: then the false obstacles of the traversable ramps by true
// slope (1 deg bands, 3-7 deg and 7-max_slope_deg), the cells pooled.
// --approach STEP: a hazard the first frame leaves clear in the corridor is
// seen again after every STEP m driven straight at it (one frame each, no
// obstacle memory), until a frame blocks it, its nearest part enters the
// camera's blind zone, or it lies within the walker's stopping reach (its
// safe_distance plus the braking distance from v_max with the reaction time
// of the navigation session's "unknown floor ahead": command latency, one
// control cycle, one frame). Reported per scene type: the distance from the
// robot's front at which such hazards were first blocked, and those never
// blocked in time (the walker would reach them on single frames).
#include <carenav/common/profile.h>
#include <carenav/common/robot.h>
#include <carenav/perception/pipeline.h>
#include <carenav/runtime/unknown_ahead.h>

#include <mrpt/poses/CPose3D.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

using namespace carenav;
using namespace carenav::perception;

namespace {

constexpr double kDeg = M_PI / 180.0;

// ------------------------------------------------------------------ scene

/** Convex prism: a rectangle (half sizes hu x hv, turned by th about its
 *  centre) between z = zb and the top plane z = z0 + slope * u (u, v: local). */
struct Prism {
  double cx, cy, th, hu, hv, z0, slope, zb;
  bool hazard;  ///< not traversable (drop, rise, overhang, steep ramp)
  bool ramp;    ///< a traversable slope (not plain floor)
  void local(double x, double y, double& u, double& v) const {
    const double c = std::cos(th), s = std::sin(th);
    u = (x - cx) * c + (y - cy) * s;
    v = -(x - cx) * s + (y - cy) * c;
  }
  bool contains(double x, double y) const {
    double u, v;
    local(x, y, u, v);
    return std::abs(u) <= hu && std::abs(v) <= hv;
  }
  double top(double x, double y) const {
    double u, v;
    local(x, y, u, v);
    return z0 + slope * u;
  }
};
struct Cylinder {
  double x, y, r, z0, z1;
};

enum class Type {
  Flat,
  StairsDown,
  CurbDown,
  Hole,
  Gutter,
  StepUp,
  RampOk,
  RampSteep,
  Threshold,
  Table,
  Person,
  kCount
};
const char* typeName(Type t) {
  static const char* n[] = {
      "flat floor",        "stairs down",      "curb down", "hole",  "gutter", "step up",
      "ramp <= max_slope", "ramp > max_slope", "threshold", "table", "person"};
  return n[static_cast<int>(t)];
}
bool isDrop(Type t) {
  return t == Type::StairsDown || t == Type::CurbDown || t == Type::Hole || t == Type::Gutter;
}

struct Scene {
  Type type = Type::Flat;
  std::vector<Prism> prisms;
  std::vector<Cylinder> cyl;
  double edge = 0;       ///< m, nominal distance of the hazard's near edge ahead
  double size = 0;       ///< m (drop, rise, width) or deg (ramp)
  double depth = 0;      ///< m (holes, gutters)
  double angle = 0;      ///< deg, turn of the hazard edge to the view
  bool in_range = true;  ///< the noise model says it is separable there
  std::string describe;  ///< parameters, for the list of failures
};

/** Ray (o, d) against a convex prism: entry distance or +inf. */
double castPrism(const Prism& p, const double o[3], const double d[3]) {
  const double c = std::cos(p.th), s = std::sin(p.th);
  const double ou = (o[0] - p.cx) * c + (o[1] - p.cy) * s,
               ov = -(o[0] - p.cx) * s + (o[1] - p.cy) * c;
  const double du = d[0] * c + d[1] * s, dv = -d[0] * s + d[1] * c;
  double t0 = 0, t1 = 1e9;
  // half-spaces n . (u, v, z) <= k
  auto clip = [&](double nu, double nv, double nz, double k) {
    const double den = nu * du + nv * dv + nz * d[2], num = k - (nu * ou + nv * ov + nz * o[2]);
    if (std::abs(den) < 1e-12) return num >= 0;
    const double t = num / den;
    if (den > 0)
      t1 = std::min(t1, t);
    else
      t0 = std::max(t0, t);
    return t0 <= t1;
  };
  if (clip(1, 0, 0, p.hu) && clip(-1, 0, 0, p.hu) && clip(0, 1, 0, p.hv) && clip(0, -1, 0, p.hv) &&
      clip(0, 0, -1, -p.zb) && clip(-p.slope, 0, 1, p.z0) && t0 > 1e-9)
    return t0;
  return std::numeric_limits<double>::infinity();
}

double castCylinder(const Cylinder& cy, const double o[3], const double d[3]) {
  const double ox = o[0] - cy.x, oy = o[1] - cy.y;
  const double a = d[0] * d[0] + d[1] * d[1], b = 2 * (ox * d[0] + oy * d[1]),
               c = ox * ox + oy * oy - cy.r * cy.r;
  const double disc = b * b - 4 * a * c;
  if (a < 1e-12 || disc < 0) return std::numeric_limits<double>::infinity();
  double t0 = (-b - std::sqrt(disc)) / (2 * a), t1 = (-b + std::sqrt(disc)) / (2 * a);
  if (std::abs(d[2]) > 1e-12) {
    double za = (cy.z0 - o[2]) / d[2], zb = (cy.z1 - o[2]) / d[2];
    if (za > zb) std::swap(za, zb);
    t0 = std::max(t0, za);
    t1 = std::min(t1, zb);
  }
  return t0 <= t1 && t0 > 1e-9 ? t0 : std::numeric_limits<double>::infinity();
}

double castScene(const Scene& s, const double o[3], const double d[3]) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& p : s.prisms) best = std::min(best, castPrism(p, o, d));
  for (const auto& c : s.cyl) best = std::min(best, castCylinder(c, o, d));
  return best;
}

// ------------------------------------------------------------------ scene generation

struct Mount {
  double h, pitch, roll;  // deg for angles; what the pipeline is given
  double pitch_err, roll_err, noise_factor;
};

constexpr double kCamX = 0.2;  // the profile's camera, ahead of the axle

/** A ground prism: a column under the top plane (zb far below). */
Prism ground(double cx, double cy, double th, double hu, double hv, double z0, double slope,
             bool hazard, bool ramp = false) {
  return {cx, cy, th, hu, hv, z0, slope, -5.0, hazard, ramp};
}

/** Point at distance `along` on the line through (ex, 0) turned by th. */
void alongEdge(double ex, double th, double u, double& x, double& y) {
  x = ex + u * std::cos(th);
  y = u * std::sin(th);
}

/** Floor up to an edge (u < 0 in the turned frame, the edge crossing y = 0 at
 *  x = ex) and, beyond it, `beyond` (its u from 0). */
void floorBefore(Scene& s, double ex, double th) {
  double x, y;
  alongEdge(ex, th, -10, x, y);
  s.prisms.push_back(ground(x, y, th, 10, 12, 0, 0, false));
}

}  // namespace

namespace {

struct Gen {
  std::mt19937_64 rng;
  double uni(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); }
};

/** Camera model of the profile's depth camera. */
struct Camera {
  int width = 512, height = 424;
  double fov = 70.6, vfov = 60, range_min = 0.5, range_max = 4.5, noise_std = 0.005;
  double rate_hz = 10;
};

/** Distance ahead of the robot of the near edge: in view of this mounting
 *  (0.3 m beyond the nearest floor in view, 0.4 m before the farthest), and
 *  at most 3 m. */
double edgeDistance(Gen& g, const Mount& m, const Camera& cam) {
  const double lo_ang = (m.pitch + cam.vfov / 2) * kDeg, hi_ang = (m.pitch - cam.vfov / 2) * kDeg;
  const double near = kCamX + (lo_ang < M_PI / 2 ? m.h / std::tan(lo_ang) : 0.0);
  double far = kCamX + std::sqrt(cam.range_max * cam.range_max - m.h * m.h);
  if (hi_ang > 2 * kDeg) far = std::min(far, kCamX + m.h / std::tan(hi_ang));
  const double a = std::max(0.8, near + 0.3), b = std::min(3.0, far - 0.4);
  return b > a ? g.uni(a, b) : a;
}

void addDrop(Scene& s, Gen& g, double ex, double th, int steps, double tread, double riser) {
  floorBefore(s, ex, th);
  double x, y;
  for (int k = 1; k <= steps; ++k) {
    alongEdge(ex, th, (k - 0.5) * tread, x, y);
    s.prisms.push_back(ground(x, y, th, tread / 2, 12, -k * riser, 0, true));
  }
  alongEdge(ex, th, steps * tread + 10, x, y);
  s.prisms.push_back(ground(x, y, th, 10, 12, -steps * riser, 0, true));
  (void)g;
}

/** Floor with a rectangular pit (w along u, l along v, depth d) centred at
 *  (cx, cy), turned by th. */
void addPit(Scene& s, double cx, double cy, double th, double w, double l, double d) {
  const double c = std::cos(th), sn = std::sin(th);
  auto at = [&](double u, double v, double hu, double hv, double top, bool hz) {
    s.prisms.push_back(ground(cx + u * c - v * sn, cy + u * sn + v * c, th, hu, hv, top, 0, hz));
  };
  at(-w / 2 - 10, 0, 10, 12, 0, false);   // before
  at(w / 2 + 10, 0, 10, 12, 0, false);    // after
  at(0, l / 2 + 6, w / 2, 6, 0, false);   // left
  at(0, -l / 2 - 6, w / 2, 6, 0, false);  // right
  at(0, 0, w / 2, l / 2, -d, true);       // bottom
}

void addRamp(Scene& s, double ex, double th, double deg, double len, bool steep) {
  floorBefore(s, ex, th);
  const double t = std::tan(deg * kDeg);
  double x, y;
  alongEdge(ex, th, len / 2, x, y);
  s.prisms.push_back(ground(x, y, th, len / 2, 12, t * len / 2, t, steep, !steep));
  alongEdge(ex, th, len + 10, x, y);
  s.prisms.push_back(ground(x, y, th, 10, 12, t * len, 0, steep, !steep));
}

void addTable(Scene& s, Gen& g, double ex) {
  s.prisms.push_back(ground(0, 0, 0, 12, 12, 0, 0, false));
  const double lu = g.uni(0.8, 1.4), lv = g.uni(0.6, 1.0), top = g.uni(0.70, 0.80);
  const double cx = ex + lu / 2, cy = g.uni(-0.3, 0.3), th = g.uni(-30, 30) * kDeg;
  s.prisms.push_back({cx, cy, th, lu / 2, lv / 2, top, 0, top - 0.03, true, false});
  const double c = std::cos(th), sn = std::sin(th);
  for (int a = -1; a <= 1; a += 2)
    for (int b = -1; b <= 1; b += 2) {
      const double u = a * (lu / 2 - 0.05), v = b * (lv / 2 - 0.05);
      s.prisms.push_back({cx + u * c - v * sn, cy + u * sn + v * c, th, 0.02, 0.02, top - 0.03, 0,
                          -0.01, true, false});
    }
  s.size = top;
  s.angle = th / kDeg;
}

/** Separable from the floor at range r (from a camera h high) by the noise
 *  model with the scene's true noise (f times depth_noise_std): a height c
 *  above or below the floor against noise_k vertical sigmas, sigma_v =
 *  f depth_noise_std r h (docs/perceive.md "Range per hazard size"). */
bool separable(double c, double r, const Mount& m, const PerceptionParams& pp) {
  return std::abs(c) >= pp.noise_k * m.noise_factor * pp.depth_noise_std * r * m.h;
}

/** Whether the hazard of scene s (its edge at s.edge) is separable from
 *  the floor by the noise model: curbs, steps up and thresholds by their
 *  height, holes and gutters by how deep the ray dips into them (w tan(alpha)
 *  = w h / r_h at their far wall); every other type always. */
bool sceneInRange(const Scene& s, const Mount& m, const PerceptionParams& pp) {
  const double ex = s.edge, r = std::hypot(ex - kCamX, m.h);
  switch (s.type) {
    case Type::CurbDown:
    case Type::StepUp:
    case Type::Threshold:
      return separable(s.size, r, m, pp);
    case Type::Hole:
    case Type::Gutter:
      return separable(std::min(s.depth, s.size * m.h / std::max(0.1, ex - kCamX)), r, m, pp);
    default:
      return true;
  }
}

/** Fills the hazard of scene type t at edge distance ex. */
void buildHazard(Scene& s, Gen& g, const Mount& m, const PerceptionParams& pp) {
  const double ex = s.edge;
  char buf[160] = "";
  switch (s.type) {
    case Type::Flat:
      s.prisms.push_back(ground(0, 0, 0, 12, 12, 0, 0, false));
      break;
    case Type::StairsDown: {
      s.angle = g.uni(-60, 60);
      const int n = 3 + static_cast<int>(g.uni(0, 4));
      const double tread = g.uni(0.25, 0.32);
      s.size = g.uni(0.15, 0.19);
      addDrop(s, g, ex, s.angle * kDeg, n, tread, s.size);
      break;
    }
    case Type::CurbDown:
      s.angle = g.uni(-60, 60);
      s.size = g.uni(0.05, 0.20);
      addDrop(s, g, ex, s.angle * kDeg, 1, 10, s.size);
      break;
    case Type::Hole:
    case Type::Gutter: {
      s.angle = g.uni(-45, 45);
      s.size = g.uni(0.05, 0.30);
      s.depth = g.uni(0.05, 0.30);
      const double l = s.type == Type::Hole ? g.uni(s.size, 2 * s.size) : 24;
      const double th = s.angle * kDeg;
      double cx, cy;
      alongEdge(ex, th, s.size / 2, cx, cy);
      if (s.type == Type::Hole) cy += g.uni(-0.15, 0.15);
      addPit(s, cx, cy, th, s.size, l, s.depth);
      break;
    }
    case Type::StepUp:
      s.angle = g.uni(-45, 45);
      s.size = g.uni(0.02, 0.10);
      addDrop(s, g, ex, s.angle * kDeg, 1, 10, -s.size);
      break;
    case Type::RampOk:
    case Type::RampSteep:
      s.angle = g.uni(-20, 20);
      s.size = s.type == Type::RampOk ? g.uni(3, pp.max_slope_deg) : g.uni(pp.max_slope_deg, 15);
      addRamp(s, ex, s.angle * kDeg, s.size, g.uni(1.0, 2.0), s.type == Type::RampSteep);
      break;
    case Type::Threshold: {
      s.angle = g.uni(-45, 45);
      s.size = g.uni(0.015, 0.03);
      const double w = g.uni(0.04, 0.10), th = s.angle * kDeg;
      double cx, cy;
      alongEdge(ex, th, w / 2, cx, cy);
      s.prisms.push_back(ground(0, 0, 0, 12, 12, 0, 0, false));
      s.prisms.push_back({cx, cy, th, w / 2, 12, s.size, 0, -0.01, true, false});
      break;
    }
    case Type::Table:
      addTable(s, g, ex);
      break;
    default: {  // Person
      s.prisms.push_back(ground(0, 0, 0, 12, 12, 0, 0, false));
      const double rad = g.uni(0.15, 0.25);
      s.cyl.push_back({ex + rad, g.uni(-0.2, 0.2), rad, 0, g.uni(1.5, 1.85)});
      s.size = rad;
    }
  }
  s.in_range = sceneInRange(s, m, pp);
  std::snprintf(buf, sizeof buf,
                "edge %.2f m, size %.3f, depth %.3f, angle %.0f deg; camera %.2f m, pitch %.1f "
                "(true %+.1f), roll %.1f (true %+.1f), noise x%.1f",
                ex, s.size, s.depth, s.angle, m.h, m.pitch, m.pitch_err, m.roll, m.roll_err,
                m.noise_factor);
  s.describe = buf;
}

Scene makeScene(Gen& g, Type t, const Mount& m, const Camera& cam, const PerceptionParams& pp) {
  Scene s;
  s.type = t;
  s.edge = edgeDistance(g, m, cam);
  buildHazard(s, g, m, pp);
  return s;
}

/** Ranges of the random mounting and noise (defaults: the issue's). */
struct MountRanges {
  double calib_deg = 3, noise_max = 3, roll_deg = 5;
};

Mount makeMount(Gen& g, const MountRanges& r) {
  Mount m;
  m.h = g.uni(0.5, 1.2);
  m.pitch = g.uni(15, 45);
  m.roll = g.uni(-1, 1) * r.roll_deg;
  m.pitch_err = g.uni(-1, 1) * r.calib_deg;
  m.roll_err = g.uni(-1, 1) * r.calib_deg;
  m.noise_factor = g.uni(0, 1) * (r.noise_max - 1) + 1;
  return m;
}

// ------------------------------------------------------------------ rendering

/** The organised cloud the pipeline gets (robot frame through the mounting it
 *  is given) and the true hit points (robot frame, for "seen" cells). */
Cloud render(const Scene& s, const Mount& m, const Camera& cam, int dec, Gen& g,
             std::vector<Point3f>& truth) {
  const int W = std::max(1, cam.width / dec), H = std::max(1, cam.height / dec);
  const double fx = (W / 2.0) / std::tan(cam.fov / 2 * kDeg),
               fy = (H / 2.0) / std::tan(cam.vfov / 2 * kDeg);
  const mrpt::poses::CPose3D true_pose(kCamX, 0, m.h, 0, (m.pitch + m.pitch_err) * kDeg,
                                       (m.roll + m.roll_err) * kDeg);
  const auto R = true_pose.getRotationMatrix();
  const double o[3] = {true_pose.x(), true_pose.y(), true_pose.z()};
  std::normal_distribution<double> n01(0, 1);
  std::uniform_real_distribution<double> u01(0, 1);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  Cloud c;
  c.width = W;
  c.height = H;
  c.points.reserve(static_cast<size_t>(W) * H);
  truth.clear();
  const double sd0 = cam.noise_std * m.noise_factor;
  for (int v = 0; v < H; ++v)
    for (int u = 0; u < W; ++u) {
      const double xc = (u + 0.5 - W / 2.0) / fx, yc = (v + 0.5 - H / 2.0) / fy;
      const double ds[3] = {1, -xc, -yc};  // sensor frame, depth along x
      double d[3];
      for (int i = 0; i < 3; ++i) d[i] = R(i, 0) * ds[0] + R(i, 1) * ds[1] + R(i, 2) * ds[2];
      const double t = castScene(s, o, d);
      const double len = std::sqrt(1 + xc * xc + yc * yc);
      if (!std::isfinite(t) || t * len < cam.range_min || t * len > cam.range_max ||
          u01(g.rng) < 0.01) {
        c.points.push_back({nan, nan, nan});
        continue;
      }
      truth.push_back({static_cast<float>(o[0] + t * d[0]), static_cast<float>(o[1] + t * d[1]),
                       static_cast<float>(o[2] + t * d[2])});
      const double tn = t + sd0 * t * t * n01(g.rng);
      c.points.push_back({static_cast<float>(tn * ds[0]), static_cast<float>(tn * ds[1]),
                          static_cast<float>(tn * ds[2])});
    }
  const mrpt::poses::CPose3D given(kCamX, 0, m.h, 0, m.pitch * kDeg, m.roll * kDeg);
  return toRobotFrame(c, given, false);
}

}  // namespace

namespace {

// ------------------------------------------------------------------ scoring

std::string pct(size_t num, size_t den) {
  if (den == 0) return "-";
  char b[32];
  std::snprintf(b, sizeof b, "%.1f %%", 100.0 * num / den);
  return b;
}

enum class Label : uint8_t { Outside, Floor, Hazard, Traversable, Margin };

Label labelAt(const Scene& s, double x, double y) {
  const Prism* topmost = nullptr;
  double best = -1e9;
  for (const auto& p : s.prisms) {
    if (!p.contains(x, y)) continue;
    if (p.zb > -1) return Label::Hazard;  // a solid standing on the floor or above it
    const double z = p.top(x, y);
    if (z > best) best = z, topmost = &p;
  }
  for (const auto& c : s.cyl)
    if (std::hypot(x - c.x, y - c.y) <= c.r) return Label::Hazard;
  if (!topmost) return Label::Outside;
  return topmost->hazard ? Label::Hazard : topmost->ramp ? Label::Traversable : Label::Floor;
}

/** Label of each local-grid cell in the scored region (x 0-4.5 m, |y| <= 2.5
 *  m): 3 x 3 samples, any hazard sample makes a hazard cell. */
std::vector<Label> labels(const Scene& s, const LocalOccupancy& g, double margin) {
  const int m = g.cells();
  const double q = g.resolution() / 3;
  std::vector<Label> lab(static_cast<size_t>(m) * m, Label::Outside);
  std::vector<int> hz;
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      const double cx = g.centreX(i), cy = g.centreY(j);
      if (cx < 0 || cx > 4.5 || std::abs(cy) > 2.5) continue;
      bool hazard = false, trav = false, out = false;
      for (int a = -1; a <= 1; ++a)
        for (int b = -1; b <= 1; ++b) {
          const Label l = labelAt(s, cx + a * q, cy + b * q);
          hazard |= l == Label::Hazard;
          trav |= l == Label::Traversable;
          out |= l == Label::Outside;
        }
      Label& l = lab[static_cast<size_t>(i) * m + j];
      l = hazard ? Label::Hazard : trav ? Label::Traversable : out ? Label::Outside : Label::Floor;
      if (hazard) hz.push_back(i * m + j);
    }
  const int r = static_cast<int>(std::ceil(margin / g.resolution() - 1e-9));
  for (int k : hz)
    for (int di = -r; di <= r; ++di)
      for (int dj = -r; dj <= r; ++dj) {
        const int a = k / m + di, b = k % m + dj;
        if (!g.inside(a, b) || std::hypot(di, dj) * g.resolution() > margin + 1e-9) continue;
        Label& l = lab[static_cast<size_t>(a) * m + b];
        if (l == Label::Floor || l == Label::Traversable) l = Label::Margin;
      }
  return lab;
}

struct SceneScore {
  size_t hazard = 0, hazard_occ = 0, trav = 0, trav_occ = 0;
  bool has_hazard_in_corridor = false, blocked = false;
  double first_hazard = 0, first_occ = 0;  ///< m ahead in the corridor (0: none)
};

struct Corridor {
  double half_width, front, clear_range, into;
};

SceneScore scoreScene(const LocalOccupancy& g, const std::vector<Label>& lab,
                      const std::vector<Point3f>& truth, const Corridor& cor, double into,
                      double occ_thr) {
  const int m = g.cells();
  std::vector<char> seen(static_cast<size_t>(m) * m, 0);
  for (const auto& p : truth) {
    const int i = g.cellX(p.x), j = g.cellY(p.y);
    if (g.inside(i, j)) seen[static_cast<size_t>(i) * m + j] = 1;
  }
  SceneScore s;
  double x_h = 1e9, x_occ = 1e9;
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      const size_t k = static_cast<size_t>(i) * m + j;
      const bool occ = g.prob(i, j) > occ_thr;
      const double x = g.centreX(i), y = g.centreY(j);
      const bool in_cor = std::abs(y) <= cor.half_width && x >= cor.front;
      if (in_cor && lab[k] == Label::Hazard) x_h = std::min(x_h, x - 0.5 * g.resolution());
      if (in_cor && occ) x_occ = std::min(x_occ, x);
      if (!seen[k]) continue;
      if (lab[k] == Label::Hazard) {
        ++s.hazard;
        s.hazard_occ += occ;
      } else if (lab[k] == Label::Floor || lab[k] == Label::Traversable) {
        ++s.trav;
        s.trav_occ += occ;
      }
    }
  s.has_hazard_in_corridor = x_h < 1e8;
  s.first_hazard = s.has_hazard_in_corridor ? x_h : 0;
  s.first_occ = x_occ < 1e8 ? x_occ : 0;
  const double limit = s.has_hazard_in_corridor ? x_h + into : cor.clear_range;
  s.blocked = x_occ <= limit;
  return s;
}

/** Text view of the local grid of one scene on stderr (x ahead up, y left
 *  to the left): '#' occupied, '.' free, ' ' unknown; on hazard cells 'H',
 *  'F', 'U'; then the voxel classes ('o' obstacle, 'g' ground). */
void dumpScene(const Pipeline& pipe, const FrameResult& fr, const std::vector<Label>& lab,
               double occ, double fre) {
  const auto& g = pipe.grid();
  const auto& e = pipe.elevation();
  for (double x = 4.5; x > 0.2; x -= g.resolution()) {
    std::string a, b;
    for (double y = 1.0; y > -1.0; y -= g.resolution()) {
      const int i = g.cellX(x), j = g.cellY(y);
      const double pr = g.prob(i, j);
      const bool hz = lab[static_cast<size_t>(i) * g.cells() + j] == Label::Hazard;
      a += pr > occ ? (hz ? 'H' : '#') : pr < fre ? (hz ? 'F' : '.') : (hz ? 'U' : ' ');
      const int ei = e.cellOf(x), ej = e.cellOf(y);
      const auto vc = fr.voxel_classes.empty()
                          ? VoxelClass::None
                          : fr.voxel_classes[static_cast<size_t>(ei) * e.cells() + ej];
      b += vc == VoxelClass::Obstacle ? 'o' : vc == VoxelClass::Ground ? 'g' : ' ';
    }
    std::fprintf(stderr, "%5.2f |%s|  |%s|\n", x, a.c_str(), b.c_str());
  }
  std::fprintf(stderr, "plane %s (%.4f %.4f %.4f %.4f), noise scale %.2f\n",
               fr.plane_source.c_str(), fr.plane ? fr.plane->a : 0, fr.plane ? fr.plane->b : 0,
               fr.plane ? fr.plane->c : 0, fr.plane ? fr.plane->d : 0, fr.noise_scale);
}

// ------------------------------------------------------------------ report

/** False obstacles of the traversable ramps pooled over 1 deg bands of
 *  their true slope (--slope-bands). */
struct SlopeBand {
  size_t scenes = 0, blocked = 0, trav = 0, trav_occ = 0;
};
using SlopeBands = std::map<int, SlopeBand>;  // key: floor of the slope, deg

void addSlopeBand(const Scene& sc, const SceneScore& s, SlopeBands& bands) {
  SlopeBand& b = bands[static_cast<int>(std::floor(sc.size))];
  ++b.scenes;
  b.blocked += s.blocked;
  b.trav += s.trav;
  b.trav_occ += s.trav_occ;
}

void printSlopeBands(const SlopeBands& bands, double max_slope) {
  std::printf(
      "| true slope | scenes | false obstacles (traversable cells seen) | blocked |\n"
      "|---|---|---|---|\n");
  SlopeBand low, high;
  for (const auto& [deg, b] : bands) {
    std::printf("| %d-%d deg | %zu | %s (%zu) | %zu |\n", deg, deg + 1, b.scenes,
                pct(b.trav_occ, b.trav).c_str(), b.trav, b.blocked);
    SlopeBand& sum = deg < 7 ? low : high;
    sum.scenes += b.scenes, sum.blocked += b.blocked, sum.trav += b.trav;
    sum.trav_occ += b.trav_occ;
  }
  std::printf("| 3-7 deg | %zu | %s (%zu) | %zu |\n", low.scenes,
              pct(low.trav_occ, low.trav).c_str(), low.trav, low.blocked);
  std::printf("| 7-%g deg | %zu | %s (%zu) | %zu |\n\n", max_slope, high.scenes,
              pct(high.trav_occ, high.trav).c_str(), high.trav, high.blocked);
}

struct TypeTotals {
  size_t scenes = 0, in_range = 0, hazard = 0, hazard_occ = 0, trav = 0, trav_occ = 0;
  size_t blocked = 0, clear = 0, blocked_out = 0, clear_out = 0, over_1pct = 0;
  std::vector<std::string> clear_list;
  std::vector<double> approach_blocked;  ///< --approach: m ahead of the front when blocked
  std::vector<std::string> approach_late;
  size_t approach_late_separable = 0;  ///< of approach_late, separable on a frame
  size_t approach_skipped = 0;         ///< clear, but in the blind zone or the reach at once
};

void printTable(const std::vector<TypeTotals>& tt, bool list_clear) {
  std::printf(
      "| scene type | scenes | in range | recall (hazard cells seen) | false obstacles "
      "(traversable cells seen) | scenes > 1 %% false | blocked / clear in range | blocked / "
      "clear out of range |\n|---|---|---|---|---|---|---|---|\n");
  for (int t = 0; t < static_cast<int>(Type::kCount); ++t) {
    const auto& x = tt[t];
    if (x.scenes == 0) continue;
    std::printf("| %s | %zu | %zu | %s (%zu) | %s (%zu) | %zu | %zu / %zu | %zu / %zu |\n",
                typeName(static_cast<Type>(t)), x.scenes, x.in_range,
                pct(x.hazard_occ, x.hazard).c_str(), x.hazard, pct(x.trav_occ, x.trav).c_str(),
                x.trav, x.over_1pct, x.blocked, x.clear, x.blocked_out, x.clear_out);
  }
  std::printf("\n");
  for (int t = 0; t < static_cast<int>(Type::kCount); ++t) {
    const bool must_block = isDrop(static_cast<Type>(t)) || static_cast<Type>(t) == Type::RampSteep;
    const auto& l = tt[t].clear_list;
    if (l.empty() || !(must_block || list_clear)) continue;
    std::printf("Wrong corridor verdicts, %s (%zu):\n", typeName(static_cast<Type>(t)), l.size());
    for (const auto& s : l) std::printf("  - %s\n", s.c_str());
  }
}

/** --approach: per scene type, the hazards the first frame left clear. */
void printApproach(const std::vector<TypeTotals>& tt, double step, double reach) {
  std::printf(
      "Approach (--approach %g m; stopping reach %.2f m ahead of the front):\n\n"
      "| scene type | clear on the first frame, in view beyond the reach (not: in the blind zone "
      "or the reach) | blocked on approach | first blocked, m ahead of the front: min / median "
      "| never blocked in time (separable on a frame / never) |\n|---|---|---|---|---|\n",
      step, reach);
  for (int t = 0; t < static_cast<int>(Type::kCount); ++t) {
    auto d = tt[t].approach_blocked;
    const size_t late = tt[t].approach_late.size();
    if (d.empty() && late == 0 && tt[t].approach_skipped == 0) continue;
    std::sort(d.begin(), d.end());
    char r[48] = "-";
    if (!d.empty()) std::snprintf(r, sizeof r, "%.2f / %.2f", d.front(), d[d.size() / 2]);
    const size_t sep = tt[t].approach_late_separable;
    std::printf("| %s | %zu (%zu) | %zu | %s | %zu / %zu |\n", typeName(static_cast<Type>(t)),
                d.size() + late, tt[t].approach_skipped, d.size(), r, sep, late - sep);
  }
  std::printf("\n");
  for (int t = 0; t < static_cast<int>(Type::kCount); ++t) {
    const auto& l = tt[t].approach_late;
    if (l.empty()) continue;
    std::printf("Never blocked in time, %s (%zu):\n", typeName(static_cast<Type>(t)), l.size());
    for (const auto& s : l) std::printf("  - %s\n", s.c_str());
  }
}

/** Command line (see the head of the file). */
struct Options {
  std::string profile_path = std::string(CARENAV_SOURCE_DIR) + "/ini/isr-aiwalker.ini";
  int scenes = 550, dec = 1;
  long seed = 1;
  double margin = 0.2;
  bool list_clear = false, slope_bands = false;
  std::string only;
  MountRanges ranges;
  int dump = -1;        // scene whose grid is printed on stderr
  double approach = 0;  // m per approach frame (0: no approach)
  std::vector<std::string> sets;
};

/** Parses the command line; returns an exit code when the run must stop
 *  (usage), -1 otherwise. */
int parseArgs(int argc, char** argv, Options& o) {
  for (int a = 1; a < argc; ++a) {
    const std::string k = argv[a];
    auto val = [&]() -> std::string {
      if (a + 1 >= argc) throw std::runtime_error(k + " needs a value");
      return argv[++a];
    };
    if (k == "--profile")
      o.profile_path = val();
    else if (k == "--scenes")
      o.scenes = std::stoi(val());
    else if (k == "--seed")
      o.seed = std::stol(val());
    else if (k == "--decimation")
      o.dec = std::stoi(val());
    else if (k == "--margin")
      o.margin = std::stod(val());
    else if (k == "--set")
      o.sets.push_back(val());
    else if (k == "--list-clear")
      o.list_clear = true;
    else if (k == "--slope-bands")
      o.slope_bands = true;
    else if (k == "--calib-error")
      o.ranges.calib_deg = std::stod(val());
    else if (k == "--noise-max")
      o.ranges.noise_max = std::stod(val());
    else if (k == "--roll")
      o.ranges.roll_deg = std::stod(val());
    else if (k == "--dump")
      o.dump = std::stoi(val());
    else if (k == "--only")
      o.only = val();
    else if (k == "--approach")
      o.approach = std::stod(val());
    else {
      std::cerr << "usage: hazard_random [--profile P] [--scenes N] [--seed S] [--decimation D] "
                   "[--margin M] [--calib-error DEG] [--noise-max F] [--roll DEG] "
                   "[--set section.key=value]... [--list-clear] [--only TYPE] [--dump N] "
                   "[--slope-bands] [--approach STEP]\n";
      return k == "--help" || k == "-h" ? 0 : 2;
    }
  }
  if (o.scenes < 1 || o.dec < 1) throw std::runtime_error("--scenes and --decimation must be >= 1");
  if (o.approach < 0 || (o.approach > 0 && o.approach < 0.01))
    throw std::runtime_error("--approach must be 0 (off) or at least 0.01 m");
  return -1;
}

/** What the profile gives: the perception parameters, the depth camera and
 *  the walker's corridor. */
struct Setup {
  PerceptionParams pp;
  Camera cam;
  Corridor cor{0, 0, 3.0, 0.1};
  double reach = 0;  ///< m ahead of the front: the walker cannot stop short of it
};

Setup loadSetup(const Options& o) {
  perception::registerProfileSections();
  Profile prof = Profile::load(o.profile_path);
  prof.applyOverrides(o.sets);
  Setup su;
  su.pp = prof.section<PerceptionParams>("perception");
  const auto robot = prof.section<RobotParams>("robot");
  bool found = false;
  for (const auto& s : loadSensors(prof))
    if (s.type == "depth-camera" && !found) {
      su.cam = {s.width, s.height, s.fov, s.vfov, s.range_min, s.range_max, s.noise_std, s.rate_hz};
      found = true;
    }
  if (!found) throw std::runtime_error(o.profile_path + ": no depth-camera sensor");
  for (const auto& p : robot.footprint) {
    su.cor.half_width = std::max(su.cor.half_width, std::abs(p.y));
    su.cor.front = std::max(su.cor.front, p.x);
  }
  navigation::UnknownAheadParams up;
  up.command_latency = robot.command_latency;
  up.frame_period = su.cam.rate_hz > 0 ? 1.0 / su.cam.rate_hz : up.frame_period;
  up.margin = robot.safe_distance;
  su.reach = navigation::UnknownAhead(robot, up, su.pp.resolution).reach(robot.v_max);
  return su;
}

/** The nearest floor the camera's lowest row sees (m ahead of the axle):
 *  nearer lies the blind zone. */
double nearView(const Mount& mt, const Camera& cam) {
  const double true_low = (mt.pitch + mt.pitch_err + cam.vfov / 2) * kDeg;
  return kCamX + (true_low < M_PI / 2 ? mt.h / std::tan(true_low) : 0.0);
}

/** Adds scene n's score to its type's totals. */
void addScore(int n, const Scene& sc, const Mount& mt, const Camera& cam, const SceneScore& s,
              bool list_clear, TypeTotals& x) {
  // A hazard whose nearest part in the corridor lies in the camera's blind
  // zone (nearer than the floor the lowest row sees) is out of range too.
  const double near_view = nearView(mt, cam);
  const bool in_range = sc.in_range && !(s.has_hazard_in_corridor && s.first_hazard < near_view);
  ++x.scenes;
  x.in_range += in_range;
  x.hazard += s.hazard;
  x.hazard_occ += s.hazard_occ;
  x.trav += s.trav;
  x.trav_occ += s.trav_occ;
  x.over_1pct += s.trav > 0 && s.trav_occ * 100 > s.trav;
  (in_range ? (s.blocked ? x.blocked : x.clear) : (s.blocked ? x.blocked_out : x.clear_out))++;
  if (s.blocked == s.has_hazard_in_corridor && !list_clear) return;
  char b[160];
  std::snprintf(b, sizeof b,
                "scene %d%s: %s; hazard at %.2f m, first occupied %.2f m, false obstacles %s", n,
                in_range ? "" : " (out of range)", s.blocked ? "blocked" : "clear", s.first_hazard,
                s.first_occ, pct(s.trav_occ, s.trav).c_str());
  x.clear_list.push_back(std::string(b) + " -- " + sc.describe);
}

/** Scene `sc` rendered from mounting `mt` (noise from `g`), perceived and
 *  scored; its grid printed on stderr when `dump`. */
SceneScore perceive(const Scene& sc, const Mount& mt, const Setup& su, const Options& o, Gen& g,
                    double into, bool dump) {
  std::vector<Point3f> truth;
  const Cloud cloud = render(sc, mt, su.cam, o.dec, g, truth);
  Pipeline pipe(su.pp, Method::RrtGpd);
  FrameInput in;
  in.cloud = &cloud;
  in.sensor_origin = {static_cast<float>(kCamX), 0.f, static_cast<float>(mt.h)};
  const FrameResult fr = pipe.process(in, false);
  const auto lab = labels(sc, pipe.grid(), o.margin);
  if (dump) dumpScene(pipe, fr, lab, su.pp.occupied_threshold, su.pp.free_threshold);
  return scoreScene(pipe.grid(), lab, truth, su.cor, into, su.pp.occupied_threshold);
}

/** The scene as seen after driving `dx` m straight ahead. */
Scene shifted(Scene s, double dx) {
  for (auto& p : s.prisms) p.cx -= dx;
  for (auto& c : s.cyl) c.x -= dx;
  s.edge -= dx;
  return s;
}

/** --approach for scene n, left clear by its first frame: new frames after
 *  every o.approach m driven at the hazard until one blocks it (true, with
 *  `ahead` its distance from the robot's front) or it enters the blind zone
 *  or the stopping reach unblocked (false; `separable`: the noise model
 *  called it separable on one of the frames that left it clear). */
bool approach(int n, const Options& o, const Setup& su, const Scene& sc, const Mount& mt,
              double into, double& ahead, bool& separable) {
  const double near_view = nearView(mt, su.cam);
  separable = sc.in_range;
  for (int k = 1;; ++k) {
    Gen g{std::mt19937_64((static_cast<uint64_t>(o.seed) * 1000003ULL + n) * 7919ULL + k)};
    const Scene at = shifted(sc, k * o.approach);
    const SceneScore s = perceive(at, mt, su, o, g, into, false);
    ahead = s.first_hazard - su.cor.front;
    if (!s.has_hazard_in_corridor || ahead < su.reach) return false;
    if (s.blocked) return true;
    if (s.first_hazard < near_view) return false;
    separable = separable || sceneInRange(at, mt, su.pp);
  }
}

/** --approach for scene n if its first frame (score s) left the hazard
 *  clear while in view and beyond the stopping reach (a hazard already in
 *  the blind zone or the reach is not one the walker drives towards: the
 *  navigation session's first frame and obstacle memory decide there). */
void addApproach(int n, const Options& o, const Setup& su, const Scene& sc, const Mount& mt,
                 double into, const SceneScore& s, TypeTotals& x) {
  if (!s.has_hazard_in_corridor || s.blocked) return;
  if (s.first_hazard < nearView(mt, su.cam) || s.first_hazard - su.cor.front < su.reach) {
    ++x.approach_skipped;
    return;
  }
  double ahead = 0;
  bool separable = false;
  if (approach(n, o, su, sc, mt, into, ahead, separable)) {
    x.approach_blocked.push_back(ahead);
    return;
  }
  char b[128];
  std::snprintf(b, sizeof b, "scene %d%s: not blocked before %.2f m ahead of the front", n,
                separable ? "" : " (never separable)", ahead);
  x.approach_late.push_back(std::string(b) + " -- " + sc.describe);
  x.approach_late_separable += separable;
}

/** Scene n: generated, rendered, perceived and scored. */
void runScene(int n, const Options& o, const Setup& su, std::vector<TypeTotals>& tt,
              SlopeBands& bands) {
  Gen g{std::mt19937_64(static_cast<uint64_t>(o.seed) * 1000003ULL + n)};
  const Type type = static_cast<Type>(n % static_cast<int>(Type::kCount));
  if (!o.only.empty() && o.only != typeName(type)) return;
  const Mount mt = makeMount(g, o.ranges);
  const Scene sc = makeScene(g, type, mt, su.cam, su.pp);
  // A ramp is blocked up to 0.3 m past its foot (it rises there at most
  // 8 cm at 15 deg); every other hazard 0.1 m past its nearest cell.
  const double into = type == Type::RampSteep ? 0.3 : su.cor.into;
  const SceneScore s = perceive(sc, mt, su, o, g, into, n == o.dump);
  TypeTotals& x = tt[static_cast<size_t>(type)];
  addScore(n, sc, mt, su.cam, s, o.list_clear, x);
  if (type == Type::RampOk) addSlopeBand(sc, s, bands);
  if (o.approach > 0) addApproach(n, o, su, sc, mt, into, s, x);
}

}  // namespace

int main(int argc, char** argv) try {
  Options o;
  const int rc = parseArgs(argc, argv, o);
  if (rc >= 0) return rc;
  const Setup su = loadSetup(o);
  std::vector<TypeTotals> tt(static_cast<size_t>(Type::kCount));
  SlopeBands bands;
  for (int n = 0; n < o.scenes; ++n) runScene(n, o, su, tt, bands);
  printTable(tt, o.list_clear);
  if (o.slope_bands) printSlopeBands(bands, su.pp.max_slope_deg);
  if (o.approach > 0) printApproach(tt, o.approach, su.reach);
  return 0;
} catch (const std::exception& e) {
  std::cerr << "hazard_random: " << e.what() << "\n";
  return 2;
}
