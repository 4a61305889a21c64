// RunMetrics as JSON: the summary of a run, and the whole record passed from
// a suite's child process to its parent.
#include <carenav/common/json.h>
#include <carenav/runtime/scenario.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>

namespace carenav::navigation {

namespace fs = std::filesystem;

namespace {

/** `j[key]` into `out` when present; null gives `if_null`. */
template <typename T>
void read(const Json& j, const char* key, T& out, T if_null = T{}) {
  const auto it = j.find(key);
  if (it == j.end()) return;
  if (it->is_null()) {
    out = if_null;
    return;
  }
  try {
    out = it->get<T>();
  } catch (const Json::exception& e) {
    throw InputError(std::string("run metrics: '") + key + "': " + e.what());
  }
}

}  // namespace

// The summary's keys are those of toJson() (below).
Json RunMetrics::toJsonValue(bool complete) const {
  Json j = parseJson(toJson(), "run metrics");
  if (complete) {
    j["min_clearance_m"] = std::isfinite(min_clearance_m) ? Json(min_clearance_m) : Json();
    j["entered_forbidden"] = entered_forbidden;
    j["outputs"] = outputs;
  }
  return j;
}

RunMetrics RunMetrics::fromJson(const Json& j) {
  if (!j.is_object()) throw InputError("run metrics: not a JSON object");
  const double nan = std::numeric_limits<double>::quiet_NaN();
  RunMetrics m;
  read(j, "scenario", m.scenario);
  read(j, "plugin", m.plugin);
  read(j, "goal_name", m.goal_name);
  read(j, "success", m.success);
  read(j, "outcome", m.outcome);
  read(j, "collisions", m.collisions);
  read(j, "min_clearance_m", m.min_clearance_m, std::numeric_limits<double>::infinity());
  read(j, "mean_clearance_m", m.mean_clearance_m, nan);
  read(j, "duration_s", m.duration_s, nan);
  read(j, "path_length_m", m.path_length_m, nan);
  read(j, "mean_speed_mps", m.mean_speed_mps, nan);
  read(j, "intent_fidelity", m.intent_fidelity, nan);
  read(j, "final_goal_error_m", m.final_goal_error_m, nan);
  read(j, "recoveries", m.recoveries);
  read(j, "recovery_cycles", m.recovery_cycles);
  read(j, "avoided_places", m.avoided_places);
  read(j, "legs_completed", m.legs_completed);
  read(j, "legs_failed", m.legs_failed);
  read(j, "legs_missed", m.legs_missed);
  read(j, "leg_miss_max_m", m.leg_miss_max_m, nan);
  read(j, "work_ms_p99", m.work_ms_p99, nan);
  read(j, "work_ms_max", m.work_ms_max, nan);
  read(j, "work_ms_p99_per_10min", m.work_ms_p99_windows);
  read(j, "rss_mb_per_minute", m.rss_mb);
  read(j, "left_map", m.left_map);
  read(j, "cycles", m.cycles);
  read(j, "stops", m.stops);
  read(j, "slowed", m.slowed);
  read(j, "cycle_ms_mean", m.cycle_ms_mean, nan);
  read(j, "cycle_ms_max", m.cycle_ms_max, nan);
  read(j, "depth_frames", m.depth_frames);
  read(j, "dead_reckoning_scans", m.dead_reckoning_scans);
  read(j, "perception_ms_mean", m.perception_ms_mean, nan);
  read(j, "wall_seconds", m.wall_seconds, nan);
  read(j, "entered_forbidden", m.entered_forbidden);
  read(j, "outputs", m.outputs);
  return m;
}

void RunMetrics::writeSummary(const std::string& out_dir, const std::string& png) {
  outputs.push_back(png);
  outputs.push_back((fs::path(out_dir) / "navlog.csv").string());
  const std::string js = (fs::path(out_dir) / "summary.json").string();
  std::ofstream(js) << toJson() << "\n";
  outputs.push_back(js);
}

void RunMetrics::failWith(const InputError& error) const {
  for (const auto& f : outputs) std::cerr << "[navigate] wrote " << f << "\n";
  throw error;
}

std::string RunMetrics::toJson() const {
  JsonWriter j;
  j.beginObject();
  j.key("scenario").value(scenario);
  j.key("plugin").value(plugin);
  if (!goal_name.empty()) j.key("goal_name").value(goal_name);
  j.key("success").value(success);
  j.key("outcome").value(outcome);
  j.key("collisions").value(static_cast<uint64_t>(collisions));
  j.key("min_clearance_m").value(std::isfinite(min_clearance_m) ? min_clearance_m : 0.0);
  j.key("mean_clearance_m").value(mean_clearance_m);
  j.key("duration_s").value(duration_s);
  j.key("path_length_m").value(path_length_m);
  j.key("mean_speed_mps").value(mean_speed_mps);
  if (std::isnan(intent_fidelity))
    j.key("intent_fidelity").null();
  else
    j.key("intent_fidelity").value(intent_fidelity);
  j.key("final_goal_error_m").value(final_goal_error_m);
  j.key("recoveries").value(static_cast<uint64_t>(recoveries));
  j.key("legs_completed").value(static_cast<uint64_t>(legs_completed));
  j.key("legs_failed").value(static_cast<uint64_t>(legs_failed));
  j.key("legs_missed").value(static_cast<uint64_t>(legs_missed));
  j.key("leg_miss_max_m").value(leg_miss_max_m);
  j.key("recovery_cycles").value(static_cast<uint64_t>(recovery_cycles));
  j.key("avoided_places").value(static_cast<uint64_t>(avoided_places));
  j.key("left_map").value(left_map);
  j.key("cycles").value(static_cast<uint64_t>(cycles));
  j.key("stops").value(static_cast<uint64_t>(stops));
  j.key("slowed").value(static_cast<uint64_t>(slowed));
  j.key("cycle_ms_mean").value(cycle_ms_mean);
  j.key("cycle_ms_max").value(cycle_ms_max);
  j.key("work_ms_p99").value(work_ms_p99);
  j.key("work_ms_max").value(work_ms_max);
  j.key("work_ms_p99_per_10min").beginArray();
  for (double v : work_ms_p99_windows) j.value(v);
  j.endArray();
  j.key("rss_mb_per_minute").beginArray();
  for (double v : rss_mb) j.value(v);
  j.endArray();
  j.key("depth_frames").value(static_cast<uint64_t>(depth_frames));
  j.key("dead_reckoning_scans").value(static_cast<uint64_t>(dead_reckoning_scans));
  j.key("perception_ms_mean").value(perception_ms_mean);
  j.key("wall_seconds").value(wall_seconds);
  j.endObject();
  return j.str();
}

}  // namespace carenav::navigation
