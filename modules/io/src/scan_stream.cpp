#include <carenav/io/scan_stream.h>

#include <algorithm>

namespace carenav::io {

ScanStream::ScanStream(const std::string& rawlog, std::string sensor_label)
    : reader_(rawlog), label_(std::move(sensor_label)) {}

bool ScanStream::next(ScanStep& step) {
  RawlogEntry e;
  while (reader_.next(e)) {
    if (e.odometry_increment) seen_odometry_ = true;
    if (e.odometry_increment)
      pending_odometry_ =
          pending_odometry_ ? *pending_odometry_ + *e.odometry_increment : *e.odometry_increment;
    mrpt::obs::CObservation2DRangeScan::Ptr scan;
    bool had_obs = false;
    for (const auto& o : e.observations()) {
      auto s = std::dynamic_pointer_cast<mrpt::obs::CObservation2DRangeScan>(o);
      if (!s) continue;
      had_obs = true;
      if (label_.empty() || s->sensorLabel == label_) {
        scan = s;
        break;
      }
      if (std::find(other_labels_.begin(), other_labels_.end(), s->sensorLabel) ==
          other_labels_.end())
        other_labels_.push_back(s->sensorLabel);
    }
    if (!scan) {
      if (e.kind != EntryKind::Actions && !had_obs) ++entries_without_scan_;
      continue;
    }
    step = ScanStep{};
    step.index = count_++;
    step.entry = e.index;
    step.time = scan->timestamp == INVALID_TIMESTAMP ? 0.0 : mrpt::Clock::toDouble(scan->timestamp);
    step.scan = scan;
    if (step.index == 0) {
      step.odometry = mrpt::poses::CPose2D();
      pending_odometry_.reset();
    } else {
      // Once the log has shown odometry, no increment between two scans
      // means the robot did not move.
      step.odometry = pending_odometry_;
      if (!step.odometry && seen_odometry_) step.odometry = mrpt::poses::CPose2D();
      pending_odometry_.reset();
    }
    return true;
  }
  return false;
}

}  // namespace carenav::io
