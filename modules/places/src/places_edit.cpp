#include <carenav/common/params.h>
#include <carenav/places/places_edit.h>

#include <cctype>
#include <filesystem>
#include <sstream>

namespace carenav::places {

namespace {

/** One item of a comma list: the whole text a finite number, no blank after it. */
bool finiteNumber(const std::string& item, double& out) {
  if (item.empty() || std::isspace(static_cast<unsigned char>(item.back()))) return false;
  try {
    out = parseReal(item);  // strict, finite; blanks before the number are allowed
    return true;
  } catch (const ParamValueError&) {
    return false;
  }
}

}  // namespace

std::vector<double> parseNumbers(const std::string& text, const std::string& what, size_t count) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    double d = 0;
    if (!finiteNumber(item, d))
      throw InputError(what + " \"" + text + "\": \"" + item + "\" is not a finite number");
    out.push_back(d);
  }
  if (out.size() != count || (!text.empty() && text.back() == ','))
    throw InputError(what + " \"" + text + "\": expected " + std::to_string(count) +
                     " numbers separated by commas");
  return out;
}

std::vector<TPoint2D> parseRect(const std::string& text, const std::string& what) {
  const auto v = parseNumbers(text, what, 4);
  return {{v[0], v[1]}, {v[2], v[1]}, {v[2], v[3]}, {v[0], v[3]}};
}

std::vector<TPoint2D> parseCorners(const std::string& text, const std::string& what) {
  std::vector<TPoint2D> out;
  std::stringstream ss(text);
  std::string corner;
  while (ss >> corner) {
    const auto v = parseNumbers(corner, what, 2);
    out.push_back({v[0], v[1]});
  }
  return out;
}

PlacesFile readPlacesFileOrEmpty(const std::string& path) {
  if (!std::filesystem::exists(path)) return {};
  return readPlacesFile(path);
}

const Room* addPlaceToRoom(PlacesFile& f, const Place& p, bool make_default) {
  f.addPlace(p);
  const Room* room = f.roomOf(f.places.back());
  if (make_default) {
    if (!room) throw InputError("--default: place \"" + p.name + "\" lies in no room");
    f.findRoom(room->name)->default_place = p.name;
  }
  return room;
}

}  // namespace carenav::places
