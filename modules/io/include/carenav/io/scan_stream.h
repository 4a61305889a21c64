// 2D scans and the odometry between them, pulled from a rawlog stream: what
// every SLAM back end consumes, whatever the rawlog's form.
#pragma once

#include <carenav/io/rawlog_reader.h>

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/poses/CPose2D.h>

#include <optional>
#include <string>

namespace carenav::io {

/** One scan and the robot motion since the previous scan. */
struct ScanStep {
  size_t index = 0;  ///< 0-based count of scans handed out
  size_t entry = 0;  ///< rawlog entry the scan came from
  double time = 0;   ///< UNIX seconds (0 when the scan has no timestamp)
  mrpt::obs::CObservation2DRangeScan::Ptr scan;
  /** Odometry accumulated since the previous step (identity before the first
   *  one); absent when the log has no odometry between the two scans. */
  std::optional<mrpt::poses::CPose2D> odometry;
};

/** Reads a rawlog and hands out the 2D scans of one sensor with the odometry
 *  between them. Both rawlog forms; odometry from actions or odometry
 *  observations (see RawlogReader). */
class ScanStream {
 public:
  /** `sensor_label` "" takes the first 2D scan of each entry. */
  ScanStream(const std::string& rawlog, std::string sensor_label);

  /** False at the end of the log. Throws RawlogError when the log is
   *  broken (the steps handed out before stay valid). */
  bool next(ScanStep& step);

  const RawlogReader& reader() const { return reader_; }
  size_t entriesWithoutScan() const { return entries_without_scan_; }
  /** Labels of the 2D scans seen but not used (another sensor). */
  const std::vector<std::string>& otherLabels() const { return other_labels_; }

 private:
  RawlogReader reader_;
  std::string label_;
  size_t count_ = 0;
  size_t entries_without_scan_ = 0;
  bool seen_odometry_ = false;
  std::optional<mrpt::poses::CPose2D> pending_odometry_;
  std::vector<std::string> other_labels_;
};

}  // namespace carenav::io
