#include <carenav/common/json.h>
#include <carenav/common/text.h>
#include <carenav/places/places_report.h>

#include <cmath>
#include <cstdio>

namespace carenav::places {

namespace {

std::string fmt(double v) { return formatFixed(v, 3); }

/** A name, or null when empty. */
Json nameOrNull(const std::string& name) { return name.empty() ? Json() : Json(name); }

std::string placeLine(const Place& p) {
  return "    " + p.name + "  (" + fmt(p.x) + ", " + fmt(p.y) + ", " + fmt(p.heading_deg) +
         " deg)  " + placeKindName(p.kind) + "\n";
}

}  // namespace

Json listJson(const PlacesFile& f, const std::string& path) {
  Json rooms = Json::array();
  for (const auto& r : f.rooms) {
    Json poly = Json::array();
    for (const auto& p : r.polygon) poly.push_back({p.x, p.y});
    rooms.push_back(
        {{"name", r.name}, {"polygon", poly}, {"default_place", nameOrNull(r.default_place)}});
  }
  Json places = Json::array();
  for (const auto& p : f.places) {
    const Room* r = f.roomOf(p);
    places.push_back({{"name", p.name},
                      {"x", p.x},
                      {"y", p.y},
                      {"heading_deg", p.heading_deg},
                      {"kind", placeKindName(p.kind)},
                      {"room", r ? Json(r->name) : Json()}});
  }
  return {{"file", path}, {"rooms", rooms}, {"places", places}};
}

std::string listText(const PlacesFile& f, const std::string& path) {
  std::string o = path + ": " + std::to_string(f.rooms.size()) + " rooms, " +
                  std::to_string(f.places.size()) + " places\n";
  for (const auto& r : f.rooms) {
    o += "  room " + r.name;
    if (!r.default_place.empty()) o += "  (default: " + r.default_place + ")";
    o += "\n";
    for (const auto& p : f.places)
      if (f.roomOf(p) == &r) o += placeLine(p);
  }
  bool header = false;
  for (const auto& p : f.places)
    if (!f.roomOf(p)) {
      if (!header) o += "  in no room:\n";
      header = true;
      o += placeLine(p);
    }
  return o;
}

Json whereJson(double x, double y, const WhereResult& w) {
  return {{"x", x},
          {"y", y},
          {"room", w.room ? Json(w.room->name) : Json()},
          {"nearest_place", w.nearest ? Json(w.nearest->name) : Json()},
          {"distance", w.nearest ? Json(w.distance) : Json()}};
}

std::string whereText(const WhereResult& w) {
  std::string o = "room: " + (w.room ? w.room->name : std::string("(none)")) + "\n";
  if (w.nearest) return o + "nearest place: " + w.nearest->name + " (" + fmt(w.distance) + " m)\n";
  return o + "nearest place: (none)\n";
}

Json checkJson(const std::string& path, const std::string& map, double turn_radius,
               const std::vector<Problem>& problems) {
  Json list = Json::array();
  for (const auto& pr : problems) list.push_back({{"kind", pr.kind}, {"what", pr.what}});
  return {{"file", path}, {"map", map}, {"turn_radius", turn_radius}, {"problems", list}};
}

std::string checkText(const PlacesFile& f, const std::string& path,
                      const std::vector<Problem>& problems) {
  std::string o;
  for (const auto& pr : problems) o += pr.kind + ": " + pr.what + "\n";
  if (problems.empty())
    o += path + ": " + std::to_string(f.rooms.size()) + " rooms, " +
         std::to_string(f.places.size()) + " places, no problem\n";
  return o;
}

std::string checkFailureText(const std::string& path, const std::vector<Problem>& problems) {
  return path + ": " + std::to_string(problems.size()) + " problem" +
         (problems.size() == 1 ? "" : "s");
}

Json goalJson(const std::string& name, const Goal& g) {
  return {{"name", name},   {"x", g.x},
          {"y", g.y},       {"heading_deg", g.heading_deg},
          {"room", g.room}, {"place", nameOrNull(g.place)}};
}

std::string goalText(const Goal& g) {
  return fmt(g.x) + " " + fmt(g.y) + " " + fmt(g.heading_deg) + "\n";
}

std::string roomAddedText(const Room& r) {
  return "room \"" + r.name + "\" added (" + std::to_string(r.polygon.size()) + " corners)\n";
}

std::string placeAddedText(const Place& p, const Room* room) {
  return "place \"" + p.name + "\" added in " +
         (room ? "room \"" + room->name + "\"" : std::string("no room")) + "\n";
}

std::string renamedText(const std::string& old_name, const std::string& new_name) {
  return "\"" + old_name + "\" renamed to \"" + new_name + "\"\n";
}

std::string removedText(const std::string& name) { return "\"" + name + "\" removed\n"; }

RoomArea readRoomArea(const std::string& places_file, const std::string& name) {
  const PlacesFile f = readPlacesFile(places_file);
  const Room* room = f.findRoom(name);
  if (!room) {
    std::string known;
    for (const auto& r : f.rooms) known += (known.empty() ? "" : ", ") + r.name;
    throw InputError(places_file + ": no room named '" + name +
                     "' (rooms: " + (known.empty() ? "none" : known) + ")");
  }
  return {room->name,
          [poly = room->polygon](double x, double y) { return pointInPolygon(poly, x, y); }};
}

}  // namespace carenav::places
