// carenav eval --est A.tum --ref B.tum [--relations R] [--out DIR] [--json]
#include "commands.h"

#include <carenav/common/errors.h>
#include <carenav/common/json.h>
#include <carenav/io/trajectory.h>
#include <carenav/slam/evaluation.h>
#include <carenav/slam/trajectory_plot.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>

namespace carenav::app {

namespace {
namespace fs = std::filesystem;
using slam::ErrorStats;

struct EvalArgs {
  std::string est, ref, relations, out, make_relations;
  double max_dt = 0.02;
  bool interpolate = false;
  double max_gap = 0.5;
  bool by_index = false;
  bool no_align = false;
  std::vector<double> rpe_dist{1, 5};
  double rel_dist = 1;
  bool json = false;
};

/** Everything computed; a stage that failed leaves its field empty. */
struct EvalResult {
  io::Trajectory2D est, ref;
  std::optional<slam::Association> assoc;
  std::optional<slam::AteResult> ate;
  std::optional<slam::RpeResult> rpe_step;
  std::vector<slam::RpeResult> rpe;
  std::optional<slam::RelationsResult> rel;
  std::vector<std::string> outputs;
};

constexpr double kRad2Deg = 180.0 / M_PI;

std::string cell(double v, const char* f = "%10.4f") {
  if (!std::isfinite(v)) return "         -";
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

std::string spanText(const io::Trajectory2D& t) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "%zu poses, t = %.6f .. %.6f s", t.size(), t.front().t,
                t.back().t);
  return buf;
}

void statsJson(JsonWriter& j, const ErrorStats& s, bool full = true) {
  j.beginObject();
  j.key("n").value(static_cast<uint64_t>(s.n));
  if (full) j.key("rmse").value(s.rmse);
  j.key("mean").value(s.mean);
  if (full) j.key("median").value(s.median);
  j.key("std").value(s.std);
  if (full) j.key("min").value(s.min);
  j.key("max").value(s.max);
  j.endObject();
}

void rpeJson(JsonWriter& j, const slam::RpeResult& r) {
  j.beginObject();
  j.key("delta_m").value(r.distance);
  j.key("pairs").value(static_cast<uint64_t>(r.translation.n));
  j.key("translation_m");
  statsJson(j, r.translation);
  j.key("rotation_deg");
  statsJson(j, r.rotation);
  j.key("drift_percent").value(r.drift_percent);
  j.key("rotation_deg_per_m").value(r.rot_drift_deg_per_m);
  j.endObject();
}

void fileJson(JsonWriter& j, const std::string& path, const io::Trajectory2D& t) {
  j.beginObject();
  j.key("file").value(path);
  j.key("poses").value(static_cast<uint64_t>(t.size()));
  j.key("t_start").value(t.front().t);
  j.key("t_end").value(t.back().t);
  j.endObject();
}

std::string toJson(const EvalArgs& a, const EvalResult& r) {
  JsonWriter j;
  j.beginObject();
  j.key("estimate");
  fileJson(j, a.est, r.est);
  j.key("reference");
  if (r.ref.empty())
    j.null();
  else
    fileJson(j, a.ref, r.ref);
  j.key("association").beginObject();
  j.key("method").value(a.by_index ? "index" : a.interpolate ? "interpolate" : "nearest");
  j.key("max_dt_s").value(a.max_dt);
  if (a.interpolate) j.key("max_gap_s").value(a.max_gap);
  j.key("matched").value(static_cast<uint64_t>(r.assoc ? r.assoc->size() : 0));
  j.key("interpolated").value(static_cast<uint64_t>(r.assoc ? r.assoc->interpolated : 0));
  j.endObject();
  j.key("alignment");
  if (r.ate) {
    j.beginObject();
    j.key("applied").value(r.ate->aligned);
    j.key("x_m").value(r.ate->alignment.x);
    j.key("y_m").value(r.ate->alignment.y);
    j.key("yaw_deg").value(r.ate->alignment.phi * kRad2Deg);
    j.endObject();
  } else {
    j.null();
  }
  j.key("ate");
  if (r.ate) {
    j.beginObject();
    j.key("translation_m");
    statsJson(j, r.ate->translation);
    j.key("rotation_deg");
    statsJson(j, r.ate->rotation);
    j.endObject();
  } else {
    j.null();
  }
  j.key("rpe_step");
  if (r.rpe_step)
    rpeJson(j, *r.rpe_step);
  else
    j.null();
  j.key("rpe").beginArray();
  for (const auto& x : r.rpe) rpeJson(j, x);
  j.endArray();
  j.key("relations");
  if (r.rel) {
    j.beginObject();
    j.key("file").value(a.relations.empty() ? a.make_relations : a.relations);
    j.key("total").value(static_cast<uint64_t>(r.rel->total));
    j.key("used").value(static_cast<uint64_t>(r.rel->used));
    j.key("translation_m");
    statsJson(j, r.rel->translation, false);
    j.key("translation_sq_m2");
    statsJson(j, r.rel->translation_sq, false);
    j.key("rotation_deg");
    statsJson(j, r.rel->rotation, false);
    j.key("rotation_sq_deg2");
    statsJson(j, r.rel->rotation_sq, false);
    j.endObject();
  } else {
    j.null();
  }
  j.key("outputs").beginArray();
  for (const auto& o : r.outputs) j.value(o);
  j.endArray();
  j.endObject();
  return j.str() + "\n";
}

std::string toText(const EvalArgs& a, const EvalResult& r) {
  std::string o;
  auto line = [&o](const std::string& s) { o += s + "\n"; };
  line("estimate    " + a.est + ": " + spanText(r.est));
  if (!r.ref.empty()) line("reference   " + a.ref + ": " + spanText(r.ref));
  if (r.assoc) {
    char buf[256];
    if (a.by_index)
      std::snprintf(buf, sizeof buf, "matched     %zu of %zu estimated poses (by index)",
                    r.assoc->size(), r.assoc->est_total);
    else
      std::snprintf(buf, sizeof buf, "matched     %zu of %zu estimated poses (%s, max-dt %g s)",
                    r.assoc->size(), r.assoc->est_total,
                    a.interpolate ? "interpolated reference" : "nearest timestamps", a.max_dt);
    std::string s = buf;
    if (a.interpolate) s += ", " + std::to_string(r.assoc->interpolated) + " interpolated";
    line(s);
  }
  if (r.ate) {
    char buf[256];
    if (r.ate->aligned)
      std::snprintf(buf, sizeof buf,
                    "alignment   SE(2) applied to the estimate: x %.4f m, y %.4f m, yaw %.3f deg",
                    r.ate->alignment.x, r.ate->alignment.y, r.ate->alignment.phi * kRad2Deg);
    else
      std::snprintf(buf, sizeof buf, "alignment   none (--no-align)");
    line(buf);
    line("");
    line("ATE (absolute trajectory error)");
    line(std::string(19, ' ') + "      rmse      mean    median       std       max");
    const auto row = [&](const char* name, const ErrorStats& s) {
      line(std::string(name) + cell(s.rmse) + cell(s.mean) + cell(s.median) + cell(s.std) +
           cell(s.max));
    };
    row("  translation [m]  ", r.ate->translation);
    row("  rotation [deg]   ", r.ate->rotation);
  }
  if (r.rpe_step) {
    line("");
    line("RPE (relative pose error)");
    char head[256];
    std::snprintf(head, sizeof head, "  %-8s%7s%16s%16s%11s%16s%13s", "delta", "pairs",
                  "trans rmse [m]", "trans mean [m]", "drift [%]", "rot mean [deg]", "rot [deg/m]");
    line(head);
    const auto row = [&](const std::string& name, const slam::RpeResult& x) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "  %-8s%7zu", name.c_str(), x.translation.n);
      line(std::string(buf) + "      " + cell(x.translation.rmse) + "      " +
           cell(x.translation.mean) + " " + cell(x.drift_percent, "%10.2f") + "      " +
           cell(x.rotation.mean, "%10.3f") + "   " + cell(x.rot_drift_deg_per_m, "%10.3f"));
    };
    row("step", *r.rpe_step);
    for (const auto& x : r.rpe) {
      char name[32];
      std::snprintf(name, sizeof name, "%g m", x.distance);
      row(name, x);
    }
  }
  if (r.rel) {
    line("");
    line("Relations metric (Kuemmerle et al. 2009): " + std::to_string(r.rel->used) + " of " +
         std::to_string(r.rel->total) + " relations used");
    line(std::string(22, ' ') + "      mean       std       max");
    const auto row = [&](const char* name, const ErrorStats& s, const char* f) {
      line(std::string(name) + cell(s.mean, f) + cell(s.std, f) + cell(s.max, f));
    };
    // Squared errors are small; %g keeps their digits.
    row("  translation [m]     ", r.rel->translation, "%10.4f");
    row("  translation^2 [m^2] ", r.rel->translation_sq, "%10.3g");
    row("  rotation [deg]      ", r.rel->rotation, "%10.4f");
    row("  rotation^2 [deg^2]  ", r.rel->rotation_sq, "%10.3g");
  }
  for (const auto& f : r.outputs) line("wrote       " + f);
  return o;
}

void checkArgs(const EvalArgs& a) {
  if (!(a.max_dt >= 0) || !std::isfinite(a.max_dt))
    throw InputError("--max-dt must be a finite number >= 0 (seconds)");
  if (!(a.max_gap > 0) || !std::isfinite(a.max_gap))
    throw InputError("--max-gap must be a finite number > 0 (seconds)");
  for (double d : a.rpe_dist)
    if (!(d > 0) || !std::isfinite(d))
      throw InputError("--rpe-dist: every distance must be a finite number > 0 (metres)");
  if (!(a.rel_dist > 0) || !std::isfinite(a.rel_dist))
    throw InputError("--rel-dist must be a finite number > 0 (metres)");
  if (!a.make_relations.empty() && a.ref.empty())
    throw InputError("--make-relations needs --ref (the trajectory to take relations from)");
  if (a.make_relations.empty() && a.est.empty())
    throw InputError("--est is required (the trajectory to evaluate)");
  if (!a.est.empty() && a.ref.empty() && a.relations.empty() && a.make_relations.empty())
    throw InputError("nothing to compare with: give --ref, --relations or both");
  if (a.by_index && a.ref.empty())
    throw InputError("--by-index pairs the estimate with a --ref trajectory: give --ref");
  if (!a.relations.empty() && !a.make_relations.empty())
    throw InputError("--relations and --make-relations exclude each other");
}

void writeOutputs(const EvalArgs& a, EvalResult& r) {
  const fs::path dir(a.out);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (!fs::is_directory(dir))
    throw InputError(a.out + ": cannot create the output directory" +
                     (ec ? " (" + ec.message() + ")" : std::string()));
  const std::string json = (dir / "eval.json").string();
  const std::string traj_png = (dir / "trajectories.png").string();
  const std::string ate_png = (dir / "ate.png").string();
  const std::string aligned = (dir / "estimate_aligned.tum").string();
  r.outputs = {json, traj_png};
  if (r.ate) r.outputs.push_back(ate_png);
  if (r.ate) r.outputs.push_back(aligned);

  // The whole estimate moved by the alignment, so the picture and the TUM file
  // show it where the ATE saw it.
  const mrpt::math::TPose2D T = r.ate ? r.ate->alignment : mrpt::math::TPose2D(0, 0, 0);
  const io::Trajectory2D est_aligned = slam::transformTrajectory(r.est, T);
  std::vector<slam::NamedTrajectory> tracks;
  // A wide light reference under a narrow estimate: both stay visible where
  // they overlap.
  if (!r.ref.empty()) tracks.push_back({"reference", r.ref, mrpt::img::TColor(150, 150, 150), 4});
  tracks.push_back({"estimate", est_aligned, mrpt::img::TColor(214, 39, 40), 1});
  slam::PlotOptions po;
  char title[256];
  if (r.ate) {
    std::snprintf(title, sizeof title, "%s: ATE RMSE %.3f m%s", fs::path(a.est).filename().c_str(),
                  r.ate->translation.rmse, r.ate->aligned ? " (SE(2)-aligned)" : " (not aligned)");
    // Residuals of at most ~600 pairs keep the picture readable.
    const size_t step = std::max<size_t>(1, r.assoc->size() / 600);
    for (size_t k = 0; k < r.assoc->size(); k += step)
      po.links.push_back({{r.ate->est_aligned[k].x, r.ate->est_aligned[k].y},
                          {r.assoc->ref[k].x, r.assoc->ref[k].y}});
  } else {
    std::snprintf(title, sizeof title, "%s", fs::path(a.est).filename().c_str());
  }
  po.title = title;
  slam::renderTrajectories(tracks, traj_png, po);

  if (r.ate) {
    std::vector<double> t;
    const double t0 = r.assoc->est.front().t;
    for (const auto& p : r.assoc->est) t.push_back(p.t - t0);
    slam::SeriesPlotOptions so;
    so.title = "ATE translation error over time";
    so.x_label = "time since the first matched pose [s]";
    so.y_label = "error [m]";
    char lab[64];
    std::snprintf(lab, sizeof lab, "RMSE %.3f m", r.ate->translation.rmse);
    so.markers.push_back({r.ate->translation.rmse, lab});
    slam::renderSeries(t, r.ate->trans_errors, ate_png, so);
    io::writeTum(aligned, est_aligned);
  }
  std::ofstream f(json);
  f << toJson(a, r);
  if (!f.flush()) throw std::runtime_error(json + ": cannot write");
}

void runEval(const EvalArgs& a, const GlobalOptions& g) {
  checkArgs(a);
  if (!a.out.empty()) prepareOutputFolder(a.out);
  slam::AssociationParams ap;
  ap.max_dt = a.max_dt;
  ap.interpolate = a.interpolate;
  ap.max_gap = a.max_gap;
  ap.by_index = a.by_index;

  EvalResult r;
  std::vector<slam::Relation> rels;
  size_t reordered = 0;
  if (!a.ref.empty()) r.ref = io::readTum(a.ref, &reordered);
  if (reordered)
    std::cerr << "note: " << a.ref << ": " << reordered
              << " timestamps step back; the poses were sorted by time\n";
  if (!a.make_relations.empty()) {
    rels = slam::makeRelations(r.ref, a.rel_dist);
    if (rels.empty())
      throw InputError(a.ref + ": no relations: the trajectory travels less than --rel-dist " +
                       std::to_string(a.rel_dist) + " m");
    slam::writeRelations(a.make_relations, rels);
    if (!g.quiet)
      std::cerr << "carenav eval: wrote " << rels.size() << " relations (" << a.rel_dist
                << " m apart) to " << a.make_relations << "\n";
    if (a.est.empty()) return;
  }
  size_t est_reordered = 0;
  r.est = io::readTum(a.est, &est_reordered);
  if (est_reordered)
    std::cerr << "note: " << a.est << ": " << est_reordered
              << " timestamps step back; the poses were sorted by time\n";
  if (!a.relations.empty()) rels = slam::readRelations(a.relations);

  // Stages that fail on bad input leave their error for the end, so what the
  // other stages computed is still printed and saved.
  std::optional<InputError> deferred;
  if (!r.ref.empty()) {
    try {
      r.assoc = slam::associate(r.est, r.ref, ap);
    } catch (const InputError& e) {
      deferred = InputError(a.est + " vs " + a.ref + ": " + e.what());
    }
  }
  if (r.assoc) {
    r.ate = slam::computeAte(*r.assoc, !a.no_align);
    r.rpe_step = slam::computeRpe(*r.assoc, 0);
    for (double d : a.rpe_dist) r.rpe.push_back(slam::computeRpe(*r.assoc, d));
  }
  if (!rels.empty()) {
    try {
      r.rel = slam::computeRelationsError(r.est, rels, ap);
    } catch (const InputError& e) {
      const std::string rf = a.relations.empty() ? a.make_relations : a.relations;
      if (!deferred) deferred = InputError(a.est + " vs " + rf + ": " + e.what());
    }
  }
  if (!a.out.empty() && (r.ate || r.rel)) writeOutputs(a, r);
  if (r.ate || r.rel) std::cout << (a.json ? toJson(a, r) : toText(a, r)) << std::flush;
  if (deferred) throw *deferred;
}

void addEvalCommand(CLI::App& app, const GlobalOptions& g) {
  auto a = std::make_shared<EvalArgs>();
  auto* cmd = app.add_subcommand(
      "eval",
      "Trajectory accuracy of an estimate (SLAM or localisation output, TUM file) against a "
      "reference: poses paired by timestamp; ATE after a least-squares SE(2) alignment "
      "(RMSE, mean, median, std, max of the translation and rotation errors); RPE per step and "
      "over travelled distances; the relations metric of Kuemmerle et al. 2009 with a "
      "relations file (t1 t2 x y z roll pitch yaw). With --out DIR: eval.json, "
      "trajectories.png, ate.png and estimate_aligned.tum. See docs/eval.md.\n"
      "Examples:\n"
      "  carenav eval --est slam.tum --ref gt.tum --out eval/\n"
      "  carenav eval --est slam.tum --relations intel.relations --json\n"
      "  carenav eval --ref gt.tum --make-relations gt.relations --rel-dist 1");
  cmd->add_option("--est", a->est, "Estimated trajectory (TUM: t x y z qx qy qz qw)");
  cmd->add_option("--ref", a->ref, "Reference trajectory (TUM); optional with --relations");
  cmd->add_option("--relations", a->relations,
                  "Relations file (t1 t2 x y z roll pitch yaw per line, as the Freiburg "
                  "benchmark's): adds the Kuemmerle et al. 2009 metric");
  cmd->add_option("--out", a->out,
                  "Output directory: eval.json, trajectories.png, ate.png, estimate_aligned.tum");
  cmd->add_flag("--json", a->json, "Print JSON instead of text");
  cmd->add_option("--max-dt", a->max_dt,
                  "Largest time difference (s) of a pose pair matched by nearest timestamps")
      ->capture_default_str();
  cmd->add_flag("--interpolate", a->interpolate,
                "Interpolate the reference linearly at the estimate's timestamps (when the "
                "reference is sampled at other times); nearest matching elsewhere");
  cmd->add_option("--max-gap", a->max_gap,
                  "With --interpolate: longest reference gap (s) to interpolate across")
      ->capture_default_str();
  cmd->add_flag("--by-index", a->by_index,
                "Pair the k-th estimated pose with the k-th reference pose, timestamps ignored "
                "(both files must have as many poses): for logs whose timestamps repeat")
      ->excludes("--interpolate");
  cmd->add_flag("--no-align", a->no_align,
                "ATE without the SE(2) alignment (when both are in the same frame already)");
  cmd->add_option("--rpe-dist", a->rpe_dist,
                  "Travelled distances (m) of the RPE, comma-separated, e.g. 1,2,5,10")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--make-relations", a->make_relations,
                  "Write a relations file made from --ref (a pair for each pose and the first "
                  "pose --rel-dist metres further along the path); with --est, also evaluate it")
      ->type_name("FILE");
  cmd->add_option("--rel-dist", a->rel_dist, "Travelled distance (m) of --make-relations pairs")
      ->capture_default_str();
  cmd->callback([a, &g] { runEval(*a, g); });
}
}  // namespace

CARENAV_COMMAND(90, addEvalCommand);

}  // namespace carenav::app
