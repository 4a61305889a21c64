// Rooms and places: geometry, names, the YAML file, checks and goals.
#include <carenav/places/places.h>
#include <gtest/gtest.h>

#include <unistd.h>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

using namespace carenav;
using namespace carenav::places;
namespace fs = std::filesystem;

namespace {

std::vector<TPoint2D> rect(double x0, double y0, double x1, double y1) {
  return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
}

// Independent reference: winding number by summing signed angles.
int windingNumber(const std::vector<TPoint2D>& poly, double x, double y) {
  double total = 0;
  for (size_t i = 0; i < poly.size(); ++i) {
    const auto& a = poly[i];
    const auto& b = poly[(i + 1) % poly.size()];
    const double a1 = std::atan2(a.y - y, a.x - x), a2 = std::atan2(b.y - y, b.x - x);
    double d = a2 - a1;
    while (d > M_PI) d -= 2 * M_PI;
    while (d < -M_PI) d += 2 * M_PI;
    total += d;
  }
  return static_cast<int>(std::lround(total / (2 * M_PI)));
}

double distToBoundary(const std::vector<TPoint2D>& poly, double x, double y) {
  double best = 1e300;
  for (size_t i = 0; i < poly.size(); ++i) {
    const auto& a = poly[i];
    const auto& b = poly[(i + 1) % poly.size()];
    const double dx = b.x - a.x, dy = b.y - a.y;
    double t = ((x - a.x) * dx + (y - a.y) * dy) / (dx * dx + dy * dy);
    t = std::max(0.0, std::min(1.0, t));
    best = std::min(best, std::hypot(a.x + t * dx - x, a.y + t * dy - y));
  }
  return best;
}

fs::path tmpDir() {
  const auto d = fs::temp_directory_path() / ("carenav_places_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

// 10 m x 10 m at 0.1 m, all free; callers paint walls and unknown areas.
COccupancyGridMap2D freeMap() { return io::makeGrid(0, 0, 0.1, 100, 100, 1.0f); }

void paint(COccupancyGridMap2D& m, double x0, double y0, double x1, double y1, float p_free) {
  for (int cy = 0; cy < 100; ++cy)
    for (int cx = 0; cx < 100; ++cx) {
      const double x = (cx + 0.5) * 0.1, y = (cy + 0.5) * 0.1;
      if (x >= x0 && x <= x1 && y >= y0 && y <= y1) m.setCell(cx, cy, p_free);
    }
}

std::string errorOf(const std::string& text) {
  try {
    parsePlaces(text, "f.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

const char* kGood =
    "format: 1\n"
    "rooms:\n"
    "  - name: Kitchen\n"
    "    polygon: [[0, 0], [4, 0], [4, 4], [0, 4]]\n"
    "    default_place: \"Table\"\n"
    "places:\n"
    "  - name: 'Table'\n"
    "    pose: [2, 2, 90]\n"
    "    kind: object-search\n"
    "end: true\n";

}  // namespace

TEST(PointInPolygon, ConvexSquare) {
  const auto sq = rect(0, 0, 2, 2);
  EXPECT_TRUE(pointInPolygon(sq, 1, 1));
  EXPECT_FALSE(pointInPolygon(sq, 3, 1));
  EXPECT_FALSE(pointInPolygon(sq, -0.001, 1));
  EXPECT_FALSE(pointInPolygon(sq, 1, 2.001));
}

TEST(PointInPolygon, ConcaveUShape) {
  // A U open to the top: the notch x in (1, 2), y in (1, 3) is outside.
  const std::vector<TPoint2D> u = {{0, 0}, {3, 0}, {3, 3}, {2, 3}, {2, 1}, {1, 1}, {1, 3}, {0, 3}};
  EXPECT_TRUE(pointInPolygon(u, 0.5, 2));
  EXPECT_TRUE(pointInPolygon(u, 2.5, 2));
  EXPECT_TRUE(pointInPolygon(u, 1.5, 0.5));
  EXPECT_FALSE(pointInPolygon(u, 1.5, 2));
  // The horizontal ray through y = 1 and y = 3 passes through vertices.
  EXPECT_FALSE(pointInPolygon(u, -1, 1));
  EXPECT_TRUE(pointInPolygon(u, 0.5, 0.9999));
  EXPECT_FALSE(pointInPolygon(u, 1.5, 1.0001));
  EXPECT_FALSE(pointInPolygon(u, -0.5, 3));
}

TEST(PointInPolygon, EdgesAndVerticesAreInside) {
  const auto sq = rect(0, 0, 2, 2);
  for (auto [x, y] : std::vector<std::pair<double, double>>{
           {0, 0}, {2, 0}, {2, 2}, {0, 2}, {1, 0}, {2, 1}, {1, 2}, {0, 1}}) {
    EXPECT_TRUE(pointInPolygon(sq, x, y)) << x << "," << y;
    EXPECT_TRUE(pointOnBoundary(sq, x, y)) << x << "," << y;
  }
  const std::vector<TPoint2D> tri = {{0, 0}, {4, 0}, {0, 3}};
  EXPECT_TRUE(pointInPolygon(tri, 2, 1.5));   // on the slanted edge
  EXPECT_FALSE(pointInPolygon(tri, 2, 1.6));  // just past it
  // Reversed orientation gives the same answers.
  const std::vector<TPoint2D> rev(tri.rbegin(), tri.rend());
  EXPECT_TRUE(pointInPolygon(rev, 2, 1.5));
  EXPECT_TRUE(pointInPolygon(rev, 1, 1));
  EXPECT_FALSE(pointInPolygon(rev, 3, 2));
}

TEST(PointInPolygon, AgreesWithWindingNumberOnAGrid) {
  // A concave star with vertices on grid lines, so the scan hits vertex rays.
  std::vector<TPoint2D> star;
  for (int k = 0; k < 10; ++k) {
    const double r = (k % 2) ? 1.0 : 3.0, a = k * M_PI / 5;
    star.push_back({std::round(10 * r * std::cos(a)) / 10, std::round(10 * r * std::sin(a)) / 10});
  }
  int inside = 0, checked = 0;
  for (double y = -3.5; y <= 3.5; y += 0.05)
    for (double x = -3.5; x <= 3.5; x += 0.05) {
      if (distToBoundary(star, x, y) < 1e-7) continue;  // the reference is undefined there
      const bool ref = windingNumber(star, x, y) != 0;
      ASSERT_EQ(pointInPolygon(star, x, y), ref) << x << "," << y;
      inside += ref;
      ++checked;
    }
  EXPECT_GT(inside, 500);
  EXPECT_GT(checked - inside, 500);
}

TEST(PlacesWhere, RoomAndNearestPlaceAgreeWithReference) {
  PlacesFile f;
  f.addRoom({"A", rect(0, 0, 5, 5), "", 0});
  f.addRoom({"B", {{5, 0}, {10, 0}, {10, 5}, {7, 2}, {5, 5}}, "", 0});  // concave, shares x=5
  f.addPlace({"pa", 1, 1, 0, PlaceKind::Place, "", 0});
  f.addPlace({"pb", 9, 1, 0, PlaceKind::Place, "", 0});
  for (double y = -0.75; y <= 5.8; y += 0.25)
    for (double x = -0.75; x <= 10.8; x += 0.25) {
      const WhereResult w = where(f, x, y);
      std::string ref;
      for (const auto& r : f.rooms)
        if (ref.empty() &&
            (windingNumber(r.polygon, x, y) != 0 || distToBoundary(r.polygon, x, y) < 1e-9))
          ref = r.name;
      EXPECT_EQ(w.room ? w.room->name : "", ref) << x << "," << y;
      const double da = std::hypot(x - 1, y - 1), db = std::hypot(x - 9, y - 1);
      ASSERT_NE(w.nearest, nullptr);
      EXPECT_EQ(w.nearest->name, da <= db ? "pa" : "pb");
      EXPECT_DOUBLE_EQ(w.distance, std::min(da, db));
    }
}

TEST(PlacesNames, CaseInsensitiveAsciiAndUtf8) {
  EXPECT_TRUE(sameName("Kitchen", "kITCHEN"));
  EXPECT_FALSE(sameName("Kitchen", "Kitchen2"));
  EXPECT_TRUE(sameName("Küche", "KüCHE"));
  EXPECT_FALSE(sameName("\xC3\x89tage", "\xC3\xA9tage"));  // É and é: only ASCII folds
  EXPECT_EQ(nameProblem("Salle à manger"), "");
  EXPECT_NE(nameProblem(""), "");
  EXPECT_NE(nameProblem("a/b"), "");
  EXPECT_NE(nameProblem(" a"), "");
  EXPECT_NE(nameProblem("a\tb"), "");
  EXPECT_NE(nameProblem("\xC3"), "");  // truncated UTF-8
  EXPECT_NE(nameProblem("a\xFF"
                        "b"),
            "");  // never valid in UTF-8
  PlacesFile f;
  f.addRoom({"Kitchen", rect(0, 0, 1, 1), "", 0});
  EXPECT_THROW(f.addRoom({"KITCHEN", rect(2, 2, 3, 3), "", 0}), InputError);
  EXPECT_THROW(f.addPlace({"kitchen", 0.5, 0.5, 0, PlaceKind::Place, "", 0}), InputError);
  EXPECT_THROW(f.addRoom({"Bad", {{0, 0}, {1, 1}}, "", 0}), InputError);
  EXPECT_THROW(f.addRoom({"Flat", {{0, 0}, {1, 1}, {2, 2}}, "", 0}), InputError);
  EXPECT_THROW(f.addPlace({"p", 5, 5, 0, PlaceKind::Place, "Kitchen", 0}), InputError);
  EXPECT_THROW(f.addPlace({"p", 0.5, 0.5, 0, PlaceKind::Place, "Nowhere", 0}), InputError);
  EXPECT_EQ(f.findRoom("kitchen")->name, "Kitchen");
}

TEST(PlacesEdits, RenameAndRemoveFollowReferences) {
  PlacesFile f;
  f.addRoom({"Kitchen", rect(0, 0, 4, 4), "", 0});
  f.addPlace({"Table", 2, 2, 0, PlaceKind::Place, "kitchen", 0});
  EXPECT_EQ(f.places[0].room, "Kitchen");  // stored with the room's spelling
  f.rooms[0].default_place = "Table";
  f.rename("TABLE", "Desk");
  EXPECT_EQ(f.rooms[0].default_place, "Desk");
  f.rename("kitchen", "Cuisine");
  EXPECT_EQ(f.places[0].room, "Cuisine");
  f.rename("cuisine", "CUISINE");  // a change of case only is allowed
  EXPECT_EQ(f.rooms[0].name, "CUISINE");
  f.addPlace({"Door", 1, 1, 0, PlaceKind::Place, "", 0});
  EXPECT_THROW(f.rename("Door", "desk"), InputError);
  EXPECT_THROW(f.rename("Nothing", "x"), InputError);
  f.remove("desk");
  EXPECT_EQ(f.rooms[0].default_place, "");
  f.remove("Cuisine");
  EXPECT_TRUE(f.rooms.empty());
  EXPECT_EQ(f.places.size(), 1u);
  EXPECT_THROW(f.remove("Cuisine"), InputError);
}

TEST(PlacesPath, BesideTheMap) {
  EXPECT_EQ(placesPathForMap("maps/sena.gridmap.gz"), "maps/sena.places.yaml");
  EXPECT_EQ(placesPathForMap("a/b.GRIDMAP"), "a/b.places.yaml");
  EXPECT_EQ(placesPathForMap("x.simplemap.gz"), "x.places.yaml");
  EXPECT_EQ(placesPathForMap("ros/map.yaml"), "ros/map.places.yaml");
  EXPECT_EQ(placesPathForMap("floor.png"), "floor.places.yaml");
  EXPECT_EQ(placesPathForMap("weird.bin"), "weird.bin.places.yaml");
}

TEST(PlacesYaml, RoundTripIsExact) {
  PlacesFile f;
  f.addRoom({"Salle à manger \"grande\"", {{0.1, -1e-7}, {1234.5678, 0}, {3, 1.0 / 3}}, "", 0});
  f.addRoom({"Back\\slash #1", rect(-10, -10, -5, -5), "", 0});
  f.addPlace({"Küche: search", 1, 0.05, -90, PlaceKind::UserSearch, "", 0});
  f.addPlace({"dock", -7, -7, 179.999, PlaceKind::Dock, "back\\SLASH #1", 0});
  f.addPlace({"obj", 2, 0.1, 0, PlaceKind::ObjectSearch, "", 0});
  f.rooms[1].default_place = "dock";
  const auto path = (tmpDir() / "rt.places.yaml").string();
  writePlacesFile(f, path);
  EXPECT_FALSE(fs::exists(path + ".tmp" + std::to_string(::getpid())));
  const PlacesFile g = readPlacesFile(path);
  ASSERT_EQ(g.rooms.size(), 2u);
  ASSERT_EQ(g.places.size(), 3u);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(g.rooms[i].name, f.rooms[i].name);
    EXPECT_EQ(g.rooms[i].default_place, f.rooms[i].default_place);
    ASSERT_EQ(g.rooms[i].polygon.size(), f.rooms[i].polygon.size());
    for (size_t k = 0; k < f.rooms[i].polygon.size(); ++k) {
      EXPECT_EQ(g.rooms[i].polygon[k].x, f.rooms[i].polygon[k].x);
      EXPECT_EQ(g.rooms[i].polygon[k].y, f.rooms[i].polygon[k].y);
    }
  }
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(g.places[i].name, f.places[i].name);
    EXPECT_EQ(g.places[i].x, f.places[i].x);
    EXPECT_EQ(g.places[i].y, f.places[i].y);
    EXPECT_EQ(g.places[i].heading_deg, f.places[i].heading_deg);
    EXPECT_EQ(g.places[i].kind, f.places[i].kind);
    EXPECT_EQ(g.places[i].room, f.places[i].room);
  }
  EXPECT_EQ(placesToYaml(g), placesToYaml(f));
  EXPECT_GT(g.places[1].line, 0);
}

TEST(PlacesYaml, HandWrittenSubsetReads) {
  const PlacesFile f = parsePlaces(
      "# comment\n\nformat: 1   # version\nrooms:\n- name: Kitchen  # a comment\n  polygon: "
      "[ [0,0] , [4,0],[4,4] ]\nplaces: []\nend: true\n",
      "x.yaml");
  ASSERT_EQ(f.rooms.size(), 1u);
  EXPECT_EQ(f.rooms[0].name, "Kitchen");
  EXPECT_EQ(f.rooms[0].polygon.size(), 3u);
  const PlacesFile g = parsePlaces(kGood, "g.yaml");
  EXPECT_EQ(g.places[0].kind, PlaceKind::ObjectSearch);
  EXPECT_EQ(g.rooms[0].default_place, "Table");
}

TEST(PlacesYaml, BrokenFilesNameTheLine) {
  struct Case {
    std::string text, expect;
  };
  const std::vector<Case> cases = {
      {"", "f.yaml:1: the file is empty"},
      {"rooms: []\nend: true\n", "f.yaml:1: the file must start with \"format: 1\""},
      {"format: 2\n", "f.yaml:1: format \"2\" is not supported"},
      {"format: 1\nrooms: []\nplaces: []\n", "f.yaml:3: the file does not end with"},
      {"format: 1\nrooms:\n  - name: A\n    polygon: [[0, 0], [1, 0], [1",
       "f.yaml:4: the file does not end with \"end: true\": it is truncated"},
      {"format: 1\nrooms:\n  - name: A\n    polygon: [[0, 0], [1, 0], [1, 1]\nend: true\n",
       "f.yaml:4: polygon"},
      {"format: 1\nrooms:\n  - name: A\n    polygon: [[0, 0], [1, x], [1, 1]]\nend: true\n",
       "f.yaml:4: polygon: \"x\" is not a finite number"},
      {"format: 1\nrooms:\n  - name: A\n    polygon: [[0, 0], [1, 0]]\nend: true\n",
       "f.yaml:3: room \"A\": a polygon needs at least 3 vertices"},
      {"format: 1\nrooms:\n  - name: A\n    colour: red\nend: true\n",
       "f.yaml:4: unknown key \"colour\""},
      {"format: 1\nrooms:\n  - name: A\n    name: B\nend: true\n", "f.yaml:4: name is given twice"},
      {"format: 1\nrooms:\n  - polygon: [[0, 0], [1, 0], [1, 1]]\nend: true\n",
       "f.yaml:3: room item has no name"},
      {"format: 1\nplaces:\n  - name: p\n    pose: [1, 2]\nend: true\n",
       "f.yaml:4: pose: expected [x, y, heading_deg]"},
      {"format: 1\nplaces:\n  - name: p\n    pose: [1, 2, 3]\n    kind: sofa\nend: true\n",
       "f.yaml:5: kind \"sofa\""},
      {"format: 1\nplaces:\n  - name: p\n    pose: [1, 2, 3]\n  - name: P\n    pose: [1, 2, "
       "3]\nend: true\n",
       "f.yaml:5: name \"P\" is taken by place \"p\""},
      {"format: 1\nplaces:\n  - name: \"p\n    pose: [1, 2, 3]\nend: true\n",
       "f.yaml:3: name: unterminated"},
      {"format: 1\nplaces:\n\t- name: p\nend: true\n", "f.yaml:3: tab in the indentation"},
      {"format: 1\nend: true\nrooms: []\n", "f.yaml:3: text after \"end: true\""},
      {"format: 1\nfloors: []\nend: true\n", "f.yaml:2: unknown key \"floors\""},
      {"format: 1\nrooms:\n    name: A\nend: true\n", "f.yaml:3: \"name: A\" is not inside"},
      {"format: 1\nplaces:\n  - name: p\n    pose: [1, 2, nan]\nend: true\n",
       "f.yaml:4: pose: \"nan\" is not a finite number"},
      {"format: 1\nplaces:\n  - name: a/b\n    pose: [1, 2, 3]\nend: true\n",
       "f.yaml:3: bad name \"a/b\""},
  };
  for (const auto& c : cases) {
    const std::string err = errorOf(c.text);
    EXPECT_EQ(err.rfind(c.expect, 0), 0u) << "got: " << err << "\nwanted: " << c.expect;
  }
}

TEST(PlacesYaml, EveryTruncationOfAWrittenFileIsRefused) {
  PlacesFile f = parsePlaces(kGood, "g.yaml");
  f.addPlace({"Door", 0.5, 3.5, 180, PlaceKind::UserSearch, "", 0});
  const std::string text = placesToYaml(f);
  // Every strict prefix except the one missing only the final newline.
  for (size_t n = 0; n + 1 < text.size(); ++n) {
    const std::string err = errorOf(text.substr(0, n));
    EXPECT_NE(err, "(no error)") << "prefix of " << n << " bytes read as a whole file";
    EXPECT_EQ(err.rfind("f.yaml:", 0), 0u) << err;
  }
  EXPECT_EQ(errorOf(text), "(no error)");
}

TEST(PlacesYaml, MissingAndBinaryFiles) {
  const auto d = tmpDir();
  EXPECT_THROW(readPlacesFile((d / "none.places.yaml").string()), InputError);
  {
    std::ofstream o(d / "bin.places.yaml", std::ios::binary);
    o << std::string("\x1f\x8b\0\0garbage", 11);
  }
  try {
    readPlacesFile((d / "bin.places.yaml").string());
    FAIL() << "binary file read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bin.places.yaml"), std::string::npos);
  }
}

TEST(PlacesCheck, CleanFileHasNoProblem) {
  auto m = freeMap();
  PlacesFile f;
  f.addRoom({"A", rect(0, 0, 5, 10), "", 0});
  f.addRoom({"B", rect(5, 0, 10, 10), "", 0});  // shares an edge: not an overlap
  f.addPlace({"search", 2.5, 5, 0, PlaceKind::UserSearch, "", 0});
  f.addPlace({"dock", 7, 5, 0, PlaceKind::Dock, "", 0});
  f.rooms[0].default_place = "search";
  EXPECT_TRUE(checkPlaces(f, m).empty());
}

TEST(PlacesCheck, FindsEachDefect) {
  auto m = freeMap();
  paint(m, 0, 8, 10, 10, 0.5f);  // unknown strip on top
  paint(m, 4.9, 0, 5.1, 8, 0);   // a wall at x = 5 (cells 4.9..5.1)
  PlacesFile f;
  f.addRoom({"West", rect(0, 0, 4, 8), "Ghost", 0});  // default place that does not exist
  f.addRoom({"East", rect(6, 0, 10, 8), "Far", 0});   // default place outside it
  f.addRoom({"Shifted", rect(8, 0, 12, 8), "", 0});   // overlaps East along shared edges
  f.addRoom({"Attic", rect(1, 8.5, 9, 9.5), "", 0});  // all unknown: no free cell
  f.addRoom({"Bow", {{0, -3}, {3, -1}, {3, -3}, {0, -1.5}}, "", 0});  // crosses itself
  f.addPlace({"Far", 1, 1, 0, PlaceKind::Place, "", 0});
  f.addPlace({"Outside", 4.5, 4, 0, PlaceKind::Place, "", 0});          // no room contains it
  f.addPlace({"Cramped", 3.8, 4, 0, PlaceKind::UserSearch, "", 0});     // wall 1.15 m away, but
  f.addPlace({"Wall", 5, 2, 0, PlaceKind::Place, "", 0});               // on the wall
  f.addPlace({"Fog", 3, 9, 0, PlaceKind::Place, "", 0});                // on unknown
  f.addPlace({"Lost", 20, 20, 0, PlaceKind::Place, "", 0});             // off the map
  f.addPlace({"Tight", 5.3, 4, 0, PlaceKind::UserSearch, "", 0});       // wall 0.25 m away
  f.places.push_back({"Moved", 1, 1, 0, PlaceKind::Place, "East", 0});  // outside its room
  f.places.push_back({"Orphan", 1, 1, 0, PlaceKind::Place, "Gone", 0});
  const auto problems = checkPlaces(f, m, CheckParams{0.35, {}});
  auto has = [&](const std::string& kind, const std::string& name) {
    for (const auto& p : problems)
      if (p.kind == kind && p.what.find("\"" + name + "\"") != std::string::npos) return true;
    return false;
  };
  EXPECT_TRUE(has("default-place-missing", "West"));
  EXPECT_TRUE(has("default-place-outside-room", "East"));
  EXPECT_TRUE(has("rooms-overlap", "Shifted"));
  EXPECT_TRUE(has("room-no-free-cell", "Attic"));
  EXPECT_TRUE(has("room-self-intersecting", "Bow"));
  EXPECT_TRUE(has("place-outside-rooms", "Outside"));
  EXPECT_TRUE(has("place-on-occupied", "Wall"));
  EXPECT_TRUE(has("place-on-unknown", "Fog"));
  EXPECT_TRUE(has("place-outside-map", "Lost"));
  EXPECT_TRUE(has("user-search-no-turn-room", "Tight"));
  EXPECT_TRUE(has("place-outside-its-room", "Moved"));
  EXPECT_TRUE(has("place-room-missing", "Orphan"));
  EXPECT_FALSE(has("user-search-no-turn-room", "Cramped"));
  EXPECT_FALSE(has("rooms-overlap", "West"));
  // A larger robot cannot turn at Cramped either.
  const auto big = checkPlaces(f, m, CheckParams{1.3, {}});
  bool cramped = false;
  for (const auto& p : big)
    cramped |= p.kind == "user-search-no-turn-room" && p.what.find("Cramped") != std::string::npos;
  EXPECT_TRUE(cramped);
}

TEST(PlacesGoal, PlacesRoomsAndCentres) {
  auto m = freeMap();
  PlacesFile f;
  f.addRoom({"Hall", rect(2, 2, 8, 6), "", 0});
  f.addRoom({"Study", rect(0, 7, 3, 10), "", 0});
  f.addPlace({"Desk", 1, 8, 45, PlaceKind::ObjectSearch, "", 0});
  f.addRoom({"Void", rect(20, 20, 22, 22), "", 0});
  // A room without a default: the centre of its free area.
  Goal g = resolveGoal(f, m, "hall");
  EXPECT_EQ(g.room, "Hall");
  EXPECT_EQ(g.place, "");
  EXPECT_NEAR(g.x, 5, 0.1);
  EXPECT_NEAR(g.y, 4, 0.1);
  // An obstacle in the middle pushes the centre away from it.
  auto m2 = m;
  paint(m2, 3.5, 2, 5.5, 6, 0);
  g = resolveGoal(f, m2, "Hall");
  EXPECT_GT(g.x, 5.5);
  EXPECT_LT(g.x, 8);
  EXPECT_NEAR(g.x, 6.75, 0.1);
  // A place, a room with its default, room/place.
  g = resolveGoal(f, m, "DESK");
  EXPECT_EQ(g.place, "Desk");
  EXPECT_EQ(g.room, "Study");
  EXPECT_DOUBLE_EQ(g.heading_deg, 45);
  f.findRoom("Study")->default_place = "Desk";
  g = resolveGoal(f, m, "study");
  EXPECT_DOUBLE_EQ(g.x, 1);
  EXPECT_DOUBLE_EQ(g.y, 8);
  g = resolveGoal(f, m, "Study/desk");
  EXPECT_DOUBLE_EQ(g.y, 8);
  EXPECT_THROW(resolveGoal(f, m, "Hall/Desk"), InputError);
  EXPECT_THROW(resolveGoal(f, m, "Kitchen"), InputError);
  EXPECT_THROW(resolveGoal(f, m, "Void"), InputError);
  f.findRoom("Hall")->default_place = "Missing";
  EXPECT_THROW(resolveGoal(f, m, "Hall"), InputError);
}

TEST(PlacesRender, DrawsRoomsInColour) {
  auto m = freeMap();
  PlacesFile f;
  f.addRoom({"Hall", rect(1, 1, 9, 9), "", 0});
  f.addPlace({"Sofa", 5, 5, 90, PlaceKind::UserSearch, "", 0});
  const auto path = (tmpDir() / "r.png").string();
  renderPlacesPng(f, m, path);
  mrpt::img::CImage img;
  ASSERT_TRUE(img.loadFromFile(path));
  EXPECT_GE(img.getWidth(), 800u);
  // Somewhere inside the room (away from labels) the free white is tinted.
  bool tinted = false;
  for (unsigned v = 0; v < img.getHeight() && !tinted; v += 7)
    for (unsigned u = 0; u < img.getWidth() && !tinted; u += 7) {
      const uint8_t* p = img.ptr<uint8_t>(u, v);
      tinted = img.isColor() && p[0] != p[1] && p[1] != 255;
    }
  EXPECT_TRUE(tinted);
}

TEST(PlacesYaml, WriteIntoAMissingFolderFailsAndLeavesNothing) {
  PlacesFile f = parsePlaces(kGood, "g.yaml");
  const auto dir = tmpDir() / "no_such_folder";
  EXPECT_THROW(writePlacesFile(f, (dir / "x.places.yaml").string()), std::runtime_error);
  EXPECT_FALSE(fs::exists(dir));
  // Overwriting an existing file replaces it whole.
  const auto path = (tmpDir() / "over.places.yaml").string();
  { std::ofstream(path) << "garbage that is much longer than the new file would be ......\n"; }
  writePlacesFile(f, path);
  EXPECT_EQ(readPlacesFile(path).places.size(), 1u);
  EXPECT_THROW(f.rename("Table", "a/b"), InputError);
  EXPECT_THROW(f.rename("Table", ""), InputError);
}
