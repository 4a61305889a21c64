#include <carenav/io/rawlog_reader.h>

#include <carenav/common/crash_guard.h>
#include <mrpt/rtti/CObject.h>

#include "gz_input.h"

#include <mrpt/io/CStream.h>
#include <mrpt/maps/registerAllClasses.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CActionRobotMovement3D.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/registerAllClasses.h>
#include <mrpt/poses/CPosePDF.h>
#include <mrpt/serialization/CArchive.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <new>
#include <stdexcept>

#include "allocation_budget.h"

namespace carenav::io {

using mrpt::obs::CActionCollection;
using mrpt::obs::CObservation;
using mrpt::obs::CSensoryFrame;

/** Passes reads through to the gzip stream and counts the uncompressed bytes,
 *  so a clean end (no byte of a new object) is told from a truncated object.
 *  Bytes looked at with peek() are handed out again by the next reads. */
class RawlogReader::CountingStream : public mrpt::io::CStream {
 public:
  CountingStream(const std::string& path, uint64_t file_size) : file_size_(file_size) {
    std::string err;
    if (!gz_.open(path, err)) throw InputError(path + ": cannot open the rawlog: " + err);
  }
  size_t Read(void* buf, size_t n) override {
    auto* out = static_cast<char*>(buf);
    size_t got = std::min(n, peeked_.size() - peek_pos_);
    std::copy_n(peeked_.data() + peek_pos_, got, out);
    peek_pos_ += got;
    if (peek_pos_ == peeked_.size()) peeked_.clear(), peek_pos_ = 0;
    if (got < n) got += rawRead(out + got, n - got);
    count_ += got;
    if (got < n) short_read_ = true;
    return got;
  }
  /** The next `n` bytes without consuming them (fewer at the end of the data). */
  std::string peek(size_t n) {
    if (peek_pos_ > 0) peeked_.erase(0, peek_pos_), peek_pos_ = 0;
    if (peeked_.size() < n) {
      const size_t have = peeked_.size();
      peeked_.resize(n);
      peeked_.resize(have + rawRead(&peeked_[have], n - have));
    }
    return peeked_.substr(0, n);
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
  size_t rawRead(char* buf, size_t n) {
    const long long got = gz_.read(buf, n);
    return got < 0 ? 0 : static_cast<size_t>(got);  // corrupt data: no more bytes
  }
  bool short_read_ = false;
  uint64_t file_size_;
  GzInput gz_;
  uint64_t count_ = 0;
  std::string peeked_;
  size_t peek_pos_ = 0;
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

std::string printable(const std::string& s) {
  std::string o;
  for (char c : s)
    o += (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) ? '?' : c;
  return o;
}

/** What is wrong with an entry's header (class name and version, the first
 *  bytes MRPT reads), or "" when it is a class MRPT knows. `h` holds the
 *  first bytes of the entry. The format: one byte 0x80 | length,
 *  the class name, one version byte; or the old form (before MRPT 0.5.5):
 *  the length as a 32-bit integer below 128, the name, a 32-bit version. */
std::string headerProblem(const std::string& h) {
  if (h.empty()) return "";  // clean end: no byte of a new entry
  const auto b0 = static_cast<uint8_t>(h[0]);
  const bool old_form = !(b0 & 0x80);
  const size_t len = b0 & 0x7f;
  const size_t name_at = old_form ? 4 : 1;
  if (old_form && (h.size() < 4 || h[1] || h[2] || h[3]))
    return "corrupt entry header (the first byte, 0x" + [&] {
      char b[8];
      std::snprintf(b, sizeof b, "%02x", b0);
      return std::string(b);
    }() + ", is no class-name length)";
  if (len == 0 || len > 120)
    return "corrupt entry header (class name of " + std::to_string(len) + " characters)";
  if (h.size() < name_at + len) return "";  // cut short: the read says 'truncated'
  const std::string name = h.substr(name_at, len);
  for (char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == ':'))
      return "corrupt entry header (class name '" + printable(name) + "' is not a name)";
  if (name == "nullptr") return "";
  if (!mrpt::rtti::findRegisteredClass(name))
    return "corrupt entry header (class '" + name + "' is unknown to MRPT)";
  return "";
}

/** Actions one CActionCollection may hold (MRPT's rawlogs have one or two;
 *  docs/rawlog.md). */
constexpr uint32_t kRawlogMaxActions = 1000;

/** One object header at `at` of `h`: the class name and where its body
 *  starts; nullopt when `h` does not hold it whole. */
struct ObjectHeader {
  std::string name;
  uint8_t version = 0;
  size_t body = 0;  // offset of the first byte after the version
};
std::optional<ObjectHeader> objectHeaderAt(const std::string& h, size_t at) {
  if (at >= h.size()) return std::nullopt;
  const auto b0 = static_cast<uint8_t>(h[at]);
  if (!(b0 & 0x80)) return std::nullopt;  // old form: not nested in the classes checked
  const size_t len = b0 & 0x7f;
  if (at + 1 + len + 1 > h.size()) return std::nullopt;
  ObjectHeader o;
  o.name = h.substr(at + 1, len);
  o.version = static_cast<uint8_t>(h[at + 1 + len]);
  o.body = at + 1 + len + 1;
  if (o.name == "nullptr") o.body -= 1;  // no version byte after "nullptr"
  return o;
}

bool derivedFrom(const std::string& name, const mrpt::rtti::TRuntimeClassId* base) {
  const auto* id = mrpt::rtti::findRegisteredClass(name);
  return id && id->derivedFrom(base);
}

/** Nested objects that MRPT would read as a null pointer and then copy
 *  through it (a crash inside MRPT's reader): the first action of an
 *  action collection must be an action, and a 2D motion action's pose
 *  change must be a pose or a pose PDF as its estimation method says.
 *  `h` holds the first bytes of the entry. "" when nothing is wrong (or
 *  the bytes do not reach that far). */
std::string nestedProblem(const std::string& h) {
  const auto top = objectHeaderAt(h, 0);
  if (!top || top->name != "CActionCollection" || top->version != 0) return "";
  if (top->body + 4 > h.size()) return "";
  uint32_t n = 0;
  std::memcpy(&n, h.data() + top->body, 4);
  if (n > kRawlogMaxActions)
    return "corrupt size field (an action collection of " + std::to_string(n) +
           " actions; at most " + std::to_string(kRawlogMaxActions) + ")";
  if (n == 0) return "";
  const auto act = objectHeaderAt(h, top->body + 4);
  if (!act) return "";
  if (!derivedFrom(act->name, CLASS_ID(mrpt::obs::CAction)))
    return "corrupt entry header (the action collection holds a '" + printable(act->name) +
           "', not an action)";
  if (act->name != "CActionRobotMovement2D" || act->version < 2 || act->version > 7) return "";
  if (act->body + 4 > h.size()) return "";
  int32_t method = 0;
  std::memcpy(&method, h.data() + act->body, 4);
  if (method != 0 && method != 1)
    return "corrupt data (a 2D motion action with estimation method " + std::to_string(method) +
           ", not 0 or 1)";
  const auto pose = objectHeaderAt(h, act->body + 4);
  if (!pose) return "";
  if (method == 0 && pose->name != "CPose2D")
    return "corrupt data (an odometry action whose increment is a '" + printable(pose->name) +
           "', not a CPose2D)";
  if (method == 1 && !derivedFrom(pose->name, CLASS_ID(mrpt::poses::CPosePDF)))
    return "corrupt data (a motion action whose pose change is a '" + printable(pose->name) +
           "', not a pose PDF)";
  return "";
}

/** Bytes a corrupt size field may make MRPT allocate at once, at most: what
 *  is left of the stream (an upper bound for gzip: deflate expands at most
 *  1032-fold), but never less than kRawlogMinAllocation (a JPEG decoded on
 *  reading may be larger than its bytes) nor more than kRawlogMaxAllocation. */
size_t allocationBudget(uint64_t left_upper_bound) {
  return static_cast<size_t>(
      std::clamp<uint64_t>(left_upper_bound, kRawlogMinAllocation, kRawlogMaxAllocation));
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
  if (const auto* format = rawlogFormatFor(path)) {
    foreign_ = (*format)(path);
    return;
  }
  if (path.size() > 4 && path.compare(path.size() - 4, 4, ".bag") == 0)
    throw InputError(path +
                     ": a ROS bag, but this carenav was built without its ROS part "
                     "(CARENAV_WITH_ROS=OFF); convert it elsewhere or rebuild with ROS");
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

uint64_t RawlogReader::filePosition() const {
  return foreign_ ? foreign_->position() : stream_->filePosition();
}
uint64_t RawlogReader::streamOffset() const {
  return foreign_ ? foreign_->position() : stream_->count();
}

// An entry of a registered format: one observation (observation-only form).
bool RawlogReader::nextForeign(RawlogEntry& out) {
  mrpt::obs::CObservation::Ptr obs;
  if (!foreign_->next(obs)) {
    if (entries_ == 0)
      throw RawlogError(path_ + ": no observations carenav reads (no scans, no odometry)", 0, 0);
    return false;
  }
  out = RawlogEntry{};
  out.index = entries_;
  out.kind = EntryKind::Observation;
  out.observation = obs;
  out.object = obs;
  fillDerived(out);
  ++entries_;
  return true;
}

bool RawlogReader::next(RawlogEntry& out) {
  if (foreign_) return nextForeign(out);
  const uint64_t start = stream_->count();
  auto broken = [&](const std::string& why) -> RawlogError {
    std::string what;
    if (why.rfind("corrupt ", 0) == 0)
      what = entries_ == 0 ? "not an MRPT rawlog (" + why + ")" : why;
    else if (stream_->shortRead())
      what =
          "the file ends inside this entry (truncated, or a corrupt size field in it reads "
          "past the end)";
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
  auto sizeMessage = [&](size_t asked, uint64_t left) {
    return "corrupt size field (it asks for " + std::to_string(asked) +
           " bytes at once; the stream has " + (gzipped_ ? "at most " : "") + std::to_string(left) +
           " bytes left, and no entry may ask for more than " +
           std::to_string(allocationBudget(left)) + ")";
  };
  // The header first, checked here: MRPT trusts it.
  {
    const std::string head = stream_->peek(512);
    if (std::string bad = headerProblem(head); !bad.empty()) throw broken(bad);
    if (std::string bad = nestedProblem(head); !bad.empty()) throw broken(bad);
  }
  const uint64_t left =
      gzipped_ ? (file_size_ - std::min(file_size_, stream_->filePosition())) * 1032 + (1u << 20)
               : file_size_ - std::min(file_size_, start);
  mrpt::serialization::CSerializable::Ptr obj;
  size_t refused = 0;
  try {
    // MRPT's deserialisers can crash on corrupt size fields; say where.
    const CrashContext guard(path_ + ": rawlog broken at entry " + std::to_string(entries_) +
                             " (byte " + std::to_string(start) + " of the " +
                             (gzipped_ ? "uncompressed " : "") +
                             "stream): corrupt data (MRPT's reader crashed on it); the " +
                             std::to_string(entries_) + " entries before it were read");
    // No single allocation larger than the bytes left: a count MRPT reads
    // before its data is refused before anything is allocated for it.
    detail::AllocationBudget budget(allocationBudget(left));
    try {
      auto arch = mrpt::serialization::archiveFrom(*stream_);
      obj = arch.ReadObject();
    } catch (...) {
      refused = budget.refused();
      throw;
    }
  } catch (const mrpt::serialization::CExceptionEOF& e) {
    if (stream_->count() == start) {  // no byte of a new object: clean end
      if (entries_ == 0)
        throw RawlogError(path_ + ": no entries: not an MRPT rawlog, or an empty one", 0, 0);
      return false;
    }
    if (refused) throw broken(sizeMessage(refused, left));
    throw broken(e.what());
  } catch (const std::bad_alloc&) {
    if (refused) throw broken(sizeMessage(refused, left));
    throw broken("a size field asks for more memory than the memory limit allows");
  } catch (const std::length_error&) {
    throw broken("corrupt size field (a count beyond what any container can hold)");
  } catch (const std::exception& e) {
    if (refused) throw broken(sizeMessage(refused, left));
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
