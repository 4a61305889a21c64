// Reading a plain or gzip file through zlib, with both the uncompressed
// position and the position in the file itself (what progress needs: the
// uncompressed size of a .gz is not known before the end).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace carenav::io {

class GzInput {
 public:
  GzInput() = default;
  ~GzInput();
  GzInput(const GzInput&) = delete;
  GzInput& operator=(const GzInput&) = delete;

  /** False (with `err` set) when the file cannot be opened. Plain files are
   *  read as they are (zlib's transparent mode). */
  bool open(const std::string& path, std::string& err);
  /** Up to n bytes; 0 at the end; -1 for corrupt compressed data. */
  long long read(void* buf, size_t n);
  /** Bytes of the file consumed so far (compressed bytes for a .gz; zlib
   *  reads ahead by its buffer, so this runs slightly ahead of the data
   *  returned, and never beyond the file size). */
  uint64_t filePosition() const;
  /** Uncompressed bytes returned so far. */
  uint64_t position() const { return position_; }

 private:
  void* f_ = nullptr;  // gzFile
  uint64_t position_ = 0;
};

}  // namespace carenav::io
