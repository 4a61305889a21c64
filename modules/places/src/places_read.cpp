// Reading a places file (docs/places.md): the YAML goes through the common
// reader (yaml-cpp, lines kept); this file checks the format's own rules.
// Two of them are about the text rather than the YAML: the file starts with
// "format: 1" and ends with "end: true", so that a cut-off file is reported
// as truncated, whatever the cut left behind.
#include <carenav/common/params.h>
#include <carenav/common/yaml.h>
#include <carenav/places/places.h>

#include <initializer_list>
#include <string>
#include <vector>

namespace carenav::places {

namespace {

using yaml::Node;

class Reader {
 public:
  explicit Reader(const std::string& origin) : origin_(origin) {}

  [[noreturn]] void fail(int line, const std::string& what) const {
    throw InputError(origin_ + ":" + std::to_string(line) + ": " + what);
  }

  std::string string(const Node& n, const std::string& key) const {
    if (n.kind != Node::Kind::Scalar)
      fail(n.line, key + ": expected a string, found a " +
                       (n.kind == Node::Kind::Seq ? "list" : "mapping") + " (quote it)");
    if (n.scalar.empty() && !n.quoted) fail(n.line, key + ": a value is required");
    return n.scalar;
  }

  double number(const Node& n, const std::string& key) const {
    if (n.kind != Node::Kind::Scalar) fail(n.line, key + ": expected a number, found a list");
    if (n.scalar.empty() && !n.quoted) fail(n.line, key + ": a number is missing");
    try {
      if (!n.quoted) return parseReal(n.scalar);
    } catch (const std::exception&) {
    }
    fail(n.line, key + ": \"" + n.scalar + "\" is not a finite number");
  }

  std::vector<double> numbers(const Node& n, const std::string& key) const {
    if (n.kind != Node::Kind::Seq)
      fail(n.line, key + ": expected a list [a, b, ...], found \"" + n.scalar + "\"");
    std::vector<double> out;
    for (const Node& item : n.seq) out.push_back(number(item, key));
    return out;
  }

  std::vector<TPoint2D> points(const Node& n, const std::string& key) const {
    if (n.kind != Node::Kind::Seq)
      fail(n.line, key + ": expected [[x, y], [x, y], ...], found \"" + n.scalar + "\"");
    std::vector<TPoint2D> out;
    for (const Node& p : n.seq) {
      if (p.kind != Node::Kind::Seq)
        fail(p.line, key + ": expected [[x, y], [x, y], ...], a point is \"" + p.scalar + "\"");
      const auto xy = numbers(p, key);
      if (xy.size() != 2)
        fail(p.line, key + ": a point needs 2 numbers [x, y], found " + std::to_string(xy.size()));
      out.push_back({xy[0], xy[1]});
    }
    return out;
  }

 private:
  std::string origin_;
};

/** One "- key: value ..." item of the rooms or places list. */
class Item {
 public:
  Item(const Reader& rd, const Node& n, const char* what) : rd_(rd), n_(n), what_(what) {
    if (n.kind == Node::Kind::Scalar && !n.scalar.empty())
      rd.fail(n.line, "expected \"key: value\", found \"" + n.scalar + "\"");
    if (n.kind == Node::Kind::Seq) rd.fail(n.line, "expected \"key: value\", found a list");
    for (size_t i = 0; i < n.map.size(); ++i)
      for (size_t j = 0; j < i; ++j)
        if (n.map[j].first == n.map[i].first)
          rd.fail(n.key_lines[i], n.map[i].first + " is given twice in this item");
  }

  int line() const { return n_.line; }
  const Node* get(const char* key) const { return n_.find(key); }
  const Node& need(const char* key) const {
    if (const Node* v = get(key)) return *v;
    rd_.fail(n_.line, std::string(what_) + " item has no " + key);
  }

  void allow(std::initializer_list<const char*> keys) const {
    for (size_t i = 0; i < n_.map.size(); ++i) {
      bool ok = false;
      for (const char* a : keys) ok = ok || n_.map[i].first == a;
      if (ok) continue;
      std::string list;
      for (const char* a : keys) list += (list.empty() ? "" : ", ") + std::string(a);
      rd_.fail(n_.key_lines[i], "unknown key \"" + n_.map[i].first + "\" (expected " + list + ")");
    }
  }

 private:
  const Reader& rd_;
  const Node& n_;
  const char* what_;
};

void addRoom(const Reader& rd, const Node& n, PlacesFile& f) {
  const Item item(rd, n, "room");
  item.allow({"name", "polygon", "default_place"});
  Room r;
  r.line = item.line();
  r.name = rd.string(item.need("name"), "name");
  r.polygon = rd.points(item.need("polygon"), "polygon");
  if (const Node* d = item.get("default_place")) r.default_place = rd.string(*d, "default_place");
  try {
    f.addRoom(r);
  } catch (const InputError& e) {
    rd.fail(item.line(), e.what());
  }
}

void addPlace(const Reader& rd, const Node& n, PlacesFile& f) {
  const Item item(rd, n, "place");
  item.allow({"name", "pose", "kind", "room"});
  Place p;
  p.line = item.line();
  p.name = rd.string(item.need("name"), "name");
  const Node& pose_node = item.need("pose");
  const auto pose = rd.numbers(pose_node, "pose");
  if (pose.size() != 3) rd.fail(pose_node.line, "pose: expected [x, y, heading_deg]");
  p.x = pose[0];
  p.y = pose[1];
  p.heading_deg = pose[2];
  if (const Node* k = item.get("kind")) {
    const std::string name = rd.string(*k, "kind");
    const auto kind = parsePlaceKind(name);
    if (!kind)
      rd.fail(k->line, "kind \"" + name + "\": expected place, user-search, object-search or dock");
    p.kind = *kind;
  }
  const std::string room = item.get("room") ? rd.string(*item.get("room"), "room") : "";
  // Room membership is checked by `places check`, not here: a file whose
  // rooms were redrawn must still load so that it can be fixed.
  try {
    f.addPlace(p);
  } catch (const InputError& e) {
    rd.fail(item.line(), e.what());
  }
  f.places.back().room = room;
}

/** The lines with something on them (comments and blanks dropped). */
struct TextLine {
  int number;
  bool top;  // starts in column 1
  std::string text;
};

std::vector<TextLine> contentLines(const std::string& text, int& count) {
  std::vector<TextLine> out;
  count = 0;
  size_t pos = 0;
  while (pos < text.size()) {
    size_t e = text.find('\n', pos);
    if (e == std::string::npos) e = text.size();
    const std::string raw = text.substr(pos, e - pos);
    ++count;
    pos = e + 1;
    const size_t hash = raw.find(" #"), a = raw.find_first_not_of(" \t\r");
    const std::string body = raw.substr(0, hash);
    const size_t b = body.find_last_not_of(" \t\r");
    if (a == std::string::npos || raw[a] == '#' || b == std::string::npos || b < a) continue;
    out.push_back({count, a == 0, body.substr(a, b - a + 1)});
  }
  return out;
}

/** "format: 1" first, "end: true" last, nothing after it. */
void checkFrame(const Reader& rd, const std::vector<TextLine>& lines, int count) {
  if (lines.empty()) rd.fail(1, "no \"format: 1\" line");
  const TextLine& first = lines.front();
  if (!first.top || first.text.rfind("format:", 0) != 0)
    rd.fail(first.number, "the file must start with \"format: 1\"");
  const std::string v =
      first.text.substr(first.text.find_first_not_of(" \t", 7) == std::string::npos
                            ? first.text.size()
                            : first.text.find_first_not_of(" \t", 7));
  if (v != "1")
    rd.fail(first.number, "format \"" + v + "\" is not supported (this carenav reads format 1)");
  for (size_t i = 0; i < lines.size(); ++i) {
    if (!lines[i].top || lines[i].text.rfind("end:", 0) != 0) continue;
    if (lines[i].text != "end: true") rd.fail(lines[i].number, "end: expected \"true\"");
    if (i + 1 < lines.size()) rd.fail(lines[i + 1].number, "text after \"end: true\"");
    return;
  }
  rd.fail(count, "the file does not end with \"end: true\": it is truncated or incomplete");
}

/** The items of "rooms:" or "places:" ("[]" or nothing: none). */
const std::vector<Node>& listOf(const Reader& rd, const std::string& key, const Node& v, int line) {
  static const std::vector<Node> none;
  if (v.kind == Node::Kind::Seq) return v.seq;
  if (v.kind == Node::Kind::Map)
    rd.fail(v.line, "\"" + v.map[0].first + ": " + v.map[0].second.scalar +
                        "\" is not inside a \"- \" list item");
  if (!v.scalar.empty() || v.quoted)
    rd.fail(line, key + ": expected a list of items below it, or []");
  return none;
}

}  // namespace

PlacesFile parsePlaces(const std::string& text, const std::string& origin) {
  const Reader rd(origin);
  if (text.find_first_not_of(" \t\r\n") == std::string::npos) rd.fail(1, "the file is empty");
  int count = 0;
  const std::vector<TextLine> lines = contentLines(text, count);
  checkFrame(rd, lines, count);
  const Node root = yaml::parse(text, origin, yaml::Duplicates::Keep);
  std::vector<std::pair<bool, const Node*>> items;  // (is a room, item) in file order
  bool seen_rooms = false, seen_places = false, seen_format = false;
  for (size_t i = 0; i < root.map.size(); ++i) {
    const auto& [key, value] = root.map[i];
    const int line = root.key_lines[i];
    if (key == "format" || key == "end") {
      if (key == "format" && seen_format) rd.fail(line, "format is given twice");
      seen_format = true;
    } else if (key == "rooms" || key == "places") {
      bool& seen = key == "rooms" ? seen_rooms : seen_places;
      if (seen) rd.fail(line, key + " is given twice");
      seen = true;
      for (const Node& n : listOf(rd, key, value, line)) items.push_back({key == "rooms", &n});
    } else {
      rd.fail(line, "unknown key \"" + key + "\" (expected format, rooms, places, end)");
    }
  }
  PlacesFile f;
  for (const auto& [is_room, n] : items) is_room ? addRoom(rd, *n, f) : addPlace(rd, *n, f);
  return f;
}

}  // namespace carenav::places
