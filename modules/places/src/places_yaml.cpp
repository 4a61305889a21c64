// The places file on disk: where it lives beside its map, reading it (the
// YAML itself is read by places_read.cpp) and writing it atomically.
#include <carenav/common/file.h>
#include <carenav/places/places.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <unistd.h>

namespace carenav::places {

namespace {

std::string lower(std::string s) {
  for (auto& c : s)
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c + 32);
  return s;
}

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

/** Shortest decimal that reads back as the same double. */
std::string num(double v) {
  char b[64];
  // Plain decimals for map-sized numbers (people edit these files), the
  // shortest %g form for the rest.
  if (v == 0) return "0";
  if (std::abs(v) < 1e15 && std::abs(v) >= 1e-6)
    for (int dec = 0; dec <= 20; ++dec) {
      std::snprintf(b, sizeof b, "%.*f", dec, v);
      if (std::strtod(b, nullptr) == v) return b;
    }
  for (int prec = 1; prec <= 17; ++prec) {
    std::snprintf(b, sizeof b, "%.*g", prec, v);
    if (std::strtod(b, nullptr) == v) break;
  }
  return b;
}

std::string quoted(const std::string& s) {
  std::string q = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') q += '\\';
    q += c;
  }
  return q + "\"";
}

}  // namespace

std::string placesPathForMap(const std::string& map_path) {
  const std::string l = lower(map_path);
  for (const char* ext : {".gridmap.gz", ".gridmap", ".simplemap.gz", ".simplemap", ".yaml", ".yml",
                          ".png", ".pgm", ".ppm"}) {
    const std::string e = ext;
    if (endsWith(l, e) && l.size() > e.size())
      return map_path.substr(0, map_path.size() - e.size()) + ".places.yaml";
  }
  return map_path + ".places.yaml";
}

PlacesFile readPlacesFile(const std::string& path) {
  const std::string text =
      readWholeFile(path, {"no such file", "is a directory", "cannot be read", "a places file"});
  if (text.find('\0') != std::string::npos)
    throw InputError(path + ": is a binary file, not a places YAML file");
  return parsePlaces(text, path);
}

std::string placesToYaml(const PlacesFile& f) {
  std::string y =
      "# carenav rooms and places (docs/places.md). Map frame, metres; heading in degrees.\n"
      "format: 1\n";
  y += f.rooms.empty() ? "rooms: []\n" : "rooms:\n";
  for (const auto& r : f.rooms) {
    y += "  - name: " + quoted(r.name) + "\n    polygon: [";
    for (size_t i = 0; i < r.polygon.size(); ++i)
      y += (i ? ", [" : "[") + num(r.polygon[i].x) + ", " + num(r.polygon[i].y) + "]";
    y += "]\n";
    if (!r.default_place.empty()) y += "    default_place: " + quoted(r.default_place) + "\n";
  }
  y += f.places.empty() ? "places: []\n" : "places:\n";
  for (const auto& p : f.places) {
    y += "  - name: " + quoted(p.name) + "\n    pose: [" + num(p.x) + ", " + num(p.y) + ", " +
         num(p.heading_deg) + "]\n    kind: " + placeKindName(p.kind) + "\n";
    if (!p.room.empty()) y += "    room: " + quoted(p.room) + "\n";
  }
  y += "end: true\n";
  return y;
}

void writePlacesFile(const PlacesFile& f, const std::string& path) {
  const std::string tmp = path + ".tmp" + std::to_string(::getpid());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error(path + ": cannot write " + tmp);
    out << placesToYaml(f);
    out.flush();
    if (!out) {
      std::remove(tmp.c_str());
      throw std::runtime_error(path + ": write failed");
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::remove(tmp.c_str());
    throw std::runtime_error(path + ": cannot rename " + tmp + ": " + ec.message());
  }
}

}  // namespace carenav::places
