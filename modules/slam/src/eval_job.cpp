#include <carenav/common/json.h>
#include <carenav/io/trajectory.h>
#include <carenav/slam/eval_job.h>
#include <carenav/slam/trajectory_plot.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>

namespace carenav::slam {

namespace {

namespace fs = std::filesystem;

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

Json statsJson(const io::ErrorStats& s, bool full = true) {
  Json j = Json::object();
  j["n"] = s.n;
  if (full) j["rmse"] = s.rmse;
  j["mean"] = s.mean;
  if (full) j["median"] = s.median;
  j["std"] = s.std;
  if (full) j["min"] = s.min;
  j["max"] = s.max;
  return j;
}

Json rpeJson(const io::RpeResult& r) {
  return {{"delta_m", r.distance},
          {"pairs", r.translation.n},
          {"translation_m", statsJson(r.translation)},
          {"rotation_deg", statsJson(r.rotation)},
          {"drift_percent", r.drift_percent},
          {"rotation_deg_per_m", r.rot_drift_deg_per_m}};
}

Json fileJson(const std::string& path, const io::Trajectory2D& t) {
  return {{"file", path}, {"poses", t.size()}, {"t_start", t.front().t}, {"t_end", t.back().t}};
}

Json associationJson(const EvalJobOptions& o, const std::optional<io::Association>& a) {
  Json j = Json::object();
  j["method"] = o.assoc.by_index ? "index" : o.assoc.interpolate ? "interpolate" : "nearest";
  j["max_dt_s"] = o.assoc.max_dt;
  if (o.assoc.interpolate) j["max_gap_s"] = o.assoc.max_gap;
  j["matched"] = a ? a->size() : 0;
  j["interpolated"] = a ? a->interpolated : 0;
  return j;
}

Json alignmentJson(const io::AteResult& ate) {
  return {{"applied", ate.aligned},
          {"x_m", ate.alignment.x},
          {"y_m", ate.alignment.y},
          {"yaw_deg", ate.alignment.phi * kRad2Deg}};
}

Json relationsJson(const EvalJobOptions& o, const io::RelationsResult& r) {
  return {{"file", o.relations.empty() ? o.make_relations : o.relations},
          {"total", r.total},
          {"used", r.used},
          {"translation_m", statsJson(r.translation, false)},
          {"translation_sq_m2", statsJson(r.translation_sq, false)},
          {"rotation_deg", statsJson(r.rotation, false)},
          {"rotation_sq_deg2", statsJson(r.rotation_sq, false)}};
}

/** "note: FILE: N timestamps step back; ..." when readTum sorted the file. */
io::Trajectory2D readSorted(const std::string& path) {
  size_t reordered = 0;
  io::Trajectory2D t = io::readTum(path, &reordered);
  if (reordered)
    std::cerr << "note: " << path << ": " << reordered
              << " timestamps step back; the poses were sorted by time\n";
  return t;
}

void writeOutputs(const EvalJobOptions& a, EvalJobResult& r) {
  const fs::path dir(a.out_dir);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (!fs::is_directory(dir))
    throw InputError(a.out_dir + ": cannot create the output directory" +
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
  const io::Trajectory2D est_aligned = io::transformTrajectory(r.est, T);
  std::vector<NamedTrajectory> tracks;
  // A wide light reference under a narrow estimate: both stay visible where
  // they overlap.
  if (!r.ref.empty()) tracks.push_back({"reference", r.ref, mrpt::img::TColor(150, 150, 150), 4});
  tracks.push_back({"estimate", est_aligned, mrpt::img::TColor(214, 39, 40), 1});
  PlotOptions po;
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
  renderTrajectories(tracks, traj_png, po);

  if (r.ate) {
    std::vector<double> t;
    const double t0 = r.assoc->est.front().t;
    for (const auto& p : r.assoc->est) t.push_back(p.t - t0);
    SeriesPlotOptions so;
    so.title = "ATE translation error over time";
    so.x_label = "time since the first matched pose [s]";
    so.y_label = "error [m]";
    char lab[64];
    std::snprintf(lab, sizeof lab, "RMSE %.3f m", r.ate->translation.rmse);
    so.markers.push_back({r.ate->translation.rmse, lab});
    renderSeries(t, r.ate->trans_errors, ate_png, so);
    io::writeTum(aligned, est_aligned);
  }
  std::ofstream f(json);
  f << r.toJson(a);
  if (!f.flush()) throw std::runtime_error(json + ": cannot write");
}

}  // namespace

Json EvalJobResult::toJsonValue(const EvalJobOptions& o) const {
  const EvalJobResult& r = *this;
  Json j = Json::object();
  j["estimate"] = fileJson(o.est, r.est);
  j["reference"] = r.ref.empty() ? Json() : fileJson(o.ref, r.ref);
  j["association"] = associationJson(o, r.assoc);
  j["alignment"] = r.ate ? alignmentJson(*r.ate) : Json();
  j["ate"] = r.ate ? Json{{"translation_m", statsJson(r.ate->translation)},
                          {"rotation_deg", statsJson(r.ate->rotation)}}
                   : Json();
  j["rpe_step"] = r.rpe_step ? rpeJson(*r.rpe_step) : Json();
  j["rpe"] = Json::array();
  for (const auto& x : r.rpe) j["rpe"].push_back(rpeJson(x));
  j["relations"] = r.rel ? relationsJson(o, *r.rel) : Json();
  j["outputs"] = r.outputs;
  return j;
}

std::string EvalJobResult::toJson(const EvalJobOptions& o) const {
  return dumpJson(toJsonValue(o)) + "\n";
}

std::string EvalJobResult::toText(const EvalJobOptions& a) const {
  const EvalJobResult& r = *this;
  std::string o;
  auto line = [&o](const std::string& s) { o += s + "\n"; };
  line("estimate    " + a.est + ": " + spanText(r.est));
  if (!r.ref.empty()) line("reference   " + a.ref + ": " + spanText(r.ref));
  if (r.assoc) {
    char buf[256];
    if (a.assoc.by_index)
      std::snprintf(buf, sizeof buf, "matched     %zu of %zu estimated poses (by index)",
                    r.assoc->size(), r.assoc->est_total);
    else
      std::snprintf(buf, sizeof buf, "matched     %zu of %zu estimated poses (%s, max-dt %g s)",
                    r.assoc->size(), r.assoc->est_total,
                    a.assoc.interpolate ? "interpolated reference" : "nearest timestamps",
                    a.assoc.max_dt);
    std::string s = buf;
    if (a.assoc.interpolate) s += ", " + std::to_string(r.assoc->interpolated) + " interpolated";
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
    const auto row = [&](const char* name, const io::ErrorStats& s) {
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
    const auto row = [&](const std::string& name, const io::RpeResult& x) {
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
    const auto row = [&](const char* name, const io::ErrorStats& s, const char* f) {
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

EvalJobResult runEvalJob(const EvalJobOptions& a) {
  EvalJobResult r;
  std::vector<io::Relation> rels;
  if (!a.ref.empty()) r.ref = readSorted(a.ref);
  if (!a.make_relations.empty()) {
    rels = io::makeRelations(r.ref, a.rel_dist);
    if (rels.empty())
      throw InputError(a.ref + ": no relations: the trajectory travels less than --rel-dist " +
                       std::to_string(a.rel_dist) + " m");
    io::writeRelations(a.make_relations, rels);
    if (a.progress)
      std::cerr << "carenav eval: wrote " << rels.size() << " relations (" << a.rel_dist
                << " m apart) to " << a.make_relations << "\n";
    if (a.est.empty()) return r;
  }
  r.est = readSorted(a.est);
  if (!a.relations.empty()) rels = io::readRelations(a.relations);

  // Stages that fail on bad input leave their error for the end, so what the
  // other stages computed is still reported and saved.
  if (!r.ref.empty()) {
    try {
      r.assoc = io::associate(r.est, r.ref, a.assoc);
    } catch (const InputError& e) {
      r.error = InputError(a.est + " vs " + a.ref + ": " + e.what());
    }
  }
  if (r.assoc) {
    r.ate = io::computeAte(*r.assoc, a.align);
    r.rpe_step = io::computeRpe(*r.assoc, 0);
    for (double d : a.rpe_dist) r.rpe.push_back(io::computeRpe(*r.assoc, d));
  }
  if (!rels.empty()) {
    try {
      r.rel = io::computeRelationsError(r.est, rels, a.assoc);
    } catch (const InputError& e) {
      const std::string rf = a.relations.empty() ? a.make_relations : a.relations;
      if (!r.error) r.error = InputError(a.est + " vs " + rf + ": " + e.what());
    }
  }
  if (!a.out_dir.empty() && r.computed()) writeOutputs(a, r);
  return r;
}

}  // namespace carenav::slam
