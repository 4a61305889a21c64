#include <carenav/common/errors.h>
#include <carenav/io/evaluation.h>
#include <carenav/io/number_table.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace carenav::io {

using mrpt::math::TPose2D;

namespace {

constexpr double kRad2Deg = 180.0 / M_PI;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Path lengths are running sums; without a little slack a pair exactly
// `distance` apart could be missed by rounding.
constexpr double kPathEps = 1e-9;

TPose2D toPose(const TimedPose2D& p) { return {p.x, p.y, p.yaw}; }

TPose2D compose(const TPose2D& a, const TPose2D& b) {
  const double c = std::cos(a.phi), s = std::sin(a.phi);
  return {a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y, wrapAngle(a.phi + b.phi)};
}

/** a⁻¹ b: b seen from a. */
TPose2D between(const TPose2D& a, const TPose2D& b) {
  const double c = std::cos(a.phi), s = std::sin(a.phi);
  const double dx = b.x - a.x, dy = b.y - a.y;
  return {c * dx + s * dy, -s * dx + c * dy, wrapAngle(b.phi - a.phi)};
}

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

std::string span(const Trajectory2D& t) {
  if (t.empty()) return "no poses";
  return std::to_string(t.size()) + " poses, t = " + fmt("%.6f", t.front().t) + " .. " +
         fmt("%.6f", t.back().t) + " s";
}

std::string ruleText(const AssociationParams& p) {
  std::string s = "nearest within " + fmt("%g", p.max_dt) + " s";
  if (p.interpolate) s += " or interpolated across gaps up to " + fmt("%g", p.max_gap) + " s";
  return s;
}

/** Index of the pose nearest in time to t (the earlier one on a tie). */
size_t nearestIndex(const Trajectory2D& traj, double t) {
  auto it = std::lower_bound(traj.begin(), traj.end(), t,
                             [](const TimedPose2D& p, double v) { return p.t < v; });
  if (it == traj.end()) return traj.size() - 1;
  size_t k = static_cast<size_t>(it - traj.begin());
  if (k > 0 && std::abs(traj[k - 1].t - t) <= std::abs(it->t - t)) --k;
  return k;
}

/** Reference pose interpolated at t, when t lies inside a short enough gap. */
std::optional<TimedPose2D> interpolateAt(const Trajectory2D& traj, double t, double max_gap) {
  auto it = std::upper_bound(traj.begin(), traj.end(), t,
                             [](double v, const TimedPose2D& p) { return v < p.t; });
  if (it == traj.begin() || it == traj.end()) return std::nullopt;
  const TimedPose2D& b = *it;
  const TimedPose2D& a = *(it - 1);
  const double gap = b.t - a.t;
  if (gap > max_gap || gap <= 0) return std::nullopt;
  const double u = (t - a.t) / gap;
  TimedPose2D p;
  p.t = t;
  p.x = a.x + u * (b.x - a.x);
  p.y = a.y + u * (b.y - a.y);
  p.yaw = wrapAngle(a.yaw + u * wrapAngle(b.yaw - a.yaw));
  return p;
}

std::vector<double> pathLengths(const Trajectory2D& t) {
  std::vector<double> s(t.size(), 0.0);
  for (size_t k = 1; k < t.size(); ++k)
    s[k] = s[k - 1] + std::hypot(t[k].x - t[k - 1].x, t[k].y - t[k - 1].y);
  return s;
}

}  // namespace

double wrapAngle(double a) {
  a = std::remainder(a, 2 * M_PI);  // [-pi, pi]
  return a <= -M_PI ? a + 2 * M_PI : a;
}

std::optional<TimedPose2D> poseAt(const Trajectory2D& traj, double t, const AssociationParams& p) {
  if (traj.empty()) return std::nullopt;
  if (p.interpolate) {
    // An exact (or near-exact) sample beats interpolation across it.
    const size_t k = nearestIndex(traj, t);
    if (std::abs(traj[k].t - t) <= 1e-9) return traj[k];
    if (auto q = interpolateAt(traj, t, p.max_gap)) return q;
  }
  const size_t k = nearestIndex(traj, t);
  if (std::abs(traj[k].t - t) <= p.max_dt) return traj[k];
  return std::nullopt;
}

size_t repeatedStamps(const Trajectory2D& t) {
  size_t n = 0;
  for (size_t i = 1; i < t.size(); ++i)
    if (t[i].t == t[i - 1].t) ++n;
  return n;
}

Association associate(const Trajectory2D& est, const Trajectory2D& ref,
                      const AssociationParams& p) {
  Association a;
  a.est_total = est.size();
  a.ref_total = ref.size();
  if (p.by_index) {
    // The k-th estimated pose against the k-th reference pose: for logs whose
    // timestamps do not tell poses apart (one pose per scan in both files).
    if (est.size() != ref.size())
      throw InputError(
          "by-index association needs as many estimated as reference poses: "
          "estimate " +
          span(est) + "; reference " + span(ref));
    if (est.size() < 2)
      throw InputError("by-index association needs at least 2 poses; estimate: " + span(est));
    a.est = est;
    a.ref = ref;
    for (size_t i = 0; i < est.size(); ++i) {
      a.ref[i].t = est[i].t;
      a.est_index.push_back(i);
    }
    return a;
  }
  if (!est.empty() && !ref.empty()) {
    for (size_t i = 0; i < est.size(); ++i) {
      const double t = est[i].t;
      if (p.interpolate) {
        const size_t k = nearestIndex(ref, t);
        if (std::abs(ref[k].t - t) > 1e-9) {
          if (auto q = interpolateAt(ref, t, p.max_gap)) {
            a.est.push_back(est[i]);
            a.ref.push_back(*q);
            a.est_index.push_back(i);
            ++a.interpolated;
            continue;
          }
        }
      }
      // Mutual nearest neighbours: each reference pose is used at most once,
      // so a faster estimate does not count one reference pose many times.
      const size_t j = nearestIndex(ref, t);
      if (std::abs(ref[j].t - t) > p.max_dt) continue;
      if (!p.interpolate && nearestIndex(est, ref[j].t) != i) continue;
      a.est.push_back(est[i]);
      a.ref.push_back(ref[j]);
      a.ref.back().t = t;
      a.est_index.push_back(i);
    }
  }
  if (a.size() < 2) {
    const size_t rep_est = repeatedStamps(est), rep_ref = repeatedStamps(ref);
    if (rep_est || rep_ref)
      throw InputError(
          "only " + std::to_string(a.size()) + " of " + std::to_string(est.size()) +
          " estimated poses matched a reference pose by time (" + ruleText(p) +
          "): the timestamps do not tell the poses apart (estimate: " + span(est) + ", " +
          std::to_string(rep_est) + " repeat the time before; reference: " + span(ref) + ", " +
          std::to_string(rep_ref) +
          " repeat the time before); associate the k-th poses of both files with --by-index");
    throw InputError("the timestamps of the estimate and the reference do not overlap: " +
                     std::to_string(a.size()) + " of " + std::to_string(est.size()) +
                     " estimated poses matched a reference pose (" + ruleText(p) +
                     "), at least 2 are needed; estimate: " + span(est) +
                     "; reference: " + span(ref));
  }
  return a;
}

ErrorStats ErrorStats::of(std::vector<double> v) {
  ErrorStats s;
  s.n = v.size();
  if (v.empty()) {
    s.rmse = s.mean = s.median = s.std = s.min = s.max = kNaN;
    return s;
  }
  std::sort(v.begin(), v.end());
  double sum = 0, sq = 0;
  for (double x : v) {
    sum += x;
    sq += x * x;
  }
  const double n = static_cast<double>(v.size());
  s.mean = sum / n;
  s.rmse = std::sqrt(sq / n);
  double var = 0;
  for (double x : v) var += (x - s.mean) * (x - s.mean);
  s.std = std::sqrt(var / n);
  s.min = v.front();
  s.max = v.back();
  const size_t m = v.size() / 2;
  s.median = (v.size() % 2) ? v[m] : 0.5 * (v[m - 1] + v[m]);
  return s;
}

TPose2D alignSE2(const Trajectory2D& est, const Trajectory2D& ref) {
  if (est.size() != ref.size())
    throw std::invalid_argument("alignSE2: the trajectories must have the same length");
  if (est.empty()) return {0, 0, 0};
  const double n = static_cast<double>(est.size());
  double ex = 0, ey = 0, rx = 0, ry = 0;
  for (size_t k = 0; k < est.size(); ++k) {
    ex += est[k].x;
    ey += est[k].y;
    rx += ref[k].x;
    ry += ref[k].y;
  }
  ex /= n, ey /= n, rx /= n, ry /= n;
  // With H the cross-covariance of the centred points, the best rotation
  // angle maximises trace(R H): atan2(H_xy - H_yx, H_xx + H_yy).
  double dot = 0, cross = 0;
  for (size_t k = 0; k < est.size(); ++k) {
    const double ax = est[k].x - ex, ay = est[k].y - ey;
    const double bx = ref[k].x - rx, by = ref[k].y - ry;
    dot += ax * bx + ay * by;
    cross += ax * by - ay * bx;
  }
  const double th = (std::abs(dot) + std::abs(cross) > 0) ? std::atan2(cross, dot) : 0.0;
  const double c = std::cos(th), s = std::sin(th);
  return {rx - (c * ex - s * ey), ry - (s * ex + c * ey), th};
}

Trajectory2D transformTrajectory(const Trajectory2D& traj, const TPose2D& T) {
  Trajectory2D out;
  out.reserve(traj.size());
  for (const auto& p : traj) {
    const TPose2D q = compose(T, toPose(p));
    out.push_back({p.t, q.x, q.y, q.phi});
  }
  return out;
}

AteResult computeAte(const Association& a, bool align) {
  AteResult r;
  r.aligned = align;
  r.alignment = align ? alignSE2(a.est, a.ref) : TPose2D(0, 0, 0);
  r.est_aligned = transformTrajectory(a.est, r.alignment);
  for (size_t k = 0; k < a.size(); ++k) {
    const auto& e = r.est_aligned[k];
    const auto& g = a.ref[k];
    r.trans_errors.push_back(std::hypot(g.x - e.x, g.y - e.y));
    r.rot_errors.push_back(std::abs(wrapAngle(g.yaw - e.yaw)) * kRad2Deg);
  }
  r.translation = ErrorStats::of(r.trans_errors);
  r.rotation = ErrorStats::of(r.rot_errors);
  return r;
}

RpeResult computeRpe(const Association& a, double distance) {
  RpeResult r;
  r.distance = distance > 0 ? distance : 0;
  const std::vector<double> s = pathLengths(a.ref);
  const size_t n = a.size();
  std::vector<double> te, re;
  double drift_sum = 0, rot_drift_sum = 0;
  size_t drift_n = 0;
  size_t j = 0;
  for (size_t i = 0; i + 1 < n; ++i) {
    if (distance > 0) {
      j = std::max(j, i + 1);  // s is non-decreasing, so j only moves forward
      while (j < n && s[j] - s[i] < distance - kPathEps) ++j;
      if (j == n) break;
    } else {
      j = i + 1;
    }
    const TPose2D dref = between(toPose(a.ref[i]), toPose(a.ref[j]));
    const TPose2D dest = between(toPose(a.est[i]), toPose(a.est[j]));
    const TPose2D e = between(dref, dest);
    const double et = std::hypot(e.x, e.y);
    const double er = std::abs(e.phi) * kRad2Deg;
    te.push_back(et);
    re.push_back(er);
    const double len = s[j] - s[i];
    if (len > kPathEps) {  // standing still: no drift per metre to speak of
      drift_sum += et / len;
      rot_drift_sum += er / len;
      ++drift_n;
    }
  }
  r.translation = ErrorStats::of(te);
  r.rotation = ErrorStats::of(re);
  r.drift_percent = drift_n ? 100.0 * drift_sum / drift_n : kNaN;
  r.rot_drift_deg_per_m = drift_n ? rot_drift_sum / drift_n : kNaN;
  return r;
}

std::vector<Relation> readRelations(const std::string& path) {
  std::vector<Relation> out;
  readNumberRows(path, 8, "t1 t2 x y z roll pitch yaw", [&](const double* v, int lineno) {
    Relation r;
    r.t1 = v[0];
    r.t2 = v[1];
    r.delta = {v[2], v[3], wrapAngle(v[7])};
    r.line = lineno;
    out.push_back(r);
  });
  if (out.empty()) throw InputError(path + ": no relations in the file");
  return out;
}

void writeRelations(const std::string& path, const std::vector<Relation>& rels) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream f(tmp);
    if (!f) throw std::runtime_error(path + ": cannot write the relations");
    f << "# t1 t2 x y z roll pitch yaw (relative pose from t1 to t2 in the frame at t1)\n";
    char buf[256];
    for (const auto& r : rels) {
      std::snprintf(buf, sizeof buf, "%.6f %.6f %.6f %.6f 0 0 0 %.9f\n", r.t1, r.t2, r.delta.x,
                    r.delta.y, r.delta.phi);
      f << buf;
    }
    if (!f.flush()) throw std::runtime_error(path + ": cannot write the relations");
  }
  std::filesystem::rename(tmp, path);
}

std::vector<Relation> makeRelations(const Trajectory2D& ref, double distance) {
  if (!(distance > 0)) throw std::invalid_argument("makeRelations: distance must be > 0");
  std::vector<Relation> out;
  const std::vector<double> s = pathLengths(ref);
  size_t j = 0;
  for (size_t i = 0; i + 1 < ref.size(); ++i) {
    j = std::max(j, i + 1);
    while (j < ref.size() && s[j] - s[i] < distance - kPathEps) ++j;
    if (j == ref.size()) break;
    Relation r;
    r.t1 = ref[i].t;
    r.t2 = ref[j].t;
    r.delta = between(toPose(ref[i]), toPose(ref[j]));
    out.push_back(r);
  }
  return out;
}

RelationsResult computeRelationsError(const Trajectory2D& est, const std::vector<Relation>& rels,
                                      const AssociationParams& p) {
  RelationsResult r;
  r.total = rels.size();
  std::vector<double> te, te2, re, re2;
  for (const auto& rel : rels) {
    const auto a = poseAt(est, rel.t1, p);
    const auto b = poseAt(est, rel.t2, p);
    if (!a || !b) continue;
    const TPose2D d = between(toPose(*a), toPose(*b));
    const TPose2D e = between(rel.delta, d);
    const double et = std::hypot(e.x, e.y);
    const double er = std::abs(e.phi) * kRad2Deg;
    te.push_back(et);
    te2.push_back(et * et);
    re.push_back(er);
    re2.push_back(er * er);
  }
  r.used = te.size();
  if (r.used == 0) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const auto& rel : rels) {
      lo = std::min({lo, rel.t1, rel.t2});
      hi = std::max({hi, rel.t1, rel.t2});
    }
    throw InputError(
        "the timestamps of the estimate and the relations do not overlap: none of " +
        std::to_string(rels.size()) + " relations has estimated poses at both its times (" +
        ruleText(p) + "); relations: t = " +
        (rels.empty() ? std::string("none") : fmt("%.6f", lo) + " .. " + fmt("%.6f", hi) + " s") +
        "; estimate: " + span(est));
  }
  r.translation = ErrorStats::of(te);
  r.translation_sq = ErrorStats::of(te2);
  r.rotation = ErrorStats::of(re);
  r.rotation_sq = ErrorStats::of(re2);
  return r;
}

}  // namespace carenav::io
