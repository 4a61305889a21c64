// The one whole-file reader for the text inputs (profiles, worlds,
// scenarios, places, intent scripts, ROS map YAML): bounded in size before
// anything is read, with each reader's own words in its messages.
#pragma once

#include <cstdint>
#include <string>

namespace carenav {

/** How readWholeFile words its refusals, each after "PATH: ". */
struct FileMessages {
  std::string missing = "no such file";
  std::string folder = "is a folder";
  std::string unreadable = "cannot be read";
  /** The kind of file, for the size refusal ("a world file"). */
  std::string what = "a text file";
};

/** Text inputs larger than this are refused before they are read (the
 *  largest real one, a world with 1000 features, is well under 1 MiB). */
inline constexpr std::uintmax_t kMaxTextFileBytes = 64ull << 20;

/** The bytes of the file at `path`. InputError "PATH: <message>" when it is
 *  missing, a folder, unreadable, or larger than `max_bytes`. */
std::string readWholeFile(const std::string& path, const FileMessages& messages = {},
                          std::uintmax_t max_bytes = kMaxTextFileBytes);

}  // namespace carenav
