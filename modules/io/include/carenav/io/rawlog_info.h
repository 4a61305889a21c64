// What a rawlog holds: entries, time span, sensors, odometry path length
// (`carenav rawlog info`).
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace carenav::io {

struct SensorStats {
  std::string label;       ///< sensorLabel ("" when the log has none)
  std::string class_name;  ///< MRPT class, e.g. CObservation2DRangeScan
  uint64_t count = 0;
  double first_time = 0, last_time = 0;  ///< UNIX seconds, 0 if never timestamped
  /** Observations per second over the sensor's own time span; 0 when fewer
   *  than two timestamped observations. */
  double rate() const;
};

struct RawlogInfo {
  std::string path;
  uint64_t file_size = 0;
  bool gzipped = false;
  uint64_t entries = 0;  ///< top-level objects (MRPT: "Overall number of objects")
  uint64_t actions = 0, sensory_frames = 0, observations = 0, others = 0;
  uint64_t observations_total = 0;  ///< observations, including those inside frames
  std::string format;               ///< "actions-sensoryframes", "observations", "mixed", "empty"
  /** The log ends with an action that no sensory frame follows (MRPT's
   *  rawlog-edit --info leaves such an action out of its object count). */
  bool trailing_action = false;
  double first_time = 0, last_time = 0;  ///< UNIX seconds; 0 when nothing is timestamped
  uint64_t odometry_increments = 0;
  double odometry_path_m = 0;        ///< sum of the translations of all increments
  double odometry_turn_rad = 0;      ///< sum of |rotation| of all increments
  std::vector<SensorStats> sensors;  ///< by label, then class
  /** Set when reading stopped early: the reason (everything above counts
   *  the entries read before it). */
  std::optional<std::string> error;

  double duration() const { return last_time > first_time ? last_time - first_time : 0; }
  std::string toText() const;
  std::string toJson() const;
};

/** Reads the whole rawlog (streaming) and summarises it. A truncated or
 *  corrupt file does not throw: the summary of what was read is returned
 *  with `error` set. Missing or empty files throw InputError. */
RawlogInfo summarizeRawlog(const std::string& path, bool show_progress = true);

}  // namespace carenav::io
