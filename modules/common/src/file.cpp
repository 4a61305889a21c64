#include <carenav/common/errors.h>
#include <carenav/common/file.h>

#include <filesystem>
#include <fstream>

namespace carenav {

namespace fs = std::filesystem;

std::string readWholeFile(const std::string& path, const FileMessages& m,
                          std::uintmax_t max_bytes) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path + ": " + m.missing);
  if (fs::is_directory(path, ec)) throw InputError(path + ": " + m.folder);
  const std::uintmax_t size = fs::is_regular_file(path, ec) ? fs::file_size(path, ec) : 0;
  if (!ec && size > max_bytes)
    throw InputError(path + ": " + std::to_string(size) + " bytes is too large for " + m.what +
                     " (at most " + std::to_string(max_bytes) + ")");
  std::ifstream f(path, std::ios::binary);
  if (!f) throw InputError(path + ": " + m.unreadable);
  std::string text;
  char buf[1 << 16];
  while (f.read(buf, sizeof buf) || f.gcount() > 0) {  // a pipe has no size: count as it comes
    text.append(buf, static_cast<size_t>(f.gcount()));
    if (text.size() > max_bytes)
      throw InputError(path + ": more than " + std::to_string(max_bytes) +
                       " bytes is too large for " + m.what);
  }
  return text;
}

}  // namespace carenav
