// Streaming reader of MRPT rawlogs: one top-level object at a time, in
// constant memory, plain or gzip-compressed, both rawlog forms.
#pragma once

#include <carenav/common/errors.h>
#include <carenav/io/rawlog_formats.h>

#include <mrpt/core/Clock.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose2D.h>

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace carenav::io {

enum class EntryKind {
  Actions,       ///< CActionCollection (action/sensory-frame form)
  SensoryFrame,  ///< CSensoryFrame (action/sensory-frame form)
  Observation,   ///< a CObservation on its own (observation-only form)
  Other          ///< any other serializable object MRPT knows
};

/** Where an entry's odometry increment came from. */
enum class OdometrySource { None, Action, OdometryObservation };

/** One top-level object of the rawlog. */
struct RawlogEntry {
  size_t index = 0;  ///< 0-based position of the object in the file
  EntryKind kind = EntryKind::Other;
  mrpt::obs::CActionCollection::Ptr actions;       ///< kind == Actions
  mrpt::obs::CSensoryFrame::Ptr frame;             ///< kind == SensoryFrame
  mrpt::obs::CObservation::Ptr observation;        ///< kind == Observation
  mrpt::serialization::CSerializable::Ptr object;  ///< the object itself, any kind
  /** Robot motion since the previous odometry reading, in the robot frame of
   *  that reading. From a CActionRobotMovement2D (or 3D, projected) in the
   *  action/SF form; from successive CObservationOdometry otherwise. Odometry
   *  observations give increments only while the file has shown no motion
   *  action, so the two never count the same motion twice. */
  std::optional<mrpt::poses::CPose2D> odometry_increment;
  OdometrySource odometry_source = OdometrySource::None;
  /** Earliest valid timestamp in the entry; INVALID_TIMESTAMP if none. */
  mrpt::Clock::time_point timestamp = INVALID_TIMESTAMP;

  /** Observations held: the frame's, the single observation, or none. */
  std::vector<mrpt::obs::CObservation::Ptr> observations() const;
};

/** A rawlog that cannot be read on: names the file, the entry and the byte
 *  offset (in the uncompressed stream) where reading broke. */
class RawlogError : public InputError {
 public:
  RawlogError(const std::string& what, size_t entry, uint64_t offset)
      : InputError(what), entry_(entry), offset_(offset) {}
  size_t entry() const { return entry_; }
  uint64_t offset() const { return offset_; }

 private:
  size_t entry_;
  uint64_t offset_;
};

/** Bounds on what one entry may make MRPT allocate at once (docs/rawlog.md):
 *  the bytes left in the stream, raised to the minimum (images decoded on
 *  reading may be larger than their bytes), capped at the maximum. A request
 *  beyond is refused before the allocation, as a corrupt size field. */
constexpr uint64_t kRawlogMinAllocation = uint64_t{64} << 20;  ///< 64 MiB
constexpr uint64_t kRawlogMaxAllocation = uint64_t{1} << 30;   ///< 1 GiB

class RawlogReader {
 public:
  /** Opens the file. Throws InputError when it is missing, unreadable, a
   *  directory or empty. A file whose extension has a registered format
   *  (rawlog_formats.h, e.g. a ROS `.bag`) is read through it, as an
   *  observation-only rawlog. */
  explicit RawlogReader(const std::string& path);
  ~RawlogReader();
  RawlogReader(const RawlogReader&) = delete;
  RawlogReader& operator=(const RawlogReader&) = delete;

  /** Reads the next entry. Returns false at a clean end of file. Throws
   *  RawlogError when the file is truncated or corrupt; every entry returned
   *  before stays valid. A file with no entry at all is an error too. */
  bool next(RawlogEntry& out);

  const std::string& path() const { return path_; }
  size_t entriesRead() const { return entries_; }
  /** Position in the file as stored (compressed bytes for .gz), for progress. */
  uint64_t filePosition() const;
  uint64_t fileSize() const { return file_size_; }
  /** Bytes of the uncompressed stream consumed so far. */
  uint64_t streamOffset() const;
  bool gzipped() const { return gzipped_; }

 private:
  class CountingStream;
  void fillDerived(RawlogEntry& e);
  bool nextForeign(RawlogEntry& out);

  std::string path_;
  uint64_t file_size_ = 0;
  bool gzipped_ = false;
  std::unique_ptr<CountingStream> stream_;
  std::unique_ptr<ObservationSource> foreign_;  ///< a registered format's reader
  size_t entries_ = 0;
  bool seen_motion_action_ = false;
  std::map<std::string, mrpt::poses::CPose2D> last_odometry_;  // per sensor label
};

}  // namespace carenav::io
