#include <carenav/common/json.h>
#include <carenav/common/progress.h>
#include <carenav/io/rawlog_info.h>
#include <carenav/io/rawlog_reader.h>

#include <mrpt/system/datetime.h>

#include <cmath>
#include <cstdio>
#include <sstream>

namespace carenav::io {

double SensorStats::rate() const {
  if (count < 2 || last_time <= first_time) return 0;
  return (count - 1) / (last_time - first_time);
}

RawlogInfo summarizeRawlog(const std::string& path, bool show_progress) {
  RawlogReader reader(path);  // throws InputError for missing/empty files
  RawlogInfo info;
  info.path = path;
  info.file_size = reader.fileSize();
  info.gzipped = reader.gzipped();
  std::map<std::pair<std::string, std::string>, SensorStats> sensors;
  Progress progress("rawlog " + path, reader.fileSize());
  progress.setEnabled(show_progress && progress.enabled());

  auto stamp = [](mrpt::Clock::time_point t) {
    return t == INVALID_TIMESTAMP ? 0.0 : mrpt::Clock::toDouble(t);
  };
  auto widen = [](double& first, double& last, double t) {
    if (t <= 0) return;
    if (first == 0 || t < first) first = t;
    if (t > last) last = t;
  };
  RawlogEntry e;
  try {
    while (reader.next(e)) {
      ++info.entries;
      info.trailing_action = e.kind == EntryKind::Actions;
      switch (e.kind) {
        case EntryKind::Actions:
          ++info.actions;
          break;
        case EntryKind::SensoryFrame:
          ++info.sensory_frames;
          break;
        case EntryKind::Observation:
          ++info.observations;
          break;
        case EntryKind::Other:
          ++info.others;
          break;
      }
      if (e.actions)
        for (size_t i = 0; i < e.actions->size(); ++i)
          if (auto a = e.actions->get(i))
            widen(info.first_time, info.last_time, stamp(a->timestamp));
      for (const auto& o : e.observations()) {
        ++info.observations_total;
        const double t = stamp(o->timestamp);
        widen(info.first_time, info.last_time, t);
        auto& s = sensors[{o->sensorLabel, o->GetRuntimeClass()->className}];
        s.label = o->sensorLabel;
        s.class_name = o->GetRuntimeClass()->className;
        ++s.count;
        widen(s.first_time, s.last_time, t);
      }
      if (e.odometry_increment) {
        ++info.odometry_increments;
        info.odometry_path_m += e.odometry_increment->norm();
        info.odometry_turn_rad += std::abs(e.odometry_increment->phi());
      }
      progress.update(reader.filePosition(), info.entries);
    }
  } catch (const RawlogError& err) {
    if (info.entries == 0) throw;  // nothing of it was a rawlog
    info.error = err.what();
  }
  progress.finish();
  for (auto& [k, s] : sensors) info.sensors.push_back(s);
  if (info.entries == 0)
    info.format = "empty";
  else if (info.observations == 0 && (info.actions > 0 || info.sensory_frames > 0))
    info.format = "actions-sensoryframes";
  else if (info.actions == 0 && info.sensory_frames == 0)
    info.format = "observations";
  else
    info.format = "mixed";
  return info;
}

namespace {
std::string isoTime(double t) {
  if (t <= 0) return "-";
  return mrpt::system::dateTimeToString(mrpt::Clock::fromDouble(t)) + " UTC";
}
}  // namespace

std::string RawlogInfo::toText() const {
  std::ostringstream os;
  char buf[512];
  os << "file:               " << path << "\n";
  std::snprintf(buf, sizeof buf, "size:               %.1f KB%s\n", file_size / 1e3,
                gzipped ? " (gzip)" : "");
  os << buf;
  os << "format:             " << format << "\n";
  os << "entries:            " << entries << " (actions " << actions << ", sensory frames "
     << sensory_frames << ", observations " << observations << ", other " << others << ")\n";
  if (trailing_action)
    os << "                    the last entry is an action with no sensory frame after it\n";
  os << "observations total: " << observations_total << "\n";
  std::snprintf(buf, sizeof buf, "time span:          %.3f s, from %s to %s\n", duration(),
                isoTime(first_time).c_str(), isoTime(last_time).c_str());
  os << buf;
  std::snprintf(buf, sizeof buf,
                "odometry:           %llu increments, path %.3f m, turned %.1f deg\n",
                static_cast<unsigned long long>(odometry_increments), odometry_path_m,
                odometry_turn_rad * 180 / M_PI);
  os << buf;
  os << "sensors:\n";
  std::snprintf(buf, sizeof buf, "  %-20s %-34s %8s %10s %10s\n", "label", "class", "count",
                "rate [Hz]", "span [s]");
  os << buf;
  for (const auto& s : sensors) {
    std::snprintf(buf, sizeof buf, "  %-20s %-34s %8llu %10.3f %10.3f\n",
                  s.label.empty() ? "(none)" : s.label.c_str(), s.class_name.c_str(),
                  static_cast<unsigned long long>(s.count), s.rate(),
                  s.last_time > s.first_time ? s.last_time - s.first_time : 0.0);
    os << buf;
  }
  if (error) os << "INCOMPLETE: " << *error << "\n";
  return os.str();
}

std::string RawlogInfo::toJson() const {
  JsonWriter j;
  j.beginObject();
  j.key("file").value(path);
  j.key("file_size").value(file_size);
  j.key("gzipped").value(gzipped);
  j.key("format").value(format);
  j.key("entries").value(entries);
  j.key("actions").value(actions);
  j.key("sensory_frames").value(sensory_frames);
  j.key("observations").value(observations);
  j.key("other").value(others);
  j.key("observations_total").value(observations_total);
  j.key("trailing_action").value(trailing_action);
  j.key("first_time").value(first_time);
  j.key("last_time").value(last_time);
  j.key("duration_s").value(duration());
  j.key("odometry").beginObject();
  j.key("increments").value(odometry_increments);
  j.key("path_length_m").value(odometry_path_m);
  j.key("turned_rad").value(odometry_turn_rad);
  j.endObject();
  j.key("sensors").beginArray();
  for (const auto& s : sensors) {
    j.beginObject();
    j.key("label").value(s.label);
    j.key("class").value(s.class_name);
    j.key("count").value(s.count);
    j.key("rate_hz").value(s.rate());
    j.key("first_time").value(s.first_time);
    j.key("last_time").value(s.last_time);
    j.endObject();
  }
  j.endArray();
  j.key("complete").value(!error.has_value());
  if (error) j.key("error").value(*error);
  j.endObject();
  return j.str() + "\n";
}

}  // namespace carenav::io
