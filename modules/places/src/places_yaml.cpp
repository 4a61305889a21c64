// The places file: a small YAML subset written and read by hand, so that
// every error names its line (mrpt::containers::yaml keeps no line numbers).
#include <carenav/places/places.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

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

struct Parser {
  std::string file;
  int line = 0;

  [[noreturn]] void fail(const std::string& what, int at = -1) const {
    throw InputError(file + ":" + std::to_string(at < 0 ? line : at) + ": " + what);
  }

  static std::string trim(const std::string& s) {
    const size_t a = s.find_first_not_of(" \t");
    if (a == std::string::npos) return "";
    const size_t b = s.find_last_not_of(" \t\r");
    return s.substr(a, b - a + 1);
  }

  // Removes a comment: '#' at the start or after a blank, outside quotes.
  std::string stripComment(const std::string& s) const {
    char quote = 0;
    for (size_t i = 0; i < s.size(); ++i) {
      const char c = s[i];
      if (quote) {
        if (quote == '"' && c == '\\')
          ++i;
        else if (c == quote)
          quote = 0;
      } else if (c == '"' || c == '\'') {
        quote = c;
      } else if (c == '#' && (i == 0 || s[i - 1] == ' ' || s[i - 1] == '\t')) {
        return s.substr(0, i);
      }
    }
    return s;
  }

  // "key: value" -> (key, value); value may be empty.
  std::pair<std::string, std::string> keyValue(const std::string& s) const {
    const size_t colon = s.find(':');
    if (colon == std::string::npos || colon == 0 ||
        (colon + 1 < s.size() && s[colon + 1] != ' ' && s[colon + 1] != '\t'))
      fail("expected \"key: value\", found \"" + s + "\"");
    const std::string key = trim(s.substr(0, colon));
    if (key.find_first_of(" \t\"'") != std::string::npos) fail("bad key \"" + key + "\"");
    return {key, trim(s.substr(colon + 1))};
  }

  std::string string(const std::string& v, const std::string& key) const {
    if (v.empty()) fail(key + ": a value is required");
    if (v[0] == '"') {
      std::string out;
      size_t i = 1;
      for (; i < v.size() && v[i] != '"'; ++i) {
        if (v[i] == '\\') {
          if (++i >= v.size()) break;
          if (v[i] != '"' && v[i] != '\\')
            fail(key + ": unsupported escape \\" + std::string(1, v[i]) + " (only \\\" and \\\\)");
        }
        out += v[i];
      }
      if (i >= v.size()) fail(key + ": unterminated \"string\"");
      if (i + 1 != v.size()) fail(key + ": text after the closing quote");
      return out;
    }
    if (v[0] == '\'') {
      std::string out;
      size_t i = 1;
      for (; i < v.size(); ++i) {
        if (v[i] == '\'') {
          if (i + 1 < v.size() && v[i + 1] == '\'') {
            out += '\'';
            ++i;
            continue;
          }
          break;
        }
        out += v[i];
      }
      if (i >= v.size()) fail(key + ": unterminated 'string'");
      if (i + 1 != v.size()) fail(key + ": text after the closing quote");
      return out;
    }
    if (std::string("[]{}&*!|>%@`,").find(v[0]) != std::string::npos)
      fail(key + ": a plain string cannot start with '" + v.substr(0, 1) + "'; quote it");
    return v;
  }

  double number(const std::string& v, const std::string& key) const {
    const std::string t = trim(v);
    if (t.empty()) fail(key + ": a number is missing");
    char* end = nullptr;
    errno = 0;
    const double d = std::strtod(t.c_str(), &end);
    if (end != t.c_str() + t.size() || errno == ERANGE || !std::isfinite(d))
      fail(key + ": \"" + t + "\" is not a finite number");
    return d;
  }

  // "[a, b, c]" -> numbers.
  std::vector<double> numberList(const std::string& v, const std::string& key) const {
    if (v.size() < 2 || v.front() != '[' || v.back() != ']')
      fail(key + ": expected a list [a, b, ...], found \"" + v + "\"");
    std::vector<double> out;
    const std::string inner = trim(v.substr(1, v.size() - 2));
    if (inner.empty()) return out;
    std::stringstream ss(inner);
    std::string item;
    while (std::getline(ss, item, ',')) out.push_back(number(item, key));
    if (inner.back() == ',') fail(key + ": a number is missing after the last ','");
    return out;
  }

  // "[[x, y], [x, y], ...]" -> points.
  std::vector<TPoint2D> pointList(const std::string& v, const std::string& key) const {
    if (v.size() < 2 || v.front() != '[' || v.back() != ']')
      fail(key + ": expected [[x, y], [x, y], ...], found \"" + v + "\"");
    std::vector<TPoint2D> out;
    size_t i = 1;
    const size_t end = v.size() - 1;
    while (true) {
      while (i < end && (v[i] == ' ' || v[i] == '\t')) ++i;
      if (i >= end) break;
      if (v[i] != '[') fail(key + ": expected '[' of a point at column " + std::to_string(i + 1));
      const size_t close = v.find(']', i);
      if (close == std::string::npos || close >= end)
        fail(key + ": a point is not closed with ']'");
      const auto xy = numberList(v.substr(i, close - i + 1), key);
      if (xy.size() != 2)
        fail(key + ": a point needs 2 numbers [x, y], found " + std::to_string(xy.size()));
      out.push_back({xy[0], xy[1]});
      i = close + 1;
      while (i < end && (v[i] == ' ' || v[i] == '\t')) ++i;
      if (i < end) {
        if (v[i] != ',') fail(key + ": expected ',' between points");
        ++i;
      }
    }
    return out;
  }
};

// One "- key: value" block while it is read.
struct Item {
  int line = 0;
  std::map<std::string, std::pair<std::string, int>> values;  // key -> (value, line)
};

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

namespace {

enum class Section { None, Rooms, Places };

/** The line pass of a places file: top-level keys and the items of its lists. */
struct PlacesLines {
  explicit PlacesLines(Parser& parser) : ps(parser) {}

  Parser& ps;
  Section section = Section::None;
  std::vector<std::pair<Section, Item>> items;
  bool have_format = false, have_rooms = false, have_places = false, ended = false;
  int dash_indent = -1;

  void readLine(const std::string& raw) {
    ++ps.line;
    if (raw.find('\t') != std::string::npos && raw.find_first_not_of(" \t") != std::string::npos &&
        raw.find('\t') < raw.find_first_not_of(" \t"))
      ps.fail("tab in the indentation; use spaces");
    const std::string body = Parser::trim(ps.stripComment(raw));
    if (body.empty()) return;
    if (ended) ps.fail("text after \"end: true\"");
    const int indent = static_cast<int>(raw.find_first_not_of(' '));
    const bool dash = body == "-" || body.rfind("- ", 0) == 0;
    // Items may start at column 1 under their key, as YAML allows.
    if (indent == 0 && !(dash && section != Section::None))
      readTopKey(body);
    else
      readItemLine(body, indent, dash);
  }

  void readTopKey(const std::string& body) {
    const auto [key, value] = ps.keyValue(body);
    if (key == "format") {
      if (have_format) ps.fail("format is given twice");
      if (ps.line != 1 && (have_rooms || have_places)) ps.fail("format must come first");
      if (value != "1")
        ps.fail("format \"" + value + "\" is not supported (this carenav reads format 1)");
      have_format = true;
      section = Section::None;
    } else if (key == "rooms" || key == "places") {
      readListKey(key, value);
    } else if (key == "end") {
      if (value != "true") ps.fail("end: expected \"true\"");
      if (!have_format) ps.fail("the file must start with \"format: 1\"");
      ended = true;
    } else {
      ps.fail("unknown key \"" + key + "\" (expected format, rooms, places, end)");
    }
  }

  void readListKey(const std::string& key, const std::string& value) {
    if (!have_format) ps.fail("the file must start with \"format: 1\"");
    bool& seen = key == "rooms" ? have_rooms : have_places;
    if (seen) ps.fail(key + " is given twice");
    seen = true;
    if (value == "[]")
      section = Section::None;
    else if (value.empty())
      section = key == "rooms" ? Section::Rooms : Section::Places;
    else
      ps.fail(key + ": expected a list of items below it, or []");
    dash_indent = -1;
  }

  /** A "- key: value" line that starts an item, or a "key: value" line inside one. */
  void readItemLine(const std::string& body, int indent, bool dash) {
    if (section == Section::None)
      ps.fail("indented line outside the rooms or places list: \"" + body + "\"");
    std::string kv = body;
    if (dash) {
      if (dash_indent >= 0 && indent != dash_indent)
        ps.fail("list items must line up with the first one (column " +
                std::to_string(dash_indent + 1) + ")");
      dash_indent = indent;
      items.push_back({section, Item{ps.line, {}}});
      kv = Parser::trim(body.substr(1));
      if (kv.empty()) return;
    } else {
      if (items.empty() || items.back().first != section)
        ps.fail("\"" + body + "\" is not inside a \"- \" list item");
      if (indent <= dash_indent) ps.fail("a key of a list item must be indented past its \"-\"");
    }
    const auto [key, value] = ps.keyValue(kv);
    auto& values = items.back().second.values;
    if (values.count(key)) ps.fail(key + " is given twice in this item");
    values[key] = {value, ps.line};
  }
};

/** The value of a required key of an item (its line becomes the parser's). */
std::pair<std::string, int> need(Parser& ps, Section sec, const Item& item,
                                 const std::string& key) {
  auto it = item.values.find(key);
  if (it == item.values.end())
    ps.fail(std::string(sec == Section::Rooms ? "room" : "place") + " item has no " + key,
            item.line);
  ps.line = it->second.second;
  return it->second;
}

void checkAllowedKeys(const Parser& ps, const Item& item, std::initializer_list<const char*> keys) {
  for (const auto& [k, v] : item.values) {
    bool ok = false;
    for (const char* a : keys) ok = ok || k == a;
    if (!ok) {
      std::string list;
      for (const char* a : keys) list += (list.empty() ? "" : ", ") + std::string(a);
      ps.fail("unknown key \"" + k + "\" (expected " + list + ")", v.second);
    }
  }
}

void addRoomItem(Parser& ps, const Item& item, PlacesFile& f) {
  const Section sec = Section::Rooms;
  checkAllowedKeys(ps, item, {"name", "polygon", "default_place"});
  Room r;
  r.line = item.line;
  r.name = ps.string(need(ps, sec, item, "name").first, "name");
  r.polygon = ps.pointList(need(ps, sec, item, "polygon").first, "polygon");
  if (item.values.count("default_place"))
    r.default_place = ps.string(need(ps, sec, item, "default_place").first, "default_place");
  try {
    f.addRoom(r);
  } catch (const InputError& e) {
    ps.fail(e.what(), item.line);
  }
}

void addPlaceItem(Parser& ps, const Item& item, PlacesFile& f) {
  const Section sec = Section::Places;
  checkAllowedKeys(ps, item, {"name", "pose", "kind", "room"});
  Place p;
  p.line = item.line;
  p.name = ps.string(need(ps, sec, item, "name").first, "name");
  const auto pose = ps.numberList(need(ps, sec, item, "pose").first, "pose");
  if (pose.size() != 3) ps.fail("pose: expected [x, y, heading_deg]");
  p.x = pose[0];
  p.y = pose[1];
  p.heading_deg = pose[2];
  if (item.values.count("kind")) {
    const std::string k = ps.string(need(ps, sec, item, "kind").first, "kind");
    const auto kind = parsePlaceKind(k);
    if (!kind) ps.fail("kind \"" + k + "\": expected place, user-search, object-search or dock");
    p.kind = *kind;
  }
  if (item.values.count("room")) p.room = ps.string(need(ps, sec, item, "room").first, "room");
  // Room membership is checked by `places check`, not here: a file whose
  // rooms were redrawn must still load so that it can be fixed.
  const std::string room = p.room;
  p.room.clear();
  try {
    f.addPlace(p);
  } catch (const InputError& e) {
    ps.fail(e.what(), item.line);
  }
  f.places.back().room = room;
}

}  // namespace

PlacesFile parsePlaces(const std::string& text, const std::string& origin) {
  Parser ps{origin};
  if (text.find_first_not_of(" \t\r\n") == std::string::npos) ps.fail("the file is empty", 1);
  PlacesLines lines(ps);
  std::stringstream ss(text);
  std::string raw;
  while (std::getline(ss, raw)) lines.readLine(raw);
  if (!lines.have_format) ps.fail("no \"format: 1\" line", 1);
  if (!lines.ended)
    ps.fail("the file does not end with \"end: true\": it is truncated or incomplete", ps.line);
  PlacesFile f;
  for (const auto& [sec, item] : lines.items) {
    if (sec == Section::Rooms)
      addRoomItem(ps, item, f);
    else
      addPlaceItem(ps, item, f);
  }
  return f;
}

PlacesFile readPlacesFile(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(path + ": no such file");
  if (std::filesystem::is_directory(path, ec)) throw InputError(path + ": is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot be read");
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
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
