// CARMEN robot logs (the text ".log"/".clf" format of the Radish data sets)
// to an MRPT rawlog in the observation-only form, keeping the logs' own
// timestamps, plus the robot poses of the log as a TUM trajectory.
//
// Messages read (one per line; every data message ends with
// "ipc_timestamp ipc_hostname logger_timestamp"):
//   FLASER/RLASER num_readings r1..rn x y theta odom_x odom_y odom_theta  (old front/rear laser)
//   LASER3/LASER4 num_readings r1..rn                                     (old, no pose)
//   RAWLASERk laser_type start_angle field_of_view angular_resolution maximum_range accuracy
//             remission_mode num_readings r1..rn num_remissions rem1..remm
//   ROBOTLASERk <as RAWLASERk> laser_pose_x y theta robot_pose_x y theta laser_tv laser_rv
//             forward_safety_dist side_safety_dist turn_axis
//   ODOM x y theta tv rv accel
//   PARAM name value            (robot_front_laser_max, laser_front_laser_resolution, ...)
// '#' lines are comments; any other message type is skipped and counted.
#pragma once

#include <carenav/common/errors.h>
#include <carenav/io/odometry_noise.h>

#include <cstdint>
#include <map>
#include <optional>
#include <string>

namespace carenav::io {

/** Where the rawlog's CObservationOdometry ("ODOMETRY") readings come from. */
enum class CarmenOdometry {
  /** Laser when the log has a laser message that carries odometry (FLASER,
   *  RLASER, ROBOTLASERk), else ODOM; decided by a quick first pass. */
  Auto,
  /** The odometry fields of the laser messages: one reading per scan, at the
   *  scan's own timestamp (what MRPT's carmen2rawlog does). ODOM lines are
   *  skipped. */
  Laser,
  /** The ODOM lines (with their velocities); laser odometry fields unused. */
  Odom,
  /** No odometry in the rawlog. */
  None
};

/** Parses "auto", "laser", "odom", "none"; throws InputError otherwise. */
CarmenOdometry parseCarmenOdometry(const std::string& name);
std::string toString(CarmenOdometry o);

/** What `importCarmen` does. */
struct CarmenImportOptions {
  /** CARMEN log, plain text or gzip-compressed (found by content, not name). */
  std::string input;
  /** MRPT rawlog to write. Always gzip-compressed, whatever its name (MRPT's
   *  and carenav's readers both take it); written to `output + ".tmp"` and
   *  renamed when done. */
  std::string output;
  /** TUM trajectory of the robot poses in the log. Empty: `output` with its
   *  .rawlog/.gz extensions replaced by .tum (see defaultTumPath). */
  std::string tum;
  /** No TUM file at all. */
  bool write_tum = true;
  CarmenOdometry odometry = CarmenOdometry::Auto;
  /** Replace the odometry readings by noisy ones made from them (for a
   *  corrected log, whose odometry fields are the reference poses: the
   *  odometry a real base would have given). None: readings as logged. */
  std::optional<OdometryNoiseParams> odometry_noise;
  /** m. Readings at or beyond it are invalid. 0: from the log (the
   *  maximum_range field; PARAM robot_front_laser_max / robot_rear_laser_max
   *  for FLASER/RLASER), else 80 m, CARMEN's own default for old messages. */
  double max_range = 0;
  /** zlib level of the rawlog, 1 (fast) to 9 (small). */
  int compression = 1;
  /** Progress line on stderr (shown only when stderr is a terminal). */
  bool progress = false;
};

/** A scanner's no-return value found in a log's readings (old laser
 *  messages state no maximum range), and the limit taken from it. */
struct NoReturnLevel {
  double level = 0;    ///< m, the repeated value at the top of the readings
  double limit = 0;    ///< m, readings at or beyond it are invalid (no return)
  uint64_t piled = 0;  ///< readings of the log at or beyond `limit`
  /** m, PARAM robot_*_laser_max of the log when it states one (0: none):
   *  the range CARMEN's robot module used, not the scanner's. */
  double param_max = 0;
};

/** What `importCarmen` found and wrote. */
struct CarmenImportStats {
  uint64_t lines = 0;                     ///< lines read, blank and comment lines included
  uint64_t comments = 0;                  ///< '#' lines
  uint64_t params = 0;                    ///< PARAM lines
  std::map<std::string, uint64_t> scans;  ///< scans written, by message type
  uint64_t empty_scans = 0;               ///< laser messages with 0 readings (not written)
  /** Readings that are nan, inf or negative (kept as invalid beams), the
   *  scans that have any, and the line of the first. */
  uint64_t bad_readings = 0, scans_with_bad_readings = 0, first_bad_reading_line = 0;
  /** Old laser message types (FLASER, RLASER, LASERk) without a stated
   *  maximum range whose readings pile up at a no-return value: readings at
   *  or beyond its limit are written as invalid beams (see importCarmen). */
  std::map<std::string, NoReturnLevel> no_return;
  uint64_t odometry = 0;                                  ///< CObservationOdometry written
  CarmenOdometry odometry_source = CarmenOdometry::None;  ///< the source used (never Auto)
  /** The noise added to the odometry (CarmenImportOptions::odometry_noise). */
  std::optional<OdometryNoiseParams> odometry_noise;
  std::map<std::string, uint64_t> unknown;  ///< unknown message types, skipped
  /** Known messages left out by the chosen odometry source: ODOM lines when
   *  it is Laser or None. */
  std::map<std::string, uint64_t> unused;
  /** Lines skipped for a negative ipc_timestamp, by message type (real
   *  logs have a few; the rest of the log is converted). */
  std::map<std::string, uint64_t> negative_time;
  uint64_t observations = 0;  ///< objects in the rawlog
  /** Timestamps of the written observations, UNIX seconds, in file order
   *  (first/last) and extremes (min/max); 0 when nothing was written. */
  double first_time = 0, last_time = 0, min_time = 0, max_time = 0;
  /** Scans whose timestamp is below the previous scan's (loggers do this),
   *  and scans whose timestamp equals it (e.g. CSAIL's log stores times
   *  with 6 significant digits, so whole seconds collapse). */
  uint64_t scans_time_backwards = 0, scans_time_repeated = 0;
  uint64_t tum_poses = 0;   ///< poses written to the TUM file
  std::string output, tum;  ///< files written ("" for the TUM when none)

  uint64_t totalScans() const;
  uint64_t totalUnknown() const;
  /** The summary: scans, odometry, time span, files written. */
  std::string toText() const;
  std::string toJson() const;
  /** What was skipped and odd timestamps, one line each ("" when nothing):
   *  the CLI prints it on stderr. */
  std::string notesText() const;
};

/** A malformed line stopped the import after some of the log was converted;
 *  the files named in `stats` hold everything before that line. */
class CarmenImportError : public InputError {
 public:
  CarmenImportError(const std::string& what, CarmenImportStats stats);
  CarmenImportStats stats;
};

/** X.rawlog -> X.tum, X.rawlog.gz -> X.tum, X.gz -> X.tum, X -> X.tum. */
std::string defaultTumPath(const std::string& rawlog_path);

/** Converts a CARMEN log, streaming line by line in constant memory (the TUM
 *  trajectory, one pose of 32 bytes per laser message, is kept until the end).
 *
 *  Scans: each laser message -> CObservation2DRangeScan labelled with its
 *  message type (FLASER, RLASER, LASER3, RAWLASER1, ROBOTLASER1, ...), beam i
 *  at start_angle + i * angular_resolution (counter-clockwise,
 *  rightToLeft = true), the scan's centre folded into sensorPose's yaw since
 *  MRPT scans are symmetric about the sensor's x axis. Old messages (FLASER,
 *  RLASER, LASERk) start at -90 deg with the resolution CARMEN's own readlog
 *  infers from the beam count: 180 or 181 beams 1 deg, 360 or 361 beams
 *  0.5 deg, 400 or 401 beams 0.25 deg; other counts use PARAM
 *  laser_front_laser_resolution / laser_rear_laser_resolution (deg) when the
 *  log has it, else span 180 deg. Sensor pose on the robot: FLASER at robot_frontlaser_offset
 * ahead, RLASER at robot_rearlaser_offset behind facing backwards, ROBOTLASERk laser_pose relative
 * to robot_pose, RAWLASERk and LASERk at the origin (their messages do not say). Readings <= 0 or
 * >= the maximum range are invalid. Old messages state no maximum range of the scanner: unless
 * `max_range` gives one, a first pass over the log looks for the scanner's no-return value
 * (readings piled up at the top of the log's ranges, NoReturnFinder); when found, readings
 * within 3 % below it and beyond are invalid (stats.no_return), else PARAM robot_*_laser_max
 * (the range CARMEN's robot module used), else 80 m.
 *
 *  Odometry: see CarmenOdometry; CObservationOdometry labelled "ODOMETRY",
 *  velocities set where the message has them (ODOM tv/rv, ROBOTLASERk
 *  laser_tv/laser_rv). Written before the scan of the same message.
 *
 *  Timestamps: the ipc_timestamp field, exactly to 100 ns when written as a
 *  plain decimal (no rounding through a double), as UNIX seconds. A line
 *  with a negative ipc_timestamp (a logger artefact of some real logs) is
 *  checked like any other, then skipped and counted in `negative_time`.
 *
 *  TUM: the robot pose of each FLASER (x y theta, less the front laser
 *  offset) and ROBOTLASERk (robot_pose) message at its timestamp, sorted by
 *  time (loggers write a few scans out of order; TUM readers need increasing
 *  times). RLASER, RAWLASERk and LASERk messages add none. Not written when
 *  the log has no such message.
 *
 *  Bad input: throws InputError "FILE:LINE: TYPE: what is wrong". A missing,
 *  unreadable or empty input, or one with nothing to convert, writes nothing.
 *  A PARAM value carenav uses (the ones above) must be a number.
 *  A malformed line (too few or too many fields, a field that is not a
 *  number, a count that does not match the fields, a negative count, a line
 *  cut short at the end of the file, corrupt or truncated gzip data) stops
 *  the import: everything converted from the lines before it is written
 *  (rawlog and TUM), then CarmenImportError says so and carries the stats.
 *  A last line without its end of line is fine when it is complete. */
CarmenImportStats importCarmen(const CarmenImportOptions& options);

}  // namespace carenav::io
