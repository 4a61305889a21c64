// Rooms and places against the occupancy grid: checks, goals, pictures.
#include <carenav/common/distance_transform.h>
#include <carenav/common/text.h>
#include <carenav/places/places.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace carenav::places {

namespace {

using io::CellClass;

struct CellRange {
  int x0 = 0, y0 = 0, x1 = -1, y1 = -1;  // inclusive; empty when x1 < x0
};

// Cells of the map whose centres may lie inside the polygon.
CellRange cellsUnder(const COccupancyGridMap2D& map, const std::vector<TPoint2D>& poly) {
  double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300;
  for (const auto& p : poly) {
    xmin = std::min(xmin, p.x), xmax = std::max(xmax, p.x);
    ymin = std::min(ymin, p.y), ymax = std::max(ymax, p.y);
  }
  const double res = map.getResolution();
  CellRange c;
  c.x0 = std::max(0, static_cast<int>(std::floor((xmin - map.getXMin()) / res)));
  c.y0 = std::max(0, static_cast<int>(std::floor((ymin - map.getYMin()) / res)));
  c.x1 = std::min(static_cast<int>(map.getSizeX()) - 1,
                  static_cast<int>(std::floor((xmax - map.getXMin()) / res)));
  c.y1 = std::min(static_cast<int>(map.getSizeY()) - 1,
                  static_cast<int>(std::floor((ymax - map.getYMin()) / res)));
  return c;
}

double cellX(const COccupancyGridMap2D& m, int cx) {
  return m.getXMin() + (cx + 0.5) * m.getResolution();
}
double cellY(const COccupancyGridMap2D& m, int cy) {
  return m.getYMin() + (cy + 0.5) * m.getResolution();
}

// Cell holding (x, y), or false when outside the map.
bool cellOf(const COccupancyGridMap2D& m, double x, double y, int& cx, int& cy) {
  cx = static_cast<int>(std::floor((x - m.getXMin()) / m.getResolution()));
  cy = static_cast<int>(std::floor((y - m.getYMin()) / m.getResolution()));
  return cx >= 0 && cy >= 0 && cx < static_cast<int>(m.getSizeX()) &&
         cy < static_cast<int>(m.getSizeY());
}

CellClass classAt(const COccupancyGridMap2D& m, int cx, int cy, const io::OccupancyThresholds& t) {
  return io::classifyCell(m.getCell(cx, cy), t);
}

bool strictlyInside(const std::vector<TPoint2D>& poly, double x, double y) {
  return pointInPolygon(poly, x, y) && !pointOnBoundary(poly, x, y, 1e-9);
}

double cross(const TPoint2D& o, const TPoint2D& a, const TPoint2D& b) {
  return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

// Segments cross at one point interior to both (touching does not count).
bool properlyCross(const TPoint2D& a, const TPoint2D& b, const TPoint2D& c, const TPoint2D& d) {
  const double d1 = cross(c, d, a), d2 = cross(c, d, b), d3 = cross(a, b, c), d4 = cross(a, b, d);
  return ((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0));
}

bool selfIntersecting(const std::vector<TPoint2D>& p) {
  const size_t n = p.size();
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 2; j < n; ++j) {
      if (i == 0 && j == n - 1) continue;  // neighbours through the closing edge
      if (properlyCross(p[i], p[(i + 1) % n], p[j], p[(j + 1) % n])) return true;
    }
  return false;
}

bool roomsOverlap(const Room& a, const Room& b, const COccupancyGridMap2D& map) {
  const auto& pa = a.polygon;
  const auto& pb = b.polygon;
  for (size_t i = 0; i < pa.size(); ++i)
    for (size_t j = 0; j < pb.size(); ++j)
      if (properlyCross(pa[i], pa[(i + 1) % pa.size()], pb[j], pb[(j + 1) % pb.size()]))
        return true;
  for (const auto& v : pa)
    if (strictlyInside(pb, v.x, v.y)) return true;
  for (const auto& v : pb)
    if (strictlyInside(pa, v.x, v.y)) return true;
  // Rooms that share edges and overlap only between vertices: look for a
  // cell centre strictly inside both.
  const CellRange c = cellsUnder(map, pa);
  for (int cy = c.y0; cy <= c.y1; ++cy)
    for (int cx = c.x0; cx <= c.x1; ++cx) {
      const double x = cellX(map, cx), y = cellY(map, cy);
      if (strictlyInside(pa, x, y) && strictlyInside(pb, x, y)) return true;
    }
  return false;
}

std::string fmt(double v) { return formatFixed(v, 2); }

const char* className(CellClass c) {
  return c == CellClass::Occupied ? "occupied" : c == CellClass::Unknown ? "unknown" : "free";
}

}  // namespace

std::vector<Problem> checkPlaces(const PlacesFile& f, const COccupancyGridMap2D& map,
                                 const CheckParams& params) {
  std::vector<Problem> out;
  auto add = [&](const std::string& kind, const std::string& what) { out.push_back({kind, what}); };

  for (const auto& r : f.rooms) {
    if (selfIntersecting(r.polygon))
      add("room-self-intersecting", "room \"" + r.name + "\": its polygon crosses itself");
    bool any_free = false;
    const CellRange c = cellsUnder(map, r.polygon);
    for (int cy = c.y0; cy <= c.y1 && !any_free; ++cy)
      for (int cx = c.x0; cx <= c.x1 && !any_free; ++cx)
        any_free = pointInPolygon(r.polygon, cellX(map, cx), cellY(map, cy)) &&
                   classAt(map, cx, cy, params.thresholds) == CellClass::Free;
    if (!any_free)
      add("room-no-free-cell", "room \"" + r.name + "\" holds no free cell of the map");
    if (!r.default_place.empty()) {
      const Place* p = f.findPlace(r.default_place);
      if (!p)
        add("default-place-missing", "room \"" + r.name + "\": its default place \"" +
                                         r.default_place + "\" does not exist");
      else if (!pointInPolygon(r.polygon, p->x, p->y))
        add("default-place-outside-room",
            "room \"" + r.name + "\": its default place \"" + p->name + "\" lies outside the room");
    }
  }
  for (size_t i = 0; i < f.rooms.size(); ++i)
    for (size_t j = i + 1; j < f.rooms.size(); ++j)
      if (roomsOverlap(f.rooms[i], f.rooms[j], map))
        add("rooms-overlap",
            "rooms \"" + f.rooms[i].name + "\" and \"" + f.rooms[j].name + "\" overlap");

  const double res = map.getResolution();
  for (const auto& p : f.places) {
    const std::string at = "place \"" + p.name + "\" at (" + fmt(p.x) + ", " + fmt(p.y) + ")";
    if (!p.room.empty()) {
      const Room* r = f.findRoom(p.room);
      if (!r)
        add("place-room-missing", at + ": its room \"" + p.room + "\" does not exist");
      else if (!pointInPolygon(r->polygon, p.x, p.y))
        add("place-outside-its-room", at + " lies outside its room \"" + r->name + "\"");
    } else if (!f.roomAt(p.x, p.y)) {
      add("place-outside-rooms", at + " lies outside every room");
    }
    int cx, cy;
    if (!cellOf(map, p.x, p.y, cx, cy)) {
      add("place-outside-map", at + " lies outside the map");
      continue;
    }
    const CellClass cc = classAt(map, cx, cy, params.thresholds);
    if (cc != CellClass::Free)
      add(cc == CellClass::Occupied ? "place-on-occupied" : "place-on-unknown",
          at + " is on an " + className(cc) + " cell");
    if (p.kind == PlaceKind::UserSearch) {
      // The robot turns on the spot: every cell whose centre lies within the
      // circumscribed radius must be free (cells off the map are not).
      const double r = params.turn_radius;
      const int span = static_cast<int>(std::ceil(r / res)) + 1;
      double nearest = std::numeric_limits<double>::infinity();
      for (int dy = -span; dy <= span; ++dy)
        for (int dx = -span; dx <= span; ++dx) {
          const int qx = cx + dx, qy = cy + dy;
          const double d = std::hypot(cellX(map, qx) - p.x, cellY(map, qy) - p.y);
          if (d > r) continue;
          const bool on_map = qx >= 0 && qy >= 0 && qx < static_cast<int>(map.getSizeX()) &&
                              qy < static_cast<int>(map.getSizeY());
          if (!on_map || classAt(map, qx, qy, params.thresholds) != CellClass::Free)
            nearest = std::min(nearest, d);
        }
      if (std::isfinite(nearest))
        add("user-search-no-turn-room", at + " (user-search) has no free disc of radius " + fmt(r) +
                                            " m to turn: a cell that is not free lies " +
                                            fmt(nearest) + " m away");
    }
  }
  return out;
}

Goal resolveGoal(const PlacesFile& f, const COccupancyGridMap2D& map, const std::string& name,
                 const io::OccupancyThresholds& t) {
  std::string room_name = name, place_name;
  const size_t slash = name.find('/');
  if (slash != std::string::npos) {
    room_name = name.substr(0, slash);
    place_name = name.substr(slash + 1);
  }
  auto known = [&] {
    std::string s;
    for (const auto& r : f.rooms) s += (s.empty() ? "" : ", ") + r.name;
    for (const auto& p : f.places) s += (s.empty() ? "" : ", ") + p.name;
    return s.empty() ? std::string("none") : s;
  };
  auto placeGoal = [&](const Place& p) {
    Goal g{p.x, p.y, p.heading_deg, "", p.name};
    if (const Room* r = f.roomOf(p)) g.room = r->name;
    return g;
  };
  if (!place_name.empty()) {
    const Room* r = f.findRoom(room_name);
    if (!r) throw InputError("goal \"" + name + "\": no room named \"" + room_name + "\"");
    const Place* p = f.findPlace(place_name);
    if (!p) throw InputError("goal \"" + name + "\": no place named \"" + place_name + "\"");
    if (f.roomOf(*p) != r)
      throw InputError("goal \"" + name + "\": place \"" + p->name + "\" is not in room \"" +
                       r->name + "\"");
    return placeGoal(*p);
  }
  if (const Place* p = f.findPlace(name)) return placeGoal(*p);
  const Room* r = f.findRoom(name);
  if (!r)
    throw InputError("goal \"" + name + "\": no room or place of that name (known: " + known() +
                     ")");
  if (!r->default_place.empty()) {
    const Place* p = f.findPlace(r->default_place);
    if (!p)
      throw InputError("goal \"" + name + "\": the default place \"" + r->default_place +
                       "\" of room \"" + r->name + "\" does not exist");
    Goal g = placeGoal(*p);
    g.room = r->name;
    return g;
  }
  // Most central free cell: distance transform over the room's cells plus a
  // one-cell frame, where every cell that is not free or whose centre lies
  // outside the polygon is an obstacle (so the polygon edge repels too).
  CellRange c = cellsUnder(map, r->polygon);
  c.x0 -= 1, c.y0 -= 1, c.x1 += 1, c.y1 += 1;
  const int w = c.x1 - c.x0 + 1, h = c.y1 - c.y0 + 1;
  if (w < 3 || h < 3)
    throw InputError("goal \"" + name + "\": room \"" + r->name + "\" holds no free cell");
  std::vector<uint8_t> room_free(static_cast<size_t>(w) * h, 0);
  bool any = false;
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const int cx = c.x0 + i, cy = c.y0 + j;
      const bool on_map = cx >= 0 && cy >= 0 && cx < static_cast<int>(map.getSizeX()) &&
                          cy < static_cast<int>(map.getSizeY());
      const bool ok = on_map && pointInPolygon(r->polygon, cellX(map, cx), cellY(map, cy)) &&
                      classAt(map, cx, cy, t) == CellClass::Free;
      room_free[static_cast<size_t>(j) * w + i] = ok ? 1 : 0;
      any = any || ok;
    }
  if (!any) throw InputError("goal \"" + name + "\": room \"" + r->name + "\" holds no free cell");
  const std::vector<double> grid = squaredDistanceTransform(room_free, w, h);
  double best = -1, sum_i = 0, sum_j = 0, count = 0;
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const double d = grid[static_cast<size_t>(j) * w + i];
      if (d > 0) sum_i += i, sum_j += j, ++count;
      best = std::max(best, d);
    }
  // On a grid many cells share the largest clearance (a long corridor): of
  // those within half a cell of it, take the one nearest the centroid of the
  // room's free cells, so the goal sits mid-room rather than at one end.
  const double ci = sum_i / count, cj = sum_j / count, limit = std::sqrt(best) - 0.5;
  double nearest = std::numeric_limits<double>::infinity();
  int bi = 0, bj = 0;
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const double clearance = std::sqrt(grid[static_cast<size_t>(j) * w + i]);
      const double dc = (i - ci) * (i - ci) + (j - cj) * (j - cj);
      if (clearance >= limit && dc < nearest) {
        nearest = dc;
        bi = i;
        bj = j;
      }
    }
  Goal g{cellX(map, c.x0 + bi), cellY(map, c.y0 + bj), 0.0, r->name, ""};
  return g;
}

void renderPlacesPng(const PlacesFile& f, const COccupancyGridMap2D& map, const std::string& path,
                     io::RenderOptions options) {
  io::RenderGeometry geo;
  mrpt::img::CImage img = io::renderGridMap(map, options, &geo);
  static const io::Rgb palette[] = {{230, 25, 75},  {60, 180, 75},  {0, 130, 200},  {245, 130, 48},
                                    {145, 30, 180}, {70, 200, 200}, {240, 50, 230}, {170, 110, 40}};
  const int W = static_cast<int>(img.getWidth()), H = static_cast<int>(img.getHeight());
  auto toMapX = [&](int u) { return geo.x_min + (u + 0.5) / geo.pixels_per_metre; };
  auto toMapY = [&](int v) { return geo.y_max - (v + 0.5) / geo.pixels_per_metre; };
  constexpr int kCharW = 9, kCharH = 15;  // CCanvas' default font
  auto label = [&](int x, int y, const std::string& text, const io::Rgb& c) {
    const int tw = static_cast<int>(text.size()) * kCharW;
    img.filledRectangle(x - 2, y - 2, x + tw + 1, y + kCharH + 1, mrpt::img::TColor(255, 255, 255));
    img.textOut(x, y, text, mrpt::img::TColor(c.r, c.g, c.b));
  };
  for (size_t k = 0; k < f.rooms.size(); ++k) {
    const Room& r = f.rooms[k];
    const io::Rgb col = palette[k % (sizeof palette / sizeof palette[0])];
    int u0 = W, u1 = -1, v0 = H, v1 = -1;
    for (const auto& p : r.polygon) {
      u0 = std::min(u0, geo.px(p.x)), u1 = std::max(u1, geo.px(p.x));
      v0 = std::min(v0, geo.py(p.y)), v1 = std::max(v1, geo.py(p.y));
    }
    u0 = std::max(u0, 0), v0 = std::max(v0, 0), u1 = std::min(u1, W - 1), v1 = std::min(v1, H - 1);
    constexpr double kAlpha = 0.3;
    for (int v = v0; v <= v1; ++v) {
      uint8_t* row = img.ptrLine<uint8_t>(static_cast<unsigned>(v));
      for (int u = u0; u <= u1; ++u) {
        if (!pointInPolygon(r.polygon, toMapX(u), toMapY(v))) continue;
        uint8_t* px = row + 3 * u;  // CImage keeps colour pixels as BGR
        px[0] = static_cast<uint8_t>((1 - kAlpha) * px[0] + kAlpha * col.b);
        px[1] = static_cast<uint8_t>((1 - kAlpha) * px[1] + kAlpha * col.g);
        px[2] = static_cast<uint8_t>((1 - kAlpha) * px[2] + kAlpha * col.r);
      }
    }
    const mrpt::img::TColor tc(col.r, col.g, col.b);
    for (size_t i = 0; i < r.polygon.size(); ++i) {
      const auto& a = r.polygon[i];
      const auto& b = r.polygon[(i + 1) % r.polygon.size()];
      img.line(geo.px(a.x), geo.py(a.y), geo.px(b.x), geo.py(b.y), tc, 2);
    }
    // Names go inside the top-left of the room's box, where place labels
    // (drawn right of and below their place) rarely reach; darker than the
    // fill so they read on white.
    const io::Rgb dark{static_cast<uint8_t>(col.r * 0.6), static_cast<uint8_t>(col.g * 0.6),
                       static_cast<uint8_t>(col.b * 0.6)};
    label(std::max(u0, 0) + 5, std::max(v0, 0) + 5, r.name, dark);
  }
  for (const auto& p : f.places) {
    const io::Rgb col = p.kind == PlaceKind::UserSearch     ? io::Rgb{200, 0, 0}
                        : p.kind == PlaceKind::ObjectSearch ? io::Rgb{0, 120, 0}
                        : p.kind == PlaceKind::Dock         ? io::Rgb{0, 0, 200}
                                                            : io::Rgb{40, 40, 40};
    const mrpt::img::TColor tc(col.r, col.g, col.b);
    const int u = geo.px(p.x), v = geo.py(p.y);
    const double th = p.heading_deg * M_PI / 180;
    const double len = 18;  // pixels
    const int ue = u + static_cast<int>(std::lround(len * std::cos(th)));
    const int ve = v - static_cast<int>(std::lround(len * std::sin(th)));
    img.drawCircle(u, v, 5, tc, 2);
    img.line(u, v, ue, ve, tc, 2);
    for (double side : {+1.0, -1.0}) {
      const double a = th + M_PI + side * 0.5;
      img.line(ue, ve, ue + static_cast<int>(std::lround(7 * std::cos(a))),
               ve - static_cast<int>(std::lround(7 * std::sin(a))), tc, 2);
    }
    std::string text = p.name;
    if (p.kind != PlaceKind::Place) text += std::string(" [") + placeKindName(p.kind) + "]";
    label(u + 8, v + 6, text, col);
  }
  const std::string tmp = path + ".tmp.png";
  if (!img.saveToFile(tmp)) throw std::runtime_error(path + ": cannot write the PNG");
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw std::runtime_error(path + ": cannot rename " + tmp);
  }
}

}  // namespace carenav::places
