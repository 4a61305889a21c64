#include <carenav/common/json.h>
#include <carenav/io/evaluation.h>
#include <carenav/io/map_io.h>
#include <carenav/io/map_render.h>
#include <carenav/io/scan_stream.h>
#include <carenav/localization/localize_job.h>

#include <unistd.h>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

namespace carenav::localization {

namespace fs = std::filesystem;

InitialPose parseInitialPose(const std::string& text) {
  std::vector<double> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    try {
      v.push_back(parseReal(item));
    } catch (const std::exception&) {
      throw InputError("--init '" + text + "': '" + item + "' is not a number");
    }
  }
  if (v.size() != 3 && v.size() != 6)
    throw InputError("--init '" + text + "': expected x,y,deg or x,y,deg,sx,sy,sdeg");
  InitialPose p;
  p.x = v[0];
  p.y = v[1];
  p.yaw = mrpt::DEG2RAD(v[2]);
  if (v.size() == 6) {
    if (v[3] <= 0 || v[4] <= 0 || v[5] <= 0)
      throw InputError("--init '" + text + "': the standard deviations must be positive");
    p.std_x = v[3];
    p.std_y = v[4];
    p.std_yaw = mrpt::DEG2RAD(v[5]);
  }
  return p;
}

namespace {

void writeCovCsv(const std::string& path, const io::Trajectory2D& track,
                 const std::vector<mrpt::math::CMatrixDouble33>& covs) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream f(tmp);
    if (!f) throw std::runtime_error(path + ": cannot write");
    f << "t,x,y,yaw,var_x,cov_xy,cov_xyaw,var_y,cov_yyaw,var_yaw\n";
    char buf[512];
    for (size_t i = 0; i < track.size(); ++i) {
      const auto& p = track[i];
      const auto& c = covs[i];
      std::snprintf(buf, sizeof buf, "%.6f,%.6f,%.6f,%.6f,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g\n", p.t,
                    p.x, p.y, p.yaw, c(0, 0), c(0, 1), c(0, 2), c(1, 1), c(1, 2), c(2, 2));
      f << buf;
    }
    if (!f) throw std::runtime_error(path + ": cannot write");
  }
  fs::rename(tmp, path);
}

io::Overlay overlayOf(const io::Trajectory2D& traj, io::Rgb colour, bool markers) {
  io::Overlay o;
  for (const auto& p : traj) o.points.push_back({p.x, p.y});
  o.colour = colour;
  o.start_end_markers = markers;
  return o;
}

}  // namespace

LocalizeJobResult runLocalize(const LocalizeJobOptions& o) {
  if (int(o.init.has_value()) + int(o.global) + int(o.region.has_value()) != 1)
    throw InputError(
        "give exactly one of --init x,y,deg[,sx,sy,sdeg], --global and --in-room NAME");
  io::MapLoadOptions mo;
  mo.simplemap_resolution = o.map_resolution;
  const auto grid = io::loadGridMap(o.map, mo);
  io::Trajectory2D ref;
  if (!o.ref.empty()) ref = io::readTum(o.ref);
  io::ScanStream stream(o.rawlog, o.params.sensor);  // throws for missing/empty rawlogs

  Localizer loc(grid, o.params);
  if (o.init)
    loc.initPose(mrpt::poses::CPose2D(o.init->x, o.init->y, o.init->yaw), o.init->std_x,
                 o.init->std_y, o.init->std_yaw);
  else if (o.region)
    loc.initInRegion(o.region->inside, "room '" + o.region->name + "'");
  else
    loc.initGlobal();
  if (!o.out_dir.empty()) fs::create_directories(o.out_dir);

  LocalizeJobResult r;
  const auto t0 = std::chrono::steady_clock::now();
  const bool tty = o.progress && isatty(fileno(stderr));
  io::ScanStep s;
  std::optional<double> t_first;
  std::optional<double> t_prev;
  size_t repeats_before_convergence = 0;
  while (true) {
    try {
      if (!stream.next(s)) break;
    } catch (const io::RawlogError& e) {
      r.rawlog_error = e.what();
      break;
    }
    // Logs without timestamps are stamped with the scan index (1 s apart).
    double t = s.time;
    if (t == 0 || r.index_times) {
      r.index_times = true;
      t = static_cast<double>(s.index);
    }
    if (!t_first) t_first = t;
    if (t_prev && t == *t_prev) ++r.repeated_times;
    t_prev = t;
    const StepResult sr = loc.step(s.odometry.value_or(mrpt::poses::CPose2D()), s.scan, t);
    ++r.scans;
    r.dead_reckoning_scans += sr.dead_reckoning;
    if (!r.convergence_updates && loc.convergenceTime()) {
      r.convergence_updates = loc.updates();
      r.convergence_scans = r.scans;
      repeats_before_convergence = r.repeated_times;
    }
    r.track.push_back({t, sr.pose.x(), sr.pose.y(), sr.pose.phi()});
    r.covs.push_back(sr.cov);
    if (sr.updated)
      r.records.push_back({t, sr.particles, sr.spread, sr.likelihood_ratio, sr.seconds, sr.injected,
                           sr.beta, sr.resampled, sr.agreement, sr.challenger_spread});
    if (tty && r.scans % 10 == 0)
      std::cerr << "\r[localize] scan " << r.scans << ", " << sr.particles << " particles, spread "
                << sr.spread << " m   " << std::flush;
  }
  if (tty) std::cerr << "\n";
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (r.scans == 0) {
    if (r.rawlog_error) throw InputError(*r.rawlog_error);
    throw InputError(
        o.rawlog + ": no 2D laser scan" +
        (o.params.sensor.empty() ? std::string() : " with sensor label '" + o.params.sensor + "'") +
        " to localise with");
  }
  r.updates = loc.updates();
  r.injections = loc.injections();
  r.challenges = loc.challenges();
  r.challenges_won = loc.challengesWon();
  r.rotate_requests = loc.rotateRequests();
  r.rotate_enabled = o.params.rotate_request;
  r.events = loc.events();
  for (auto& e : r.events) e.t -= *t_first;
  for (auto& q : r.rotate_requests) {
    q.t_start -= *t_first;
    if (q.t_end) *q.t_end -= *t_first;
  }
  if (loc.convergenceTime() && repeats_before_convergence == 0)
    r.convergence_time = *loc.convergenceTime() - *t_first;
  r.converged_at_end = loc.converged();
  r.final_spread = loc.spread();
  if (o.out_dir.empty()) return r;

  io::RenderOptions ro;
  ro.crop_to_known = true;
  ro.title =
      "carenav localize: estimate (red)" + std::string(ref.empty() ? "" : ", reference (blue)");
  if (!ref.empty()) {
    const auto a = io::associate(r.track, ref);
    const auto ate = io::computeAte(a, /*align=*/false);
    r.ate_rmse = ate.translation.rmse;
    r.ate_max = ate.translation.max;
    r.ate_pairs = a.size();
    ro.overlays.push_back(overlayOf(ref, {40, 80, 220}, false));
  }
  ro.overlays.push_back(overlayOf(r.track, {220, 30, 30}, true));

  const std::string tum = (fs::path(o.out_dir) / "track.tum").string();
  const std::string csv = (fs::path(o.out_dir) / "track_cov.csv").string();
  const std::string png = (fs::path(o.out_dir) / "map.png").string();
  const std::string json = (fs::path(o.out_dir) / "summary.json").string();
  io::writeTum(tum, r.track);
  writeCovCsv(csv, r.track, r.covs);
  io::renderGridMapPng(grid, png, ro);
  r.outputs = {tum, csv, png, json};
  {
    std::ofstream f(json);
    f << r.summaryJson(o) << "\n";
    if (!f) throw std::runtime_error(json + ": cannot write");
  }
  return r;
}

std::string LocalizeJobResult::summaryJson(const LocalizeJobOptions& o) const {
  JsonWriter j;
  j.beginObject();
  j.key("map").value(o.map);
  j.key("rawlog").value(o.rawlog);
  j.key("start").value(o.global ? "global" : o.region ? "room" : "pose");
  if (o.region) j.key("room").value(o.region->name);
  if (o.init) {
    j.key("init").beginObject();
    j.key("x").value(o.init->x).key("y").value(o.init->y);
    j.key("yaw_deg").value(mrpt::RAD2DEG(o.init->yaw));
    j.key("std_x").value(o.init->std_x).key("std_y").value(o.init->std_y);
    j.key("std_yaw_deg").value(mrpt::RAD2DEG(o.init->std_yaw));
    j.endObject();
  }
  j.key("scans").value(static_cast<uint64_t>(scans));
  j.key("updates").value(static_cast<uint64_t>(updates));
  j.key("dead_reckoning_scans").value(static_cast<uint64_t>(dead_reckoning_scans));
  j.key("time_source").value(index_times ? "scan index" : "rawlog timestamps");
  j.key("repeated_times").value(static_cast<uint64_t>(repeated_times));
  j.key("converged").value(convergence_updates.has_value());
  j.key("convergence_time");
  if (convergence_time)
    j.value(*convergence_time);
  else
    j.null();
  j.key("convergence_updates");
  if (convergence_updates)
    j.value(static_cast<uint64_t>(*convergence_updates));
  else
    j.null();
  j.key("convergence_scans");
  if (convergence_scans)
    j.value(static_cast<uint64_t>(*convergence_scans));
  else
    j.null();
  j.key("converged_at_end").value(converged_at_end);
  j.key("converged_spread").value(o.params.converged_spread);
  if (!track.empty()) {
    const auto& f = track.back();
    j.key("final_pose").beginObject();
    j.key("t").value(f.t).key("x").value(f.x).key("y").value(f.y);
    j.key("yaw_deg").value(mrpt::RAD2DEG(f.yaw));
    j.key("std_x").value(std::sqrt(covs.back()(0, 0)));
    j.key("std_y").value(std::sqrt(covs.back()(1, 1)));
    j.key("std_yaw_deg").value(mrpt::RAD2DEG(std::sqrt(covs.back()(2, 2))));
    j.endObject();
  }
  j.key("losses").value(
      static_cast<uint64_t>(std::count_if(events.begin(), events.end(), [](const auto& e) {
        return e.kind == LocalizationEvent::Kind::Loss;
      })));
  j.key("injections").value(static_cast<uint64_t>(injections));
  j.key("challenges").value(static_cast<uint64_t>(challenges));
  j.key("challenges_won").value(static_cast<uint64_t>(challenges_won));
  j.key("events").beginArray();
  for (const auto& e : events) {
    j.beginObject();
    j.key("type").value(e.name()).key("t").value(e.t).key("spread").value(e.spread);
    j.endObject();
  }
  j.endArray();
  // rotate-in-place requests to the navigation layer (times relative to the first scan)
  j.key("rotate_in_place").beginObject();
  j.key("enabled").value(rotate_enabled);
  j.key("requests").value(static_cast<uint64_t>(rotate_requests.size()));
  j.key("list").beginArray();
  for (const auto& q : rotate_requests) {
    j.beginObject();
    j.key("t").value(q.t_start);
    j.key("end_t");
    if (q.t_end)
      j.value(*q.t_end);
    else
      j.null();
    j.key("outcome").value(!q.t_end ? "open" : q.relocalised ? "converged" : "turned");
    j.endObject();
  }
  j.endArray();
  j.endObject();
  double total = 0, worst = 0;
  for (const auto& rec : records) {
    total += rec.seconds;
    worst = std::max(worst, rec.seconds);
  }
  j.key("wall_seconds").value(seconds);
  j.key("update_ms_mean").value(records.empty() ? 0.0 : 1000 * total / records.size());
  j.key("update_ms_max").value(1000 * worst);
  if (ate_rmse) {
    j.key("ate").beginObject();
    j.key("aligned").value(false);
    j.key("pairs").value(static_cast<uint64_t>(ate_pairs));
    j.key("rmse").value(*ate_rmse).key("max").value(*ate_max);
    j.endObject();
  }
  if (rawlog_error) j.key("rawlog_error").value(*rawlog_error);
  j.key("updates_over_time").beginArray();
  for (const auto& rec : records) {
    j.beginObject();
    j.key("t").value(rec.t).key("particles").value(static_cast<uint64_t>(rec.particles));
    j.key("spread").value(rec.spread).key("likelihood_ratio").value(rec.likelihood_ratio);
    j.key("injected").value(static_cast<uint64_t>(rec.injected));
    j.key("beta").value(rec.beta).key("resampled").value(rec.resampled);
    j.key("agreement").value(rec.agreement);
    j.key("challenger_spread").value(rec.challenger_spread);
    j.key("ms").value(1000 * rec.seconds);
    j.endObject();
  }
  j.endArray();
  j.key("outputs").beginArray();
  for (const auto& f : outputs) j.value(f);
  j.endArray();
  j.endObject();
  return j.str();
}

}  // namespace carenav::localization
