#include <carenav/common/data_dir.h>
#include <carenav/common/errors.h>

#include <cstdlib>
#include <filesystem>
#include <system_error>
#include <vector>

namespace fs = std::filesystem;

namespace carenav {
namespace {

bool holdsData(const fs::path& d) {
  std::error_code ec;
  return fs::is_regular_file(d / "ini" / "defaults.ini", ec);
}

std::vector<fs::path> candidates() {
  std::vector<fs::path> c;
  if (const char* e = std::getenv("CARENAV_DATA_DIR"); e && *e) c.emplace_back(e);
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) c.push_back((exe.parent_path() / ".." / "share" / "carenav").lexically_normal());
  return c;
}

}  // namespace

std::string dataDir() {
  for (const auto& d : candidates())
    if (holdsData(d)) return d.string();
  return {};
}

std::string dataFile(const std::string& rel, const std::string& what) {
  const std::string dir = dataDir();
  if (dir.empty()) {
    std::string looked;
    for (const auto& d : candidates()) looked += (looked.empty() ? "" : ", ") + d.string();
    throw InputError(what + ": carenav's data folder (ini/, maps/) not found (looked in " + looked +
                     "); set CARENAV_DATA_DIR or give the file explicitly");
  }
  const fs::path p = fs::path(dir) / rel;
  std::error_code ec;
  if (!fs::exists(p, ec)) throw InputError(what + ": " + p.string() + " not found");
  return p.string();
}

}  // namespace carenav
