#include <carenav/common/errors.h>
#include <carenav/common/json.h>
#include <carenav/common/progress.h>
#include <carenav/common/text.h>
#include <carenav/io/carmen.h>
#include <carenav/io/trajectory.h>

#include "gz_input.h"
#include "no_return_level.h"

#include <mrpt/core/Clock.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt/serialization/CArchive.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string_view>
#include <vector>

namespace carenav::io {

namespace fs = std::filesystem;
using mrpt::poses::CPose2D;

namespace {

constexpr double kPi = M_PI;
constexpr double kDefaultMaxRange = 80.0;    // m: CARMEN's readlog for old messages
constexpr double kDefaultAccuracy = 0.01;    // m: idem
constexpr size_t kMaxLineBytes = 64u << 20;  // far above any laser line; stops binary junk
// Bounds of what a robot log can hold; a value beyond them is corrupt data
// (1e300, a wrapped integer), refused with the line named.
constexpr double kMaxCoordinate = 1e7;  // m: beyond 10 000 km (UTM coordinates are within it)
constexpr double kMaxAngle = 1e6;       // rad: unwrapped odometry headings stay far below
constexpr double kMaxSpeed = 1e3;       // m/s, rad/s, m/s^2
constexpr double kMaxRangeBound = 1e6;  // m: laser maximum range, accuracy, mount offsets
constexpr double kMaxTime = 1e10;       // s since 1970: year 2286

/** One malformed line: the full message, "FILE:LINE: TYPE: what". */
class BadLine : public std::runtime_error {
 public:
  BadLine(const std::string& what, uint64_t lines_before)
      : std::runtime_error(what), lines_before(lines_before) {}
  uint64_t lines_before;  ///< lines read in full before the bad one
};

// ---------------------------------------------------------------------------
// Input: lines of a plain or gzip file, read in chunks (constant memory).

class LineSource {
 public:
  explicit LineSource(const std::string& path) : path_(path) {
    std::error_code ec;
    if (!fs::exists(path, ec)) throw InputError(path + ": CARMEN log not found (no such file)");
    if (fs::is_directory(path, ec)) throw InputError(path + ": is a directory, not a CARMEN log");
    file_size_ = fs::file_size(path, ec);
    if (ec) throw InputError(path + ": cannot read the file size: " + ec.message());
    if (file_size_ == 0) throw InputError(path + ": empty file (0 bytes), not a CARMEN log");
    {
      std::ifstream f(path, std::ios::binary);
      if (!f) throw InputError(path + ": cannot open the CARMEN log for reading");
      unsigned char head[2] = {0, 0};
      f.read(reinterpret_cast<char*>(head), 2);
      gzipped_ = f.gcount() == 2 && head[0] == 0x1f && head[1] == 0x8b;
      if (gzipped_ && file_size_ >= 18) {
        // gzip trailer: CRC32 then ISIZE, the uncompressed size modulo 2^32.
        unsigned char t[4];
        f.seekg(-4, std::ios::end);
        f.read(reinterpret_cast<char*>(t), 4);
        if (f.gcount() == 4)
          trailer_size_ =
              uint32_t(t[0]) | uint32_t(t[1]) << 8 | uint32_t(t[2]) << 16 | uint32_t(t[3]) << 24;
      }
    }
    std::string err;
    if (!in_.open(path, err)) throw InputError(path + ": cannot open the CARMEN log: " + err);
    buf_.resize(1 << 16);
  }

  /** Next line without its end of line. False at the end of the data.
   *  `complete` is false for a last line the file ends in without '\n'.
   *  Throws BadLine for corrupt compressed data or a line with NUL bytes. */
  bool next(std::string& line, bool& complete) {
    line.clear();
    for (;;) {
      if (pos_ == end_) {
        if (eof_ || !fill()) {
          if (line.empty()) return false;
          ++line_no_;
          complete = false;
          return finish(line);
        }
      }
      const char* b = buf_.data() + pos_;
      const void* nl = std::memchr(b, '\n', end_ - pos_);
      const size_t take = nl ? static_cast<const char*>(nl) - b : end_ - pos_;
      line.append(b, take);
      pos_ += take;
      if (line.size() > kMaxLineBytes)
        throw BadLine(where(line_no_ + 1) + "a line longer than 64 MiB: not a CARMEN text log",
                      line_no_);
      if (nl) {
        ++pos_;
        ++line_no_;
        complete = true;
        return finish(line);
      }
    }
  }

  /** After the last line: a gzip stream shorter than its trailer says was cut. */
  void checkComplete() const {
    if (!gzipped_ || !trailer_size_) return;
    if (static_cast<uint32_t>(bytes_) != *trailer_size_)
      throw BadLine(path_ + ": the gzip data ends early (truncated .gz: " + std::to_string(bytes_) +
                        " bytes decompressed after line " + std::to_string(line_no_) +
                        ", the gzip trailer expects " + std::to_string(*trailer_size_) +
                        " modulo 2^32)",
                    line_no_);
  }

  uint64_t lineNumber() const { return line_no_; }
  uint64_t fileSize() const { return file_size_; }
  /** Bytes of the file read so far (compressed bytes for a .gz): comparable
   *  with fileSize(), for progress. */
  uint64_t filePosition() { return std::min(in_.filePosition(), file_size_); }
  bool gzipped() const { return gzipped_; }

 private:
  std::string where(uint64_t line) const { return path_ + ":" + std::to_string(line) + ": "; }

  bool fill() {
    const long long got = in_.read(buf_.data(), buf_.size());
    if (got < 0)
      throw BadLine(where(line_no_ + 1) +
                        "corrupt compressed data (not a valid gzip stream) after " +
                        std::to_string(bytes_) + " decompressed bytes",
                    line_no_);
    const size_t n = static_cast<size_t>(got);
    pos_ = 0;
    end_ = n;
    bytes_ += n;
    if (n == 0) eof_ = true;
    return n > 0;
  }

  bool finish(std::string& line) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find('\0') != std::string::npos)
      throw BadLine(where(line_no_) + "binary data (a NUL byte): not a CARMEN text log",
                    line_no_ - 1);
    return true;
  }

  std::string path_;
  uint64_t file_size_ = 0;
  bool gzipped_ = false;
  std::optional<uint32_t> trailer_size_;
  GzInput in_;
  std::vector<char> buf_;
  size_t pos_ = 0, end_ = 0;
  bool eof_ = false;
  uint64_t bytes_ = 0;
  uint64_t line_no_ = 0;
};

void splitFields(const std::string& line, std::vector<std::string_view>& out) {
  out.clear();
  const char* s = line.data();
  const size_t n = line.size();
  size_t i = 0;
  auto space = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; };
  while (i < n) {
    while (i < n && space(s[i])) ++i;
    const size_t b = i;
    while (i < n && !space(s[i])) ++i;
    if (i > b) out.emplace_back(s + b, i - b);
  }
}

bool isLaserWithOdometry(std::string_view t) {
  return t == "FLASER" || t == "RLASER" ||
         (t.size() > 10 && t.substr(0, 10) == "ROBOTLASER" &&
          std::all_of(t.begin() + 10, t.end(), [](char c) { return c >= '0' && c <= '9'; }));
}

bool hasDigitSuffix(std::string_view t, std::string_view prefix) {
  return t.size() > prefix.size() && t.substr(0, prefix.size()) == prefix &&
         t.size() <= prefix.size() + 2 &&
         std::all_of(t.begin() + prefix.size(), t.end(),
                     [](char c) { return c >= '0' && c <= '9'; });
}

std::string printable(std::string_view t) {
  std::string s(t.substr(0, 40));
  for (auto& c : s)
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = '?';
  return s;
}

std::string fmtLimit(double v) { return formatGeneral(v); }

// ---------------------------------------------------------------------------
// Field parsing with messages that name the file, line, message and field.

class Fields {
 public:
  Fields(const std::string& path, uint64_t line, bool complete,
         const std::vector<std::string_view>& f)
      : path_(path), line_(line), complete_(complete), f_(f) {}

  size_t size() const { return f_.size(); }
  std::string_view operator[](size_t i) const { return f_[i]; }
  std::string type() const { return printable(f_[0]); }

  [[noreturn]] void fail(const std::string& what) const {
    std::string msg = path_ + ":" + std::to_string(line_) + ": " + type() + ": ";
    if (!complete_) msg += "the file ends in the middle of this line (truncated log): ";
    throw BadLine(msg + what, line_ - 1);
  }

  /** At least `n` fields, or a message saying which one is missing. */
  void need(size_t n, const std::string& field) const {
    if (f_.size() < n)
      fail("too few fields: " + std::to_string(f_.size()) + ", no " + field + " (field " +
           std::to_string(n - 1) + ")");
  }

  void exact(size_t n, const std::string& layout) const {
    if (f_.size() != n)
      fail("expected " + std::to_string(n) + " fields (" + layout + "), found " +
           std::to_string(f_.size()));
  }

  /** A number, maybe inf or nan (used for range readings). */
  double anyNumber(size_t i, const std::string& name) const {
    std::string_view s = f_[i];
    if (!s.empty() && s[0] == '+') s.remove_prefix(1);
    double v = 0;
    const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
    if (r.ec == std::errc::result_out_of_range) return HUGE_VAL;  // 1e999: no return
    if (r.ec != std::errc() || r.ptr != s.data() + s.size() || s.empty())
      fail(name + " is not a number: '" + printable(f_[i]) + "' (field " + std::to_string(i) + ")");
    return v;
  }

  double real(size_t i, const std::string& name) const {
    const double v = anyNumber(i, name);
    if (!std::isfinite(v))
      fail(name + " is not a finite number: '" + printable(f_[i]) + "' (field " +
           std::to_string(i) + ")");
    return v;
  }

  /** A finite number within +-limit (the unit names it in the message). */
  double bounded(size_t i, const std::string& name, double limit, const char* unit) const {
    const double v = real(i, name);
    if (std::abs(v) > limit) {
      const std::string u = *unit ? std::string(" ") + unit : std::string();
      fail(name + " is " + printable(f_[i]) + u + ", beyond +-" + fmtLimit(limit) + u +
           ": not a value a robot log holds (field " + std::to_string(i) + ")");
    }
    return v;
  }
  double coordinate(size_t i, const std::string& name) const {
    return bounded(i, name, kMaxCoordinate, "m");
  }
  double angle(size_t i, const std::string& name) const {
    return bounded(i, name, kMaxAngle, "rad");
  }
  double speed(size_t i, const std::string& name) const {
    return bounded(i, name, kMaxSpeed, "per s");
  }

  /** A non-negative integer count. */
  size_t count(size_t i, const std::string& name) const {
    const std::string_view s = f_[i];
    long long v = 0;
    const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
    if (r.ec != std::errc() || r.ptr != s.data() + s.size())
      fail(name + " is not an integer: '" + printable(s) + "' (field " + std::to_string(i) + ")");
    if (v < 0)
      fail(name + " is negative: " + std::to_string(v) + " (field " + std::to_string(i) + ")");
    return static_cast<size_t>(v);
  }

  /** The ipc_timestamp, third field from the end: UNIX seconds. Plain
   *  decimals convert exactly to MRPT's 100 ns ticks; the double in `secs`
   *  is for the TUM file and the statistics. */
  /** Empty for a negative ipc_timestamp: real logs have a few (acapulco,
   *  infinite-corridor, freiburg-campus of Radish), the caller skips the line. */
  std::optional<mrpt::Clock::time_point> timestamp(double& secs) const {
    const size_t i = f_.size() - 3;
    secs = bounded(i, "ipc_timestamp", kMaxTime, "s");
    (void)bounded(f_.size() - 1, "logger_timestamp", kMaxTime, "s");  // the line must end so
    if (secs < 0) return std::nullopt;
    static const mrpt::Clock::time_point kUnixEpoch = mrpt::Clock::fromDouble(0);
    std::string_view s = f_[i];
    if (!s.empty() && s[0] == '+') s.remove_prefix(1);
    const size_t dot = s.find('.');
    const std::string_view ip = s.substr(0, dot);
    const std::string_view fp =
        dot == std::string_view::npos ? std::string_view() : s.substr(dot + 1);
    auto digits = [](std::string_view d) {
      return std::all_of(d.begin(), d.end(), [](char c) { return c >= '0' && c <= '9'; });
    };
    if (!ip.empty() && ip.size() <= 12 && digits(ip) && digits(fp)) {
      int64_t ticks = 0;
      for (char c : ip) ticks = ticks * 10 + (c - '0');
      for (size_t k = 0; k < 7; ++k) ticks = ticks * 10 + (k < fp.size() ? fp[k] - '0' : 0);
      if (fp.size() > 7 && fp[7] >= '5') ++ticks;  // round to the nearest 100 ns
      return kUnixEpoch + mrpt::Clock::duration(ticks);
    }
    return mrpt::Clock::fromDouble(secs);  // exponent form, e.g. 1.13487e+09
  }

 private:
  const std::string& path_;
  uint64_t line_;
  bool complete_;
  const std::vector<std::string_view>& f_;
};

/** Where the beams of a scan point: beam i at start + i * increment. */
struct ScanGeometry {
  double start = -kPi / 2, increment = kPi / 180;
  double max_range = kDefaultMaxRange, accuracy = kDefaultAccuracy;
};

/** CARMEN's readlog rule for old messages (FLASER, RLASER, LASERk) that do
 *  not state their resolution: a SICK's beam count gives it away. */
double oldLaserIncrement(size_t n, double param_resolution_deg) {
  if (n == 180 || n == 181) return kPi / 180;
  if (n == 360 || n == 361) return kPi / 360;
  if (n == 400 || n == 401) return kPi / 720;
  if (param_resolution_deg > 0) return param_resolution_deg * kPi / 180;
  return n > 1 ? kPi / static_cast<double>(n - 1) : 0;
}

/** Values of PARAM lines that shape later old-format messages. */
struct LogParams {
  double front_max = 0, rear_max = 0;                // m, 0 = not given
  double front_resolution = 0, rear_resolution = 0;  // deg, 0 = not given
  double front_offset = 0, rear_offset = 0;          // m
};

void writeObject(mrpt::io::CFileGZOutputStream& out, const mrpt::serialization::CSerializable& o) {
  auto arch = mrpt::serialization::archiveFrom(out);
  arch << o;
}

std::string fmtTime(double t) { return formatFixed(t, 6); }

std::string fmtNumber(double v, int decimals) { return formatFixed(v, decimals); }

std::string joinCounts(const std::map<std::string, uint64_t>& m) {
  std::string s;
  for (const auto& [k, v] : m) s += (s.empty() ? "" : ", ") + k + " " + std::to_string(v);
  return s;
}

/** The first pass of CarmenOdometry::Auto: only the message names. */
CarmenOdometry chooseOdometry(const std::string& path) {
  bool odom = false;
  try {
    LineSource src(path);
    std::string line;
    bool complete = true;
    while (src.next(line, complete)) {
      const auto b = line.find_first_not_of(" \t");
      if (b == std::string::npos) continue;
      const auto e = line.find_first_of(" \t", b);
      const std::string_view t =
          std::string_view(line).substr(b, e == std::string::npos ? e : e - b);
      if (isLaserWithOdometry(t)) return CarmenOdometry::Laser;
      if (t == "ODOM") odom = true;
    }
  } catch (const std::exception&) {
    // The conversion pass reports what is wrong, at its line.
  }
  return odom ? CarmenOdometry::Odom : CarmenOdometry::Laser;
}

bool isOldLaser(std::string_view t) {
  return t == "FLASER" || t == "RLASER" || hasDigitSuffix(t, "LASER");
}

/** Readings of one old laser line into its type's finder (malformed lines
 *  are skipped: the conversion pass reports them at their line). */
void addOldLaserReadings(const std::vector<std::string_view>& tok,
                         std::map<std::string, NoReturnFinder>& finders) {
  size_t n = 0;
  if (tok.size() < 2 ||
      std::from_chars(tok[1].data(), tok[1].data() + tok[1].size(), n).ec != std::errc() ||
      n > tok.size() - 2)
    return;
  auto it = finders.try_emplace(std::string(tok[0]), kDefaultMaxRange).first;
  for (size_t i = 0; i < n; ++i) {
    double r = 0;
    const std::string_view v = tok[2 + i];
    if (std::from_chars(v.data(), v.data() + v.size(), r).ec == std::errc()) it->second.add(r);
  }
}

/** First pass: the no-return value of each old laser message type whose
 *  readings pile up at one (NoReturnFinder), for logs that state no maximum. */
std::map<std::string, NoReturnLevel> findNoReturnLevels(const std::string& path) {
  std::map<std::string, NoReturnFinder> finders;
  try {
    LineSource src(path);
    std::string line;
    std::vector<std::string_view> tok;
    bool complete = true;
    while (src.next(line, complete)) {
      splitFields(line, tok);
      if (!tok.empty() && isOldLaser(tok[0])) addOldLaserReadings(tok, finders);
    }
  } catch (const std::exception&) {
    // The conversion pass reports what is wrong, at its line.
  }
  std::map<std::string, NoReturnLevel> levels;
  for (const auto& [type, finder] : finders) {
    NoReturnLevel l;
    if (finder.find(l)) levels[type] = l;
  }
  return levels;
}

}  // namespace

// ---------------------------------------------------------------------------

CarmenOdometry parseCarmenOdometry(const std::string& name) {
  if (name == "auto") return CarmenOdometry::Auto;
  if (name == "laser") return CarmenOdometry::Laser;
  if (name == "odom") return CarmenOdometry::Odom;
  if (name == "none") return CarmenOdometry::None;
  throw InputError("unknown odometry source '" + name + "' (auto, laser, odom or none)");
}

std::string toString(CarmenOdometry o) {
  switch (o) {
    case CarmenOdometry::Auto:
      return "auto";
    case CarmenOdometry::Laser:
      return "laser";
    case CarmenOdometry::Odom:
      return "odom";
    case CarmenOdometry::None:
      return "none";
  }
  return "?";
}

std::string defaultTumPath(const std::string& rawlog_path) {
  fs::path p(rawlog_path);
  if (p.extension() == ".gz") p.replace_extension();
  if (p.extension() == ".rawlog") p.replace_extension();
  p += ".tum";
  return p.string();
}

uint64_t CarmenImportStats::totalScans() const {
  uint64_t n = 0;
  for (const auto& [k, v] : scans) n += v;
  return n;
}

uint64_t CarmenImportStats::totalUnknown() const {
  uint64_t n = 0;
  for (const auto& [k, v] : unknown) n += v;
  return n;
}

std::string CarmenImportStats::toText() const {
  std::ostringstream o;
  o << "lines:        " << lines << " (" << comments << " comments, " << params << " PARAM)\n";
  o << "scans:        " << totalScans();
  if (!scans.empty()) o << " (" << joinCounts(scans) << ")";
  o << "\n";
  if (!negative_time.empty()) {
    uint64_t n = 0;
    for (const auto& [k, v] : negative_time) n += v;
    o << "skipped:      " << n << " line(s) with a negative ipc_timestamp ("
      << joinCounts(negative_time) << ")\n";
  }
  for (const auto& [k, l] : no_return)
    o << "no return:    " << k << " readings >= " << fmtNumber(l.limit, 2) << " m (" << l.piled
      << " piled at " << fmtNumber(l.level, 2) << " m"
      << (l.param_max > 0 ? "; PARAM says " + fmtLimit(l.param_max) + " m" : "") << ")\n";
  o << "odometry:     " << odometry << " (source: " << toString(odometry_source);
  if (odometry_noise)
    o << "; noise seed " << odometry_noise->seed << ": "
      << fmtNumber(100 * odometry_noise->dist_frac, 3) << " % of distance, "
      << fmtNumber(odometry_noise->deg_per_m, 3) << " deg per m, "
      << fmtNumber(100 * odometry_noise->turn_frac, 3) << " % of turn";
  o << ")\n";
  if (observations)
    o << "time span:    " << fmtTime(min_time) << " .. " << fmtTime(max_time) << " s ("
      << fmtNumber(max_time - min_time, 1) << " s)\n";
  o << "rawlog:       " << output << " (" << observations << " observations)\n";
  if (!tum.empty())
    o << "trajectory:   " << tum << " (" << tum_poses << " poses, TUM)\n";
  else
    o << "trajectory:   none (no FLASER or ROBOTLASER message with a robot pose)\n";
  return o.str();
}

std::string CarmenImportStats::toJson() const {
  JsonWriter j;
  j.beginObject();
  j.key("lines").value(lines);
  j.key("comments").value(comments);
  j.key("params").value(params);
  j.key("scans").value(totalScans());
  j.key("scans_by_type").beginObject();
  for (const auto& [k, v] : scans) j.key(k).value(v);
  j.endObject();
  j.key("empty_scans").value(empty_scans);
  j.key("bad_readings").value(bad_readings);
  j.key("scans_with_bad_readings").value(scans_with_bad_readings);
  j.key("no_return").beginObject();
  for (const auto& [k, l] : no_return) {
    j.key(k).beginObject();
    j.key("level_m").value(l.level);
    j.key("limit_m").value(l.limit);
    j.key("readings").value(l.piled);
    if (l.param_max > 0) j.key("param_max_m").value(l.param_max);
    j.endObject();
  }
  j.endObject();
  j.key("odometry").value(odometry);
  j.key("odometry_source").value(toString(odometry_source));
  if (odometry_noise) {
    j.key("odometry_noise").beginObject();
    j.key("seed").value(odometry_noise->seed);
    j.key("dist_frac").value(odometry_noise->dist_frac);
    j.key("deg_per_m").value(odometry_noise->deg_per_m);
    j.key("turn_frac").value(odometry_noise->turn_frac);
    j.endObject();
  }
  j.key("observations").value(observations);
  j.key("first_time").value(first_time);
  j.key("last_time").value(last_time);
  j.key("min_time").value(min_time);
  j.key("max_time").value(max_time);
  j.key("scans_time_backwards").value(scans_time_backwards);
  j.key("scans_time_repeated").value(scans_time_repeated);
  j.key("unknown").beginObject();
  for (const auto& [k, v] : unknown) j.key(k).value(v);
  j.endObject();
  j.key("negative_time").beginObject();
  for (const auto& [k, v] : negative_time) j.key(k).value(v);
  j.endObject();
  j.key("unused").beginObject();
  for (const auto& [k, v] : unused) j.key(k).value(v);
  j.endObject();
  j.key("rawlog").value(output);
  j.key("tum").value(tum);
  j.key("tum_poses").value(tum_poses);
  j.endObject();
  return j.str() + "\n";
}

std::string CarmenImportStats::notesText() const {
  std::string s;
  for (const auto& [k, v] : unknown)
    s += "skipped " + std::to_string(v) + " " + k + " line" + (v == 1 ? "" : "s") +
         " (unknown message type)\n";
  for (const auto& [k, v] : unused)
    s += "skipped " + std::to_string(v) + " " + k + " line" + (v == 1 ? "" : "s") +
         " (odometry source is '" + toString(odometry_source) + "'; --odometry odom uses them)\n";
  for (const auto& [k, v] : negative_time)
    s += "skipped " + std::to_string(v) + " " + k + " line" + (v == 1 ? "" : "s") +
         " with a negative ipc_timestamp (a logger artefact; left out)\n";
  if (empty_scans)
    s += "skipped " + std::to_string(empty_scans) + " laser message(s) with no reading\n";
  if (bad_readings)
    s += "warning: " + std::to_string(bad_readings) + " reading(s) in " +
         std::to_string(scans_with_bad_readings) +
         " scan(s) are nan, inf or negative (first at line " +
         std::to_string(first_bad_reading_line) + "): kept as invalid beams\n";
  for (const auto& [k, l] : no_return)
    s += "note: " + std::to_string(l.piled) + " " + k + " reading(s) pile up at " +
         fmtNumber(l.level, 2) +
         " m, the top of the log's ranges: the scanner's no-return value; readings >= " +
         fmtNumber(l.limit, 2) + " m are invalid beams" +
         (l.param_max > 0 ? ", not PARAM's " + fmtLimit(l.param_max) +
                                " m (the range CARMEN's robot module used; the readings go "
                                "beyond it)"
                          : "") +
         "; --max-range sets the limit\n";
  if (scans_time_backwards)
    s += "note: " + std::to_string(scans_time_backwards) +
         " scan(s) have a timestamp earlier than the scan before (kept in file order; the TUM "
         "file is sorted by time)\n";
  if (scans_time_repeated)
    s += "note: " + std::to_string(scans_time_repeated) +
         " scan(s) repeat the timestamp of the scan before (the log's own time resolution)\n";
  return s;
}

CarmenImportError::CarmenImportError(const std::string& what, CarmenImportStats s)
    : InputError(what), stats(std::move(s)) {}

namespace {

void checkOptions(const CarmenImportOptions& opt) {
  if (opt.output.empty()) throw InputError("no output rawlog given");
  if (!(opt.max_range >= 0) || !std::isfinite(opt.max_range))
    throw InputError("max range must be a finite number >= 0 (0: from the log)");
  if (opt.compression < 1 || opt.compression > 9)
    throw InputError("compression level must be 1..9");
  if (opt.odometry_noise) {
    const auto& n = *opt.odometry_noise;
    if (opt.odometry == CarmenOdometry::None)
      throw InputError("odometry noise needs an odometry source (not --odometry none)");
    for (double v : {n.dist_frac, n.deg_per_m, n.turn_frac})
      if (!(v >= 0 && v <= 10)) throw InputError("odometry noise model values must be in [0, 10]");
  }
}

void checkOutputNotInput(const CarmenImportOptions& opt) {
  std::error_code ec;
  if (fs::exists(opt.output, ec) && fs::equivalent(opt.input, opt.output, ec))
    throw InputError(opt.output + ": the output would overwrite the input log");
}

std::string tumPathOf(const CarmenImportOptions& opt) {
  return !opt.write_tum ? std::string() : (opt.tum.empty() ? defaultTumPath(opt.output) : opt.tum);
}

/** Found now rather than after a long conversion. */
void checkTumPath(const CarmenImportOptions& opt, const std::string& tum_path) {
  std::error_code ec;
  const fs::path dir = fs::path(tum_path).parent_path();
  if (!dir.empty() && !fs::is_directory(dir, ec))
    throw InputError(tum_path + ": cannot write the trajectory: no directory " + dir.string());
  if (fs::exists(tum_path, ec) && fs::equivalent(opt.input, tum_path, ec))
    throw InputError(tum_path + ": the trajectory would overwrite the input log");
  if (fs::path(tum_path).lexically_normal() == fs::path(opt.output).lexically_normal())
    throw InputError(tum_path + ": the trajectory and the rawlog are the same file");
}

/** The header of a RAWLASERk or ROBOTLASERk line, up to its remissions. */
struct RawLaserHeader {
  ScanGeometry g;
  double fov = 0, res = 0, maxr = 0, acc = 0;
  size_t n = 0, m = 0;  ///< readings, remissions
};

/** The robot's pose, speeds and laser mount of a ROBOTLASERk line from field p. */
struct RobotLaserTail {
  CPose2D robot, mount;
  std::pair<double, double> vel;
};

/** The conversion pass: the lines of the log into a temporary rawlog. */
class CarmenConverter {
 public:
  CarmenConverter(const CarmenImportOptions& opt, LineSource& src, CarmenImportStats& st,
                  std::map<std::string, NoReturnLevel> no_return)
      : no_return_(std::move(no_return)),
        opt_(opt),
        src_(src),
        st_(st),
        tmp_(opt.output + ".tmp"),
        progress_("carmen " + opt.input, src.fileSize(), false),
        laser_odom_(st.odometry_source == CarmenOdometry::Laser),
        odom_lines_(st.odometry_source == CarmenOdometry::Odom) {
    if (opt.odometry_noise) noise_.emplace(*opt.odometry_noise);
    if (!out_.open(tmp_, opt.compression))
      throw InputError(opt.output + ": cannot write the rawlog (does the directory exist?)");
    if (!opt.progress) progress_.setEnabled(false);
  }

  /** Converts every line; the first malformed line stops it and is returned. */
  std::optional<BadLine> run() {
    std::string line;
    std::vector<std::string_view> tok;
    bool complete = true;
    std::optional<BadLine> failure;
    try {
      while (src_.next(line, complete)) convertLine(line, complete, tok);
      src_.checkComplete();
    } catch (const BadLine& e) {
      failure = e;
    } catch (...) {
      out_.close();
      removeTemporary();
      throw;
    }
    progress_.finish();
    out_.close();
    return failure;
  }

  const std::string& temporary() const { return tmp_; }
  void removeTemporary() const {
    std::error_code ec;
    fs::remove(tmp_, ec);
  }
  Trajectory2D& trajectory() { return traj_; }

 private:
  void convertLine(const std::string& line, bool complete, std::vector<std::string_view>& tok) {
    ++st_.lines;
    if ((st_.lines & 255) == 0) progress_.update(src_.filePosition(), st_.lines);
    splitFields(line, tok);
    if (tok.empty()) return;
    if (tok[0][0] == '#') {
      ++st_.comments;
      return;
    }
    const Fields f(opt_.input, src_.lineNumber(), complete, tok);
    const std::string_view type = tok[0];
    if (type == "PARAM") return readParam(f);
    if (isOldLaser(type)) return readOldLaser(f);
    const bool raw = hasDigitSuffix(type, "RAWLASER");
    const bool robot = hasDigitSuffix(type, "ROBOTLASER");
    if (raw || robot) return readNewLaser(f, robot);
    if (type == "ODOM") return readOdom(f);
    skipUnknown(f, complete);
  }

  void readParam(const Fields& f) {
    ++st_.params;
    f.need(3, "param_value");
    const std::string_view name = f[1];
    auto number = [&](double& dst, bool positive) {
      const double v = f.bounded(2, std::string(name), kMaxRangeBound, "");
      if (positive && !(v > 0)) f.fail(std::string(name) + " must be > 0");
      dst = v;
    };
    if (name == "robot_front_laser_max") number(par_.front_max, true);
    if (name == "robot_rear_laser_max") number(par_.rear_max, true);
    if (name == "laser_front_laser_resolution") number(par_.front_resolution, true);
    if (name == "laser_rear_laser_resolution") number(par_.rear_resolution, true);
    if (name == "robot_frontlaser_offset") number(par_.front_offset, false);
    if (name == "robot_rearlaser_offset") number(par_.rear_offset, false);
  }

  /** num_readings of a line of `type`, checked against its field count. */
  static size_t readingCount(const Fields& f, size_t i) {
    const size_t n = f.count(i, "num_readings");
    if (n > f.size())
      f.fail("num_readings is " + std::to_string(n) + " but the line has only " +
             std::to_string(f.size()) + " fields");
    return n;
  }

  /** The line's timestamp, or empty (and counted) for a negative one. */
  std::optional<mrpt::Clock::time_point> stampOrSkip(const Fields& f, double& t) {
    const auto stamp = f.timestamp(t);
    if (!stamp) ++st_.negative_time[f.type()];
    return stamp;
  }

  // FLASER/RLASER n r1..rn x y theta odom_x odom_y odom_theta ts host lts
  // LASERk n r1..rn ts host lts
  void readOldLaser(const Fields& f) {
    const std::string_view type = f[0];
    const bool front = type == "FLASER", rear = type == "RLASER";
    f.need(2, "num_readings");
    const size_t n = readingCount(f, 1);
    const size_t poses = (front || rear) ? 6 : 0;
    f.exact(2 + n + poses + 3, std::string(type) + " num_readings=" + std::to_string(n) + ": " +
                                   std::to_string(n) + " readings, " +
                                   (poses ? "x y theta odom_x odom_y odom_theta, " : "") +
                                   "ipc_timestamp ipc_hostname logger_timestamp");
    double t = 0;
    const auto stamp = stampOrSkip(f, t);
    if (!stamp) return;
    buildScan(f, 2, n, oldLaserGeometry(type, n, front, rear), oldLaserMount(front, rear), *stamp);
    if (poses) readOldLaserPoses(f, 2 + n, front, *stamp, t);
    writeScan(n, t);
  }

  /** The maximum range: the type's no-return limit when its readings show
   *  one (used ones are reported in the stats), else PARAM's, else CARMEN's
   *  default. The scanner's own no-return value wins over PARAM
   *  robot_*_laser_max: that is a setting of CARMEN's robot module (the range
   *  it used), which a log may state far below what its scanner measured. */
  ScanGeometry oldLaserGeometry(std::string_view type, size_t n, bool front, bool rear) {
    ScanGeometry g;
    g.increment = oldLaserIncrement(n, front  ? par_.front_resolution
                                       : rear ? par_.rear_resolution
                                              : 0);
    const double pmax = front ? par_.front_max : rear ? par_.rear_max : 0;
    const auto level = no_return_.find(std::string(type));
    if (level != no_return_.end()) {
      g.max_range = level->second.limit;
      auto& used = st_.no_return[level->first];
      used = level->second;
      used.param_max = pmax;
    } else if (pmax > 0) {
      g.max_range = pmax;
    }
    return g;
  }

  CPose2D oldLaserMount(bool front, bool rear) const {
    CPose2D mount;
    if (front) mount = CPose2D(par_.front_offset, 0, 0);
    if (rear) mount = CPose2D(-par_.rear_offset, 0, kPi);
    return mount;
  }

  /** The laser and odometry poses of FLASER/RLASER from field p. */
  void readOldLaserPoses(const Fields& f, size_t p, bool front, mrpt::Clock::time_point stamp,
                         double t) {
    const CPose2D laser(f.coordinate(p, "x"), f.coordinate(p + 1, "y"), f.angle(p + 2, "theta"));
    const CPose2D odo(f.coordinate(p + 3, "odom_x"), f.coordinate(p + 4, "odom_y"),
                      f.angle(p + 5, "odom_theta"));
    if (laser_odom_) writeOdometry(odo, std::nullopt, stamp, t);
    if (front) {
      // CARMEN logs the front laser's pose; the robot is offset behind it.
      const CPose2D robot = laser + CPose2D(-par_.front_offset, 0, 0);
      traj_.push_back({t, robot.x(), robot.y(), robot.phi()});
    }
  }

  // type start fov res max_range accuracy remission_mode n r.. m rem.. [poses..] ts host lts
  void readNewLaser(const Fields& f, bool robot) {
    const RawLaserHeader h = readRawLaserHeader(f, robot);
    double t = 0;
    const auto stamp = stampOrSkip(f, t);
    if (!stamp) return;
    const ScanGeometry g = rawLaserGeometry(f, h);
    std::optional<RobotLaserTail> tail;
    if (robot) tail = readRobotLaserTail(f, 10 + h.n + h.m);
    buildScan(f, 9, h.n, g, tail ? tail->mount : CPose2D(), *stamp);
    if (tail) {
      if (laser_odom_) writeOdometry(tail->robot, tail->vel, *stamp, t);
      traj_.push_back({t, tail->robot.x(), tail->robot.y(), tail->robot.phi()});
    }
    writeScan(h.n, t);
  }

  static RawLaserHeader readRawLaserHeader(const Fields& f, bool robot) {
    f.need(9, "num_readings");
    RawLaserHeader h;
    (void)f.real(1, "laser_type");
    h.g.start = f.angle(2, "start_angle");
    h.fov = f.angle(3, "field_of_view");
    h.res = f.angle(4, "angular_resolution");
    h.maxr = f.bounded(5, "maximum_range", kMaxRangeBound, "m");
    h.acc = f.bounded(6, "accuracy", kMaxRangeBound, "m");
    (void)f.real(7, "remission_mode");
    h.n = readingCount(f, 8);
    f.need(10 + h.n, "num_remissions after " + std::to_string(h.n) + " readings");
    h.m = f.count(9 + h.n, "num_remissions");
    if (h.m > f.size())
      f.fail("num_remissions is " + std::to_string(h.m) + " but the line has only " +
             std::to_string(f.size()) + " fields");
    const size_t tail = robot ? 11 : 0;
    f.exact(10 + h.n + h.m + tail + 3,
            std::string(f[0]) + " num_readings=" + std::to_string(h.n) +
                " num_remissions=" + std::to_string(h.m) +
                (robot ? ", laser_pose x y theta, robot_pose x y theta, laser_tv laser_rv "
                         "forward_safety_dist side_safety_dist turn_axis"
                       : "") +
                ", ipc_timestamp ipc_hostname logger_timestamp");
    for (size_t k = 0; k < h.m; ++k)
      (void)f.anyNumber(10 + h.n + k, "remission " + std::to_string(k));
    return h;
  }

  static ScanGeometry rawLaserGeometry(const Fields& f, const RawLaserHeader& h) {
    ScanGeometry g = h.g;
    if (h.res > 0)
      g.increment = h.res;
    else if (h.fov > 0 && h.n > 1)
      g.increment = h.fov / static_cast<double>(h.n - 1);
    else if (h.n > 1)
      f.fail("angular_resolution and field_of_view are both <= 0");
    if (h.maxr > 0) g.max_range = h.maxr;
    if (h.acc > 0) g.accuracy = h.acc;
    return g;
  }

  static RobotLaserTail readRobotLaserTail(const Fields& f, size_t p) {
    RobotLaserTail r;
    const CPose2D laser(f.coordinate(p, "laser_pose_x"), f.coordinate(p + 1, "laser_pose_y"),
                        f.angle(p + 2, "laser_pose_theta"));
    r.robot = CPose2D(f.coordinate(p + 3, "robot_pose_x"), f.coordinate(p + 4, "robot_pose_y"),
                      f.angle(p + 5, "robot_pose_theta"));
    r.vel = {f.speed(p + 6, "laser_tv"), f.speed(p + 7, "laser_rv")};
    (void)f.real(p + 8, "forward_safety_dist");
    (void)f.real(p + 9, "side_safety_dist");
    (void)f.real(p + 10, "turn_axis");
    r.mount = laser - r.robot;  // the laser in the robot's frame
    return r;
  }

  void readOdom(const Fields& f) {
    f.exact(10, "ODOM x y theta tv rv accel ipc_timestamp ipc_hostname logger_timestamp");
    const CPose2D pose(f.coordinate(1, "x"), f.coordinate(2, "y"), f.angle(3, "theta"));
    const double tv = f.speed(4, "tv"), rv = f.speed(5, "rv");
    (void)f.speed(6, "accel");
    double t = 0;
    const auto stamp = f.timestamp(t);
    if (!stamp) {
      ++st_.negative_time["ODOM"];
      return;
    }
    if (odom_lines_)
      writeOdometry(pose, std::make_pair(tv, rv), *stamp, t);
    else
      ++st_.unused["ODOM"];
  }

  void skipUnknown(const Fields& f, bool complete) {
    const std::string_view type = f[0];
    // A log cut inside the name of its last message.
    if (!complete)
      for (const char* known : {"FLASER", "RLASER", "ROBOTLASER", "RAWLASER", "ODOM", "PARAM"})
        if (std::string_view(known).substr(0, type.size()) == type)
          f.fail("the message name is cut short");
    const std::string name = printable(type);
    if (st_.unknown.size() < 100 || st_.unknown.count(name))
      ++st_.unknown[name];
    else
      ++st_.unknown["(other)"];
  }

  void emitted(double t) {
    if (st_.observations == 0) {
      st_.first_time = st_.min_time = st_.max_time = t;
    }
    st_.last_time = t;
    st_.min_time = std::min(st_.min_time, t);
    st_.max_time = std::max(st_.max_time, t);
    ++st_.observations;
  }

  void writeOdometry(const CPose2D& pose, std::optional<std::pair<double, double>> vel,
                     mrpt::Clock::time_point stamp, double t) {
    mrpt::obs::CObservationOdometry o;
    o.sensorLabel = "ODOMETRY";
    o.timestamp = stamp;
    o.odometry = noise_ ? noise_->next(pose) : pose;
    if (vel) {
      o.hasVelocities = true;
      o.velocityLocal = mrpt::math::TTwist2D(vel->first, 0, vel->second);
    }
    writeObject(out_, o);
    ++st_.odometry;
    emitted(t);
  }

  // Builds (and so checks) the scan whose readings are fields [first, first + n)
  // before anything of its line is written: a bad line adds nothing.
  void buildScan(const Fields& f, size_t first, size_t n, const ScanGeometry& g,
                 const CPose2D& mount, mrpt::Clock::time_point stamp) {
    const double aperture = n ? static_cast<double>(n - 1) * g.increment : 0;
    if (!(aperture <= 2 * kPi + 1e-6))
      f.fail(std::to_string(n) + " readings " + fmtNumber(g.increment * 180 / kPi, 4) +
             " deg apart span more than 360 deg");
    const double max_range = opt_.max_range > 0 ? opt_.max_range : g.max_range;
    scan_.sensorLabel = f.type();
    scan_.timestamp = stamp;
    scan_.aperture = static_cast<float>(aperture);
    scan_.rightToLeft = true;
    scan_.maxRange = static_cast<float>(max_range);
    scan_.stdError = static_cast<float>(g.accuracy);
    scan_.resizeScan(n);
    pending_bad_readings_ = readRanges(f, first, n, max_range);
    // MRPT's beams are symmetric about the sensor's x axis: turn the sensor
    // to the middle of CARMEN's [start, start + aperture].
    scan_.sensorPose = mrpt::poses::CPose3D(mount + CPose2D(0, 0, g.start + aperture / 2));
  }

  /** Fills the scan's ranges; returns how many are nan, inf or negative. */
  uint64_t readRanges(const Fields& f, size_t first, size_t n, double max_range) {
    uint64_t not_finite = 0;
    for (size_t i = 0; i < n; ++i) {
      const double r = f.anyNumber(first + i, "reading " + std::to_string(i));
      if (!std::isfinite(r) || r < 0) ++not_finite;
      const bool valid = std::isfinite(r) && r > 0 && r < max_range;
      // Invalid readings are stored as the maximum range (1e300 fits no float).
      scan_.setScanRange(i, valid ? static_cast<float>(r) : static_cast<float>(max_range));
      scan_.setScanRangeValidity(i, valid);
    }
    return not_finite;
  }

  void writeScan(size_t n, double t) {
    if (n == 0) {  // MRPT's scan code divides by the beam count
      ++st_.empty_scans;
      return;
    }
    if (pending_bad_readings_) {
      st_.bad_readings += pending_bad_readings_;
      ++st_.scans_with_bad_readings;
      if (!st_.first_bad_reading_line) st_.first_bad_reading_line = src_.lineNumber();
    }
    writeObject(out_, scan_);
    ++st_.scans[scan_.sensorLabel];
    if (have_prev_scan_) {
      if (t < prev_scan_t_) ++st_.scans_time_backwards;
      if (t == prev_scan_t_) ++st_.scans_time_repeated;
    }
    have_prev_scan_ = true;
    prev_scan_t_ = t;
    emitted(t);
  }

  const std::map<std::string, NoReturnLevel> no_return_;  // found by the first pass
  const CarmenImportOptions& opt_;
  LineSource& src_;
  CarmenImportStats& st_;
  const std::string tmp_;
  mrpt::io::CFileGZOutputStream out_;
  Progress progress_;
  const bool laser_odom_, odom_lines_;
  std::optional<NoisyOdometry> noise_;  // --odometry-noise
  Trajectory2D traj_;
  LogParams par_;
  bool have_prev_scan_ = false;
  double prev_scan_t_ = 0;
  mrpt::obs::CObservation2DRangeScan scan_;
  uint64_t pending_bad_readings_ = 0;  // of the scan built last
};

[[noreturn]] void failNothingConverted(const CarmenImportOptions& opt, const CarmenImportStats& st,
                                       const std::optional<BadLine>& failure) {
  if (failure)
    throw InputError(std::string(failure->what()) +
                     "; nothing was converted before it, no file written");
  std::string what = opt.input + ": nothing to convert: no laser or odometry message in " +
                     std::to_string(st.lines) + " lines";
  if (!st.unknown.empty()) what += " (skipped: " + joinCounts(st.unknown) + ")";
  if (!st.unused.empty()) what += " (not used: " + joinCounts(st.unused) + ")";
  throw InputError(what);
}

void moveRawlogInPlace(const CarmenImportOptions& opt, const CarmenConverter& conv) {
  std::error_code ec;
  fs::rename(conv.temporary(), opt.output, ec);
  if (ec) {
    conv.removeTemporary();
    throw std::runtime_error(opt.output + ": cannot write the rawlog: " + ec.message());
  }
}

void writeTrajectory(const std::string& tum_path, Trajectory2D& traj, CarmenImportStats& st) {
  if (tum_path.empty() || traj.empty()) return;
  std::stable_sort(traj.begin(), traj.end(),
                   [](const TimedPose2D& a, const TimedPose2D& b) { return a.t < b.t; });
  writeTum(tum_path, traj);
  st.tum = tum_path;
  st.tum_poses = traj.size();
}

[[noreturn]] void failPartlyConverted(const BadLine& failure, const CarmenImportStats& st) {
  std::string what = std::string(failure.what()) + "; the " + std::to_string(failure.lines_before) +
                     " lines before it were converted: " + st.output + " (" +
                     std::to_string(st.observations) + " observations)";
  if (!st.tum.empty()) what += ", " + st.tum + " (" + std::to_string(st.tum_poses) + " poses)";
  throw CarmenImportError(what, st);
}

}  // namespace

CarmenImportStats importCarmen(const CarmenImportOptions& opt) {
  checkOptions(opt);
  LineSource src(opt.input);  // checks the input before any output exists
  checkOutputNotInput(opt);

  CarmenImportStats st;
  st.odometry_source =
      opt.odometry == CarmenOdometry::Auto ? chooseOdometry(opt.input) : opt.odometry;
  if (st.odometry_source != CarmenOdometry::None) st.odometry_noise = opt.odometry_noise;
  const std::string tum_path = tumPathOf(opt);
  if (!tum_path.empty()) checkTumPath(opt, tum_path);

  CarmenConverter conv(
      opt, src, st,
      opt.max_range > 0 ? std::map<std::string, NoReturnLevel>() : findNoReturnLevels(opt.input));
  const std::optional<BadLine> failure = conv.run();
  if (st.observations == 0) {
    conv.removeTemporary();
    failNothingConverted(opt, st, failure);
  }
  moveRawlogInPlace(opt, conv);
  st.output = opt.output;
  writeTrajectory(tum_path, conv.trajectory(), st);
  if (failure) failPartlyConverted(*failure, st);
  return st;
}

}  // namespace carenav::io
