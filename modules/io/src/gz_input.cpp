#include "gz_input.h"

#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace carenav::io {

GzInput::~GzInput() {
  if (f_) gzclose_r(static_cast<gzFile>(f_));
}

bool GzInput::open(const std::string& path, std::string& err) {
  if (f_) gzclose_r(static_cast<gzFile>(f_));
  position_ = 0;
  errno = 0;
  f_ = gzopen(path.c_str(), "rb");
  if (!f_) {
    err = errno ? std::strerror(errno) : "cannot open";
    return false;
  }
  gzbuffer(static_cast<gzFile>(f_), 1u << 15);
  return true;
}

long long GzInput::read(void* buf, size_t n) {
  if (!f_) return -1;
  auto* out = static_cast<unsigned char*>(buf);
  size_t done = 0;
  while (done < n) {
    const unsigned ask = static_cast<unsigned>(std::min<size_t>(n - done, 1u << 30));
    const int r = gzread(static_cast<gzFile>(f_), out + done, ask);
    if (r < 0) return -1;
    if (r == 0) break;
    done += static_cast<size_t>(r);
  }
  position_ += done;
  return static_cast<long long>(done);
}

uint64_t GzInput::filePosition() const {
  if (!f_) return 0;
  const auto off = gzoffset(static_cast<gzFile>(f_));
  return off < 0 ? 0 : static_cast<uint64_t>(off);
}

}  // namespace carenav::io
