#include <carenav/common/file.h>
#include <carenav/common/text.h>
#include <carenav/io/map_io.h>
#include <carenav/sim/world.h>

#include <carenav/common/yaml.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace carenav::sim {

namespace fs = std::filesystem;
constexpr float kInf = std::numeric_limits<float>::infinity();

const char* Feature::kindName(Kind k) {
  switch (k) {
    case Kind::Step:
      return "step";
    case Kind::Hole:
      return "hole";
    case Kind::Gutter:
      return "gutter";
    case Kind::Stairs:
      return "stairs";
    case Kind::Ramp:
      return "ramp";
    case Kind::Table:
      return "table";
  }
  return "?";
}

Vec2 Person::at(double t) const {
  if (path.empty()) return {};
  if (path.size() == 1 || speed <= 0) return path.front();
  // Legs of the walk: path, plus the closing leg when looping.
  std::vector<double> len;
  double total = 0;
  const size_t n = path.size();
  const size_t legs = loop ? n : n - 1;
  for (size_t i = 0; i < legs; ++i) {
    const Vec2& a = path[i];
    const Vec2& b = path[(i + 1) % n];
    len.push_back(std::hypot(b.x - a.x, b.y - a.y));
    total += len.back();
  }
  if (total <= 0) return path.front();
  double s = speed * std::max(0.0, t);
  if (loop)
    s = std::fmod(s, total);
  else if (s >= total)
    return path.back();
  for (size_t i = 0; i < legs; ++i) {
    if (s <= len[i] || i + 1 == legs) {
      const Vec2& a = path[i];
      const Vec2& b = path[(i + 1) % n];
      const double u = len[i] > 0 ? std::min(1.0, s / len[i]) : 0;
      return {a.x + u * (b.x - a.x), a.y + u * (b.y - a.y)};
    }
    s -= len[i];
  }
  return path.back();
}

bool pointInPolygon(const std::vector<Vec2>& poly, double x, double y) {
  bool in = false;
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const Vec2& a = poly[i];
    const Vec2& b = poly[j];
    if (((a.y > y) != (b.y > y)) && (x < (b.x - a.x) * (y - a.y) / (b.y - a.y) + a.x)) in = !in;
  }
  return in;
}

World::World(mrpt::maps::COccupancyGridMap2D grid, std::vector<Feature> features,
             std::vector<Person> people, double wall_height)
    : grid_(std::move(grid)),
      features_(std::move(features)),
      people_(std::move(people)),
      wall_height_(wall_height) {
  nx_ = static_cast<int>(grid_.getSizeX());
  ny_ = static_cast<int>(grid_.getSizeY());
  res_ = grid_.getResolution();
  x0_ = grid_.getXMin();
  y0_ = grid_.getYMin();
  rasterise();
  computeClearance();
}

namespace {
/** floor(d) as a cell index, clamped to [-1, n] (outside the grid either
 *  way) so that a far-away or non-finite coordinate never overflows an int. */
int cellIndex(double d, int n) {
  const double c = std::floor(d);
  if (!(c >= -1)) return -1;
  return c > n ? n : static_cast<int>(c);
}
}  // namespace

int World::cellX(double x) const { return cellIndex((x - x0_) / res_, nx_); }
int World::cellY(double y) const { return cellIndex((y - y0_) / res_, ny_); }

double World::floorAt(double x, double y) const {
  const int cx = cellX(x), cy = cellY(y);
  if (!inside(cx, cy)) return 0;
  return cell(cx, cy).floor;
}

void World::rasterise() {
  cells_.assign(static_cast<size_t>(nx_) * ny_, Cell{});
  const io::OccupancyThresholds th;
  for (int cy = 0; cy < ny_; ++cy)
    for (int cx = 0; cx < nx_; ++cx)
      if (io::classifyCell(grid_.getCell(cx, cy), th) == io::CellClass::Occupied)
        cells_[static_cast<size_t>(cy) * nx_ + cx].floor = kInf;
  for (const Feature& f : features_) {
    double bx0 = 1e300, by0 = 1e300, bx1 = -1e300, by1 = -1e300;
    double s0 = 1e300, s1 = -1e300;
    for (const auto& v : f.polygon) {
      bx0 = std::min(bx0, v.x), by0 = std::min(by0, v.y);
      bx1 = std::max(bx1, v.x), by1 = std::max(by1, v.y);
      const double s = v.x * f.axis.x + v.y * f.axis.y;
      s0 = std::min(s0, s), s1 = std::max(s1, s);
    }
    const int cx0 = std::max(0, cellX(bx0)), cx1 = std::min(nx_ - 1, cellX(bx1));
    const int cy0 = std::max(0, cellY(by0)), cy1 = std::min(ny_ - 1, cellY(by1));
    // table legs: squares of side `leg` in the corners of the bounding box
    auto inLeg = [&](double x, double y) {
      if (f.leg <= 0) return false;
      const bool nx = x < bx0 + f.leg || x > bx1 - f.leg;
      const bool ny = y < by0 + f.leg || y > by1 - f.leg;
      return nx && ny;
    };
    for (int cy = cy0; cy <= cy1; ++cy)
      for (int cx = cx0; cx <= cx1; ++cx) {
        const double x = x0_ + (cx + 0.5) * res_, y = y0_ + (cy + 0.5) * res_;
        if (!pointInPolygon(f.polygon, x, y)) continue;
        Cell& c = cells_[static_cast<size_t>(cy) * nx_ + cx];
        if (c.wall()) continue;  // the map's walls win
        const double u = s1 > s0 ? ((x * f.axis.x + y * f.axis.y) - s0) / (s1 - s0) : 0;
        switch (f.kind) {
          case Feature::Kind::Step:
          case Feature::Kind::Hole:
          case Feature::Kind::Gutter:
            c.floor = static_cast<float>(f.height);
            break;
          case Feature::Kind::Stairs: {
            const int i = std::min(f.steps - 1, static_cast<int>(std::floor(u * f.steps)));
            c.floor = static_cast<float>((i + 1) * f.rise);
            break;
          }
          case Feature::Kind::Ramp:
            c.floor = static_cast<float>(u * f.rise);
            break;
          case Feature::Kind::Table:
            if (inLeg(x, y)) {
              c.floor = static_cast<float>(f.height);
            } else {
              c.slab_lo = static_cast<float>(f.height - f.thickness);
              c.slab_hi = static_cast<float>(f.height);
            }
            break;
        }
      }
  }
}

void World::computeClearance() {
  // Chebyshev distance transform (two passes), capped at 255.
  clear_.assign(cells_.size(), 255);
  auto at = [&](int x, int y) -> uint8_t& { return clear_[static_cast<size_t>(y) * nx_ + x]; };
  for (int y = 0; y < ny_; ++y)
    for (int x = 0; x < nx_; ++x)
      if (!cell(x, y).plain()) at(x, y) = 0;
  for (int y = 0; y < ny_; ++y)
    for (int x = 0; x < nx_; ++x) {
      int v = at(x, y);
      if (x > 0) v = std::min(v, at(x - 1, y) + 1);
      if (y > 0) {
        v = std::min(v, at(x, y - 1) + 1);
        if (x > 0) v = std::min(v, at(x - 1, y - 1) + 1);
        if (x + 1 < nx_) v = std::min(v, at(x + 1, y - 1) + 1);
      }
      at(x, y) = static_cast<uint8_t>(std::min(v, 255));
    }
  for (int y = ny_ - 1; y >= 0; --y)
    for (int x = nx_ - 1; x >= 0; --x) {
      int v = at(x, y);
      if (x + 1 < nx_) v = std::min(v, at(x + 1, y) + 1);
      if (y + 1 < ny_) {
        v = std::min(v, at(x, y + 1) + 1);
        if (x + 1 < nx_) v = std::min(v, at(x + 1, y + 1) + 1);
        if (x > 0) v = std::min(v, at(x - 1, y + 1) + 1);
      }
      at(x, y) = static_cast<uint8_t>(std::min(v, 255));
    }
}

// ------------------------------------------------------------ world files

namespace {

using yaml::Node;

struct Reader {
  std::string file;

  [[noreturn]] void fail(int line, const std::string& what) const {
    throw InputError(file + ":" + std::to_string(line) + ": " + what);
  }

  double number(const Node& n, const std::string& what) const {
    if (n.kind != Node::Kind::Scalar || n.quoted) fail(n.line, what + ": expected a number");
    const auto v = parseNumber(n.scalar);
    if (!v) fail(n.line, what + ": '" + n.scalar + "' is not a number");
    return *v;
  }
  double number(const Node& n, const std::string& what, double lo, double hi) const {
    const double v = number(n, what);
    if (v < lo || v > hi) {
      std::ostringstream o;
      o << what << ": " << n.scalar << " is out of range [" << lo << ", " << hi << "]";
      fail(n.line, o.str());
    }
    return v;
  }
  bool boolean(const Node& n, const std::string& what) const {
    if (n.kind == Node::Kind::Scalar && !n.quoted) {
      if (n.scalar == "true" || n.scalar == "yes") return true;
      if (n.scalar == "false" || n.scalar == "no") return false;
    }
    fail(n.line, what + ": expected true or false");
  }
  std::string text(const Node& n, const std::string& what) const {
    if (n.kind != Node::Kind::Scalar || n.scalar.empty()) fail(n.line, what + ": expected text");
    return n.scalar;
  }
  Vec2 point(const Node& n, const std::string& what) const {
    if (n.kind != Node::Kind::Seq || n.seq.size() != 2)
      fail(n.line, what + ": expected a point [x, y]");
    return {number(n.seq[0], what, -kMaxCoordinate, kMaxCoordinate),
            number(n.seq[1], what, -kMaxCoordinate, kMaxCoordinate)};
  }
  std::vector<Vec2> points(const Node& n, const std::string& what, size_t min_count) const {
    if (n.kind != Node::Kind::Seq) fail(n.line, what + ": expected a list of points [[x, y], ...]");
    if (n.seq.size() > kMaxPoints)
      fail(n.line, what + ": " + std::to_string(n.seq.size()) + " points, at most " +
                       std::to_string(kMaxPoints));
    std::vector<Vec2> out;
    for (const auto& p : n.seq) out.push_back(point(p, what));
    if (out.size() < min_count)
      fail(n.line, what + ": needs at least " + std::to_string(min_count) + " points");
    return out;
  }
  void onlyKeys(const Node& m, const std::set<std::string>& allowed,
                const std::string& where) const {
    for (size_t i = 0; i < m.map.size(); ++i)
      if (!allowed.count(m.map[i].first)) {
        std::string list;
        for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
        fail(m.key_lines[i],
             "unknown key '" + m.map[i].first + "' in " + where + " (allowed: " + list + ")");
      }
  }
  const Node& need(const Node& m, const std::string& key, const std::string& where) const {
    const Node* n = m.find(key);
    if (!n) fail(m.line, where + ": missing key '" + key + "'");
    if (n->kind == Node::Kind::Scalar && n->scalar.empty() && !n->quoted)
      fail(n->line, where + ": '" + key + "' has no value");
    return *n;
  }
  const Node* opt(const Node& m, const std::string& key) const {
    const Node* n = m.find(key);
    if (n && n->kind == Node::Kind::Scalar && n->scalar.empty() && !n->quoted)
      fail(n->line, "'" + key + "' has no value");
    return n;
  }

  Feature feature(const Node& m, size_t index) const {
    const std::string where = "features[" + std::to_string(index) + "]";
    if (m.kind != Node::Kind::Map) fail(m.line, where + ": expected 'type: ...' and its keys");
    Feature f;
    const std::string type = text(need(m, "type", where), where + ".type");
    std::set<std::string> keys{"type", "rect", "polygon", "name"};
    if (type == "step") {
      f.kind = Feature::Kind::Step;
      keys.insert("height");
    } else if (type == "hole" || type == "gutter") {
      f.kind = type == "hole" ? Feature::Kind::Hole : Feature::Kind::Gutter;
      keys.insert("depth");
    } else if (type == "stairs") {
      f.kind = Feature::Kind::Stairs;
      keys.insert({"direction", "steps", "rise"});
    } else if (type == "ramp") {
      f.kind = Feature::Kind::Ramp;
      keys.insert({"direction", "rise"});
    } else if (type == "table") {
      f.kind = Feature::Kind::Table;
      keys.insert({"height", "thickness", "leg"});
    } else {
      fail(m.find("type")->line,
           where + ".type: '" + type + "' is not one of step, hole, gutter, stairs, ramp, table");
    }
    onlyKeys(m, keys, where + " (" + type + ")");
    const Node* rect = opt(m, "rect");
    const Node* poly = opt(m, "polygon");
    if ((rect != nullptr) == (poly != nullptr))
      fail(m.line, where + ": give exactly one of 'rect: [x0, y0, x1, y1]' and 'polygon'");
    if (rect) {
      if (rect->kind != Node::Kind::Seq || rect->seq.size() != 4)
        fail(rect->line, where + ".rect: expected [x0, y0, x1, y1]");
      double c[4];
      for (int k = 0; k < 4; ++k)
        c[k] = number(rect->seq[k], where + ".rect", -kMaxCoordinate, kMaxCoordinate);
      const double x0 = c[0], y0 = c[1], x1 = c[2], y1 = c[3];
      if (!(x1 > x0 && y1 > y0)) fail(rect->line, where + ".rect: needs x1 > x0 and y1 > y0");
      f.polygon = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
    } else {
      f.polygon = points(*poly, where + ".polygon", 3);
    }
    switch (f.kind) {
      case Feature::Kind::Step:
        f.height = number(need(m, "height", where), where + ".height", -5, 5);
        break;
      case Feature::Kind::Hole:
      case Feature::Kind::Gutter:
        f.height = -number(need(m, "depth", where), where + ".depth", 0.001, 100);
        break;
      case Feature::Kind::Stairs:
      case Feature::Kind::Ramp: {
        const double deg = number(need(m, "direction", where), where + ".direction", -360, 360);
        f.axis = {std::cos(deg * M_PI / 180), std::sin(deg * M_PI / 180)};
        f.rise = number(need(m, "rise", where), where + ".rise", -5, 5);
        if (f.kind == Feature::Kind::Stairs) {
          const double s = number(need(m, "steps", where), where + ".steps", 1, 100);
          if (s != std::floor(s))
            fail(m.find("steps")->line, where + ".steps: expected a whole number");
          f.steps = static_cast<int>(s);
        }
        break;
      }
      case Feature::Kind::Table:
        f.height = number(need(m, "height", where), where + ".height", 0.05, 5);
        if (const Node* t = opt(m, "thickness"))
          f.thickness = number(*t, where + ".thickness", 0.001, f.height);
        if (const Node* l = opt(m, "leg")) f.leg = number(*l, where + ".leg", 0, 1);
        break;
    }
    return f;
  }

  Person person(const Node& m, size_t index) const {
    const std::string where = "people[" + std::to_string(index) + "]";
    if (m.kind != Node::Kind::Map) fail(m.line, where + ": expected 'path: ...' and its keys");
    onlyKeys(m, {"radius", "height", "speed", "loop", "path", "name"}, where);
    Person p;
    if (const Node* n = opt(m, "radius")) p.radius = number(*n, where + ".radius", 0.01, 5);
    if (const Node* n = opt(m, "height")) p.height = number(*n, where + ".height", 0.01, 5);
    if (const Node* n = opt(m, "speed")) p.speed = number(*n, where + ".speed", 0, 10);
    if (const Node* n = opt(m, "loop")) p.loop = boolean(*n, where + ".loop");
    p.path = points(need(m, "path", where), where + ".path", 1);
    return p;
  }
};

std::string slurp(const std::string& path) {
  return readWholeFile(path, {"no such world file", "is a folder, not a world file",
                              "cannot read the world file", "a world file"});
}

}  // namespace

World worldFromText(const std::string& text, const std::string& origin, const std::string& base_dir,
                    double default_wall_height) {
  Reader r{origin};
  const Node root = yaml::parse(text, origin);
  if (root.kind != Node::Kind::Map)
    r.fail(root.line, "expected 'map: ...' and the other world keys");
  r.onlyKeys(root,
             {"format", "map", "resolution", "origin", "negate", "wall_height", "features",
              "people", "name", "description"},
             "the world file");
  if (const Node* fmt = r.opt(root, "format"))
    if (r.number(*fmt, "format") != 1) r.fail(fmt->line, "format: only format 1 is known");
  const Node& mapNode = r.need(root, "map", "the world file");
  const std::string map_rel = r.text(mapNode, "map");
  const fs::path map_path =
      fs::path(map_rel).is_absolute() ? fs::path(map_rel) : fs::path(base_dir) / map_rel;
  std::error_code ec;
  if (!fs::exists(map_path, ec))
    r.fail(mapNode.line, "map: '" + map_path.string() + "' does not exist");
  io::MapLoadOptions mo;
  if (const Node* n = r.opt(root, "resolution"))
    mo.image_resolution = r.number(*n, "resolution", 1e-4, 100);
  if (const Node* n = r.opt(root, "origin")) {
    const Vec2 o = r.point(*n, "origin");
    mo.image_origin_x = o.x;
    mo.image_origin_y = o.y;
  }
  if (const Node* n = r.opt(root, "negate")) mo.image_negate = r.boolean(*n, "negate");
  const auto kind = io::mapKindOf(map_path.string());
  if (kind == io::MapKind::Image && !mo.image_resolution)
    r.fail(mapNode.line, "map: an image map needs 'resolution: <m per pixel>' in the world file");
  double wall_height = default_wall_height;
  if (const Node* n = r.opt(root, "wall_height"))
    wall_height = r.number(*n, "wall_height", 0.1, 100);
  mrpt::maps::COccupancyGridMap2D grid;
  try {
    grid = io::loadGridMap(map_path.string(), mo);
  } catch (const InputError& e) {
    r.fail(mapNode.line, std::string("map: ") + e.what());
  }
  std::vector<Feature> features;
  if (const Node* fs_ = r.opt(root, "features")) {
    if (fs_->kind != Node::Kind::Seq)
      r.fail(fs_->line, "features: expected a list ('- type: ...')");
    if (fs_->seq.size() > kMaxFeatures)
      r.fail(fs_->line, "features: " + std::to_string(fs_->seq.size()) + " features, at most " +
                            std::to_string(kMaxFeatures));
    for (size_t i = 0; i < fs_->seq.size(); ++i) features.push_back(r.feature(fs_->seq[i], i));
  }
  std::vector<Person> people;
  if (const Node* ps = r.opt(root, "people")) {
    if (ps->kind != Node::Kind::Seq) r.fail(ps->line, "people: expected a list ('- path: ...')");
    if (ps->seq.size() > kMaxPeople)
      r.fail(ps->line, "people: " + std::to_string(ps->seq.size()) + " people, at most " +
                           std::to_string(kMaxPeople));
    for (size_t i = 0; i < ps->seq.size(); ++i) people.push_back(r.person(ps->seq[i], i));
  }
  World w(std::move(grid), std::move(features), std::move(people), wall_height);
  w.source = origin;
  return w;
}

World loadWorld(const std::string& yaml_path, double default_wall_height) {
  const std::string text = slurp(yaml_path);
  std::string base = fs::path(yaml_path).parent_path().string();
  if (base.empty()) base = ".";
  return worldFromText(text, yaml_path, base, default_wall_height);
}

}  // namespace carenav::sim
