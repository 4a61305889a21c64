#include <carenav/io/rawlog_formats.h>

#include <algorithm>
#include <cctype>
#include <map>

namespace carenav::io {

namespace {

struct Format {
  std::string name;
  ObservationSourceFactory factory;
};

std::map<std::string, Format>& registry() {
  static std::map<std::string, Format> r;
  return r;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

}  // namespace

void registerRawlogFormat(const std::string& extension, const std::string& name,
                          ObservationSourceFactory factory) {
  registry()[lower(extension)] = Format{name, std::move(factory)};
}

const ObservationSourceFactory* rawlogFormatFor(const std::string& path) {
  const std::string p = lower(path);
  for (const auto& [ext, f] : registry())
    if (p.size() > ext.size() && p.compare(p.size() - ext.size(), ext.size(), ext) == 0)
      return &f.factory;
  return nullptr;
}

std::vector<std::string> rawlogFormatExtensions() {
  std::vector<std::string> out;
  for (const auto& kv : registry()) out.push_back(kv.first);
  return out;
}

}  // namespace carenav::io
