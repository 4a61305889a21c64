// The rooms/places model: names, geometry, edits.
#include <carenav/places/places.h>

#include <cmath>

namespace carenav::places {

const char* placeKindName(PlaceKind k) {
  switch (k) {
    case PlaceKind::Place:
      return "place";
    case PlaceKind::UserSearch:
      return "user-search";
    case PlaceKind::ObjectSearch:
      return "object-search";
    case PlaceKind::Dock:
      return "dock";
  }
  return "place";
}

std::optional<PlaceKind> parsePlaceKind(const std::string& s) {
  for (PlaceKind k :
       {PlaceKind::Place, PlaceKind::UserSearch, PlaceKind::ObjectSearch, PlaceKind::Dock})
    if (s == placeKindName(k)) return k;
  return std::nullopt;
}

bool sameName(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    // Only ASCII letters fold: bytes >= 0x80 belong to UTF-8 sequences and
    // must not be touched by a locale-dependent tolower.
    auto fold = [](char c) { return (c >= 'A' && c <= 'Z') ? static_cast<char>(c + 32) : c; };
    if (fold(a[i]) != fold(b[i])) return false;
  }
  return true;
}

namespace {
bool validUtf8(const std::string& s) {
  size_t i = 0;
  while (i < s.size()) {
    const auto c = static_cast<unsigned char>(s[i]);
    size_t n;  // continuation bytes that follow
    if (c < 0x80)
      n = 0;
    else if (c >= 0xC2 && c <= 0xDF)
      n = 1;
    else if ((c & 0xF0) == 0xE0)
      n = 2;
    else if (c >= 0xF0 && c <= 0xF4)
      n = 3;
    else
      return false;
    if (i + n >= s.size()) return false;
    for (size_t k = 1; k <= n; ++k)
      if ((static_cast<unsigned char>(s[i + k]) >> 6) != 2) return false;
    i += n + 1;
  }
  return true;
}
}  // namespace

std::string nameProblem(const std::string& name) {
  if (name.empty()) return "the name is empty";
  if (name.front() == ' ' || name.back() == ' ') return "the name starts or ends with a blank";
  for (char c : name) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
      return "the name holds a control character";
    if (c == '/') return "the name holds '/', which separates room/place in goals";
  }
  if (!validUtf8(name)) return "the name is not valid UTF-8";
  return "";
}

bool pointOnBoundary(const std::vector<TPoint2D>& poly, double x, double y, double eps) {
  const size_t n = poly.size();
  for (size_t i = 0; i < n; ++i) {
    const TPoint2D& a = poly[i];
    const TPoint2D& b = poly[(i + 1) % n];
    const double dx = b.x - a.x, dy = b.y - a.y;
    const double len2 = dx * dx + dy * dy;
    double t = len2 > 0 ? ((x - a.x) * dx + (y - a.y) * dy) / len2 : 0;
    t = std::max(0.0, std::min(1.0, t));
    const double ex = a.x + t * dx - x, ey = a.y + t * dy - y;
    if (ex * ex + ey * ey <= eps * eps) return true;
  }
  return false;
}

bool pointInPolygon(const std::vector<TPoint2D>& poly, double x, double y, double eps) {
  if (poly.size() < 3) return false;
  // The boundary is inside by definition: a place drawn on a wall line still
  // belongs to the room, and the crossing count below is ambiguous there.
  if (pointOnBoundary(poly, x, y, eps)) return true;
  // Crossing number (Shimrat 1962, with the half-open rule of Eppstein's
  // notes): an edge counts when it straddles the horizontal line through the
  // point with one end strictly above and the other at or below, so a ray
  // through a vertex counts the two edges meeting there once in total.
  bool inside = false;
  const size_t n = poly.size();
  for (size_t i = 0, j = n - 1; i < n; j = i++) {
    const TPoint2D& a = poly[i];
    const TPoint2D& b = poly[j];
    if ((a.y > y) != (b.y > y)) {
      const double xc = a.x + (y - a.y) * (b.x - a.x) / (b.y - a.y);
      if (x < xc) inside = !inside;
    }
  }
  return inside;
}

const Room* PlacesFile::findRoom(const std::string& name) const {
  for (const auto& r : rooms)
    if (sameName(r.name, name)) return &r;
  return nullptr;
}
const Place* PlacesFile::findPlace(const std::string& name) const {
  for (const auto& p : places)
    if (sameName(p.name, name)) return &p;
  return nullptr;
}
Room* PlacesFile::findRoom(const std::string& name) {
  return const_cast<Room*>(static_cast<const PlacesFile*>(this)->findRoom(name));
}
Place* PlacesFile::findPlace(const std::string& name) {
  return const_cast<Place*>(static_cast<const PlacesFile*>(this)->findPlace(name));
}

const Room* PlacesFile::roomAt(double x, double y) const {
  for (const auto& r : rooms)
    if (pointInPolygon(r.polygon, x, y)) return &r;
  return nullptr;
}

const Room* PlacesFile::roomOf(const Place& p) const {
  if (!p.room.empty()) return findRoom(p.room);
  return roomAt(p.x, p.y);
}

namespace {
void checkNewName(const PlacesFile& f, const std::string& name) {
  const std::string bad = nameProblem(name);
  if (!bad.empty()) throw InputError("bad name \"" + name + "\": " + bad);
  if (const Room* r = f.findRoom(name))
    throw InputError("name \"" + name + "\" is taken by room \"" + r->name +
                     "\" (names are case-insensitive; rooms and places share them)");
  if (const Place* p = f.findPlace(name))
    throw InputError("name \"" + name + "\" is taken by place \"" + p->name +
                     "\" (names are case-insensitive; rooms and places share them)");
}

double signedArea(const std::vector<TPoint2D>& poly) {
  double a = 0;
  for (size_t i = 0, n = poly.size(); i < n; ++i)
    a += poly[i].x * poly[(i + 1) % n].y - poly[(i + 1) % n].x * poly[i].y;
  return a / 2;
}
}  // namespace

std::string polygonProblem(const std::vector<TPoint2D>& poly) {
  if (poly.size() < 3) return "a polygon needs at least 3 vertices";
  for (const auto& p : poly)
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) return "a vertex is not a finite number";
  if (std::abs(signedArea(poly)) < 1e-12) return "the polygon has no area";
  return "";
}

void PlacesFile::addRoom(const Room& r) {
  checkNewName(*this, r.name);
  const std::string bad = polygonProblem(r.polygon);
  if (!bad.empty()) throw InputError("room \"" + r.name + "\": " + bad);
  rooms.push_back(r);
}

void PlacesFile::addPlace(const Place& p) {
  checkNewName(*this, p.name);
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.heading_deg))
    throw InputError("place \"" + p.name + "\": the pose is not finite");
  Place q = p;
  if (!p.room.empty()) {
    const Room* r = findRoom(p.room);
    if (!r) throw InputError("place \"" + p.name + "\": no room named \"" + p.room + "\"");
    if (!pointInPolygon(r->polygon, p.x, p.y))
      throw InputError("place \"" + p.name + "\" is not inside room \"" + r->name + "\"");
    q.room = r->name;
  }
  places.push_back(q);
}

void PlacesFile::rename(const std::string& old_name, const std::string& new_name) {
  Room* r = findRoom(old_name);
  Place* p = findPlace(old_name);
  if (!r && !p) throw InputError("no room or place named \"" + old_name + "\"");
  const std::string old_exact = r ? r->name : p->name;
  if (!sameName(old_name, new_name)) checkNewName(*this, new_name);
  const std::string bad = nameProblem(new_name);
  if (!bad.empty()) throw InputError("bad name \"" + new_name + "\": " + bad);
  if (r) {
    r->name = new_name;
    for (auto& q : places)
      if (sameName(q.room, old_exact)) q.room = new_name;
  } else {
    p->name = new_name;
    for (auto& rr : rooms)
      if (sameName(rr.default_place, old_exact)) rr.default_place = new_name;
  }
}

void PlacesFile::remove(const std::string& name) {
  if (const Room* r = findRoom(name)) {
    const std::string exact = r->name;
    for (auto& q : places)
      if (sameName(q.room, exact)) q.room.clear();
    rooms.erase(rooms.begin() + (r - rooms.data()));
    return;
  }
  if (const Place* p = findPlace(name)) {
    const std::string exact = p->name;
    for (auto& rr : rooms)
      if (sameName(rr.default_place, exact)) rr.default_place.clear();
    places.erase(places.begin() + (p - places.data()));
    return;
  }
  throw InputError("no room or place named \"" + name + "\"");
}

WhereResult where(const PlacesFile& f, double x, double y) {
  WhereResult w;
  w.room = f.roomAt(x, y);
  for (const auto& p : f.places) {
    const double d = std::hypot(p.x - x, p.y - y);
    if (!w.nearest || d < w.distance) {
      w.nearest = &p;
      w.distance = d;
    }
  }
  return w;
}

}  // namespace carenav::places
