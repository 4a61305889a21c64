// Foreign log formats read as observation-only rawlogs. A module above io
// (the ROS module: `.bag`) registers a reader for a file name extension at
// program start; RawlogReader then hands out that file's observations as the
// entries of an observation-only rawlog, so every command that reads a
// rawlog reads the format too, while io itself knows nothing of it.
#pragma once

#include <mrpt/obs/CObservation.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace carenav::io {

/** A foreign log read one observation at a time. */
class ObservationSource {
 public:
  virtual ~ObservationSource() = default;
  /** The next observation; false at a clean end. Throws RawlogError (the
   *  file, the message and the byte offset where it broke) when the file is
   *  truncated or corrupt; what was returned before stays valid. */
  virtual bool next(mrpt::obs::CObservation::Ptr& out) = 0;
  /** Bytes of the file consumed so far (progress). */
  virtual uint64_t position() const = 0;
};

/** Opens a file of the format; throws InputError when it cannot. */
using ObservationSourceFactory =
    std::function<std::unique_ptr<ObservationSource>(const std::string& path)>;

/** Registers `factory` for file names ending with `extension` (".bag",
 *  compared without ASCII case); `name` is what messages call the format.
 *  A second registration of the same extension replaces the first. */
void registerRawlogFormat(const std::string& extension, const std::string& name,
                          ObservationSourceFactory factory);

/** The reader registered for `path`'s extension, or null. */
const ObservationSourceFactory* rawlogFormatFor(const std::string& path);

/** The extensions registered, e.g. {".bag"}. */
std::vector<std::string> rawlogFormatExtensions();

}  // namespace carenav::io
