// RunMetrics as JSON: the summary of a run, and the whole record passed from
// a suite's child process to its parent.
#include <carenav/common/json.h>
#include <carenav/navigation/scenario.h>

#include <cmath>
#include <limits>

namespace carenav::navigation {

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

// The summary's keys are those of toJson() (beside runScenario).
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
  read(j, "perception_ms_mean", m.perception_ms_mean, nan);
  read(j, "wall_seconds", m.wall_seconds, nan);
  read(j, "entered_forbidden", m.entered_forbidden);
  read(j, "outputs", m.outputs);
  return m;
}

}  // namespace carenav::navigation
