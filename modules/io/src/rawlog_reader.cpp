#include <carenav/io/rawlog_reader.h>

#include <carenav/common/crash_guard.h>

#include "gz_input.h"

#include <mrpt/io/CStream.h>
#include <mrpt/maps/registerAllClasses.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CActionRobotMovement3D.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/registerAllClasses.h>
#include <mrpt/serialization/CArchive.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <new>

namespace carenav::io {

using mrpt::obs::CActionCollection;
using mrpt::obs::CObservation;
using mrpt::obs::CSensoryFrame;

/** Passes reads through to the gzip stream and counts the uncompressed bytes,
 *  so a clean end (no byte of a new object) is told from a truncated object. */
class RawlogReader::CountingStream : public mrpt::io::CStream {
 public:
  CountingStream(const std::string& path, uint64_t file_size) : file_size_(file_size) {
    std::string err;
    if (!gz_.open(path, err)) throw InputError(path + ": cannot open the rawlog: " + err);
  }
  size_t Read(void* buf, size_t n) override {
    const long long got = gz_.read(buf, n);
    const size_t r = got < 0 ? 0 : static_cast<size_t>(got);  // corrupt data: no more bytes
    count_ += r;
    if (r < n) short_read_ = true;
    return r;
  }
  size_t Write(const void*, size_t) override { return 0; }
  uint64_t Seek(int64_t, TSeekOrigin) override { return count_; }
  uint64_t getTotalBytesCount() const override { return file_size_; }
  uint64_t getPosition() const override { return count_; }
  /** In the file: compressed bytes for a .gz, comparable with its size. */
  uint64_t filePosition() const { return std::min(gz_.filePosition(), file_size_); }
  uint64_t count() const { return count_; }
  /** True once a read got fewer bytes than asked: the data ran out. */
  bool shortRead() const { return short_read_; }

 private:
  bool short_read_ = false;
  uint64_t file_size_;
  GzInput gz_;
  uint64_t count_ = 0;
};

std::vector<CObservation::Ptr> RawlogEntry::observations() const {
  std::vector<CObservation::Ptr> out;
  if (frame)
    for (const auto& o : *frame)
      if (o) out.push_back(o);
  if (observation) out.push_back(observation);
  return out;
}

namespace {
/** MRPT's exceptions carry a banner and a call stack: keep the message. */
std::string mrptMessage(const std::string& what) {
  const auto m = what.find("Message:");
  std::string s = m == std::string::npos ? what : what.substr(m + 8);
  s = s.substr(0, s.find('\n'));
  const auto b = s.find_first_not_of(' ');
  s = b == std::string::npos ? what.substr(0, what.find('\n')) : s.substr(b);
  for (auto& c : s)  // class names read from garbage are not text
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = '?';
  return s;
}
}  // namespace

RawlogReader::RawlogReader(const std::string& path) : path_(path) {
  // Observation classes that live in mrpt-maps (CObservationPointCloud,
  // CObservationRotatingScan, ...) must be registered to be deserialised.
  mrpt::obs::registerAllClasses_mrpt_obs();
  mrpt::maps::registerAllClasses_mrpt_maps();
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path + ": rawlog not found (no such file)");
  if (fs::is_directory(path, ec)) throw InputError(path + ": is a directory, not a rawlog");
  file_size_ = fs::file_size(path, ec);
  if (ec) throw InputError(path + ": cannot read the file size: " + ec.message());
  if (file_size_ == 0) throw InputError(path + ": empty file (0 bytes), not a rawlog");
  {
    std::ifstream f(path, std::ios::binary);
    if (!f) throw InputError(path + ": cannot open the rawlog for reading");
    unsigned char magic[2] = {0, 0};
    f.read(reinterpret_cast<char*>(magic), 2);
    gzipped_ = f.gcount() == 2 && magic[0] == 0x1f && magic[1] == 0x8b;
  }
  stream_ = std::make_unique<CountingStream>(path, file_size_);
}

RawlogReader::~RawlogReader() = default;

uint64_t RawlogReader::filePosition() const { return stream_->filePosition(); }
uint64_t RawlogReader::streamOffset() const { return stream_->count(); }

bool RawlogReader::next(RawlogEntry& out) {
  const uint64_t start = stream_->count();
  auto broken = [&](const std::string& why) -> RawlogError {
    std::string what;
    if (stream_->shortRead())
      what = "the file ends inside this entry (truncated)";
    else if (entries_ == 0)
      what = "not an MRPT rawlog (" + mrptMessage(why) + ")";
    else
      what = "corrupt data (" + mrptMessage(why) + ")";
    const std::string msg =
        path_ + ": rawlog broken at entry " + std::to_string(entries_) + " (byte " +
        std::to_string(start) + " of the " + (gzipped_ ? "uncompressed " : "") +
        "stream): " + what +
        (entries_ == 0 ? std::string("; nothing could be read")
                       : "; the " + std::to_string(entries_) + " entries before it were read");
    return RawlogError(msg, entries_, start);
  };
  mrpt::serialization::CSerializable::Ptr obj;
  try {
    // MRPT's deserialisers can crash on corrupt size fields; say where.
    const CrashContext guard(path_ + ": rawlog broken at entry " + std::to_string(entries_) +
                             " (byte " + std::to_string(start) + " of the " +
                             (gzipped_ ? "uncompressed " : "") +
                             "stream): corrupt data (MRPT's reader crashed on it); the " +
                             std::to_string(entries_) + " entries before it were read");
    auto arch = mrpt::serialization::archiveFrom(*stream_);
    obj = arch.ReadObject();
  } catch (const mrpt::serialization::CExceptionEOF& e) {
    if (stream_->count() == start) {  // no byte of a new object: clean end
      if (entries_ == 0)
        throw RawlogError(path_ + ": no entries: not an MRPT rawlog, or an empty one", 0, 0);
      return false;
    }
    throw broken(e.what());
  } catch (const std::bad_alloc&) {
    throw broken("a size field asks for more memory than the memory limit allows");
  } catch (const std::exception& e) {
    if (stream_->count() == start && entries_ > 0) return false;
    throw broken(e.what());
  }
  if (!obj) throw broken("corrupt (null object)");

  out = RawlogEntry{};
  out.index = entries_;
  out.object = obj;
  if (auto a = std::dynamic_pointer_cast<CActionCollection>(obj)) {
    out.kind = EntryKind::Actions;
    out.actions = a;
  } else if (auto f = std::dynamic_pointer_cast<CSensoryFrame>(obj)) {
    out.kind = EntryKind::SensoryFrame;
    out.frame = f;
  } else if (auto o = std::dynamic_pointer_cast<CObservation>(obj)) {
    out.kind = EntryKind::Observation;
    out.observation = o;
  } else {
    out.kind = EntryKind::Other;
  }
  fillDerived(out);
  ++entries_;
  return true;
}

void RawlogReader::fillDerived(RawlogEntry& e) {
  using namespace mrpt::obs;
  auto earliest = [&e](mrpt::Clock::time_point t) {
    if (t == INVALID_TIMESTAMP) return;
    if (e.timestamp == INVALID_TIMESTAMP || t < e.timestamp) e.timestamp = t;
  };
  if (e.actions) {
    for (size_t i = 0; i < e.actions->size(); ++i) {
      auto act = e.actions->get(i);
      if (!act) continue;
      earliest(act->timestamp);
      if (e.odometry_increment) continue;
      if (auto m2 = std::dynamic_pointer_cast<CActionRobotMovement2D>(act)) {
        e.odometry_increment =
            m2->poseChange ? m2->poseChange->getMeanVal() : m2->rawOdometryIncrementReading;
      } else if (auto m3 = std::dynamic_pointer_cast<CActionRobotMovement3D>(act)) {
        e.odometry_increment = mrpt::poses::CPose2D(m3->poseChange.mean);
      }
      if (e.odometry_increment) {
        e.odometry_source = OdometrySource::Action;
        seen_motion_action_ = true;
      }
    }
  }
  for (const auto& o : e.observations()) {
    earliest(o->timestamp);
    auto odo = std::dynamic_pointer_cast<CObservationOdometry>(o);
    if (!odo || seen_motion_action_) continue;
    auto it = last_odometry_.find(odo->sensorLabel);
    if (it != last_odometry_.end() && !e.odometry_increment) {
      e.odometry_increment = odo->odometry - it->second;  // previous ⊖: motion in its frame
      e.odometry_source = OdometrySource::OdometryObservation;
    }
    last_odometry_[odo->sensorLabel] = odo->odometry;
  }
}

}  // namespace carenav::io
