// Helpers shared by the map readers and writers (not part of the public API).
#pragma once

#include <cstdio>
#include <filesystem>
#include <string>

namespace carenav::io::map_detail {

inline bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string toLower(std::string s);

/** The fewest decimals that read back (strtof) as the same float, never in
 *  exponent form: "0.05", "-12.2", "3.0". */
std::string floatText(float v);

/** A temporary file next to `path` that replaces it on commit() and is
 *  removed if never committed, so readers never see a half-written file.
 *  The temporary name keeps the extension (`keep_ext`) for writers that
 *  choose their format by it (OpenCV). */
class TempFile {
 public:
  explicit TempFile(const std::string& path, const std::string& keep_ext = "");
  ~TempFile();
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  const std::string& path() const { return tmp_; }
  /** Renames the temporary file onto the target. Throws std::runtime_error. */
  void commit();

 private:
  std::string target_, tmp_;
  bool done_ = false;
};

/** Throws InputError when the folder that would hold `path` does not exist. */
void requireParentFolder(const std::string& path);

}  // namespace carenav::io::map_detail
