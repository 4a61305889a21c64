// World files: the shipped worlds load with their features; bad files give
// InputError naming the file, the line and the fault.
#include <carenav/io/map_io.h>
#include <carenav/sim/world.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

using namespace carenav;
using namespace carenav::sim;
namespace fs = std::filesystem;

namespace {
const std::string kWorlds = std::string(CARENAV_SOURCE_DIR) + "/maps/worlds";

fs::path scratch() {
  auto d = fs::temp_directory_path() / ("carenav_sim_world_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

/** Writes `text` as a world next to a copy-free reference to the shipped PNG. */
std::string writeWorld(const std::string& name, const std::string& text) {
  const auto p = scratch() / name;
  std::ofstream(p) << text;
  return p.string();
}

std::string errorOf(const std::string& path) {
  try {
    loadWorld(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

const std::string kMapLines = "map: " + kWorlds + "/empty_room.png\nresolution: 0.05\n";
}  // namespace

TEST(SimWorld, ApartmentHasItsFeaturesAndPerson) {
  const World w = loadWorld(kWorlds + "/apartment.yaml");
  ASSERT_EQ(w.features().size(), 5u);
  ASSERT_EQ(w.people().size(), 1u);
  EXPECT_NEAR(w.resolution(), 0.05, 1e-9);
  EXPECT_EQ(w.sizeX(), 240);
  EXPECT_EQ(w.sizeY(), 160);
  // stairs: 5 steps of -0.17 along +x over x 10..11.9
  EXPECT_NEAR(w.floorAt(10.1, 6.0), -0.17, 1e-6);
  EXPECT_NEAR(w.floorAt(11.8, 6.0), -0.85, 1e-6);
  // gutter 0.10 deep
  EXPECT_NEAR(w.floorAt(4.9, 1.0), -0.10, 1e-6);
  // plain floor and walls
  EXPECT_EQ(w.floorAt(1.0, 1.0), 0.0);
  EXPECT_TRUE(std::isinf(w.floorAt(0.02, 4.0)));
  // table: legs are solid up to the top, the rest an overhang slab
  const Cell& leg = w.cell(w.cellX(2.02), w.cellY(5.02));
  EXPECT_NEAR(leg.floor, 0.75, 1e-6);
  const Cell& top = w.cell(w.cellX(2.8), w.cellY(5.45));
  EXPECT_EQ(top.floor, 0.0f);
  ASSERT_TRUE(top.hasSlab());
  EXPECT_NEAR(top.slab_lo, 0.71, 1e-6);
  EXPECT_NEAR(top.slab_hi, 0.75, 1e-6);
  // ramp rises 0.08 m northwards
  EXPECT_LT(w.floorAt(11.5, 0.6), 0.01);
  EXPECT_GT(w.floorAt(11.5, 2.4), 0.07);
  // the clearance field is 0 on features and grows away from them
  EXPECT_EQ(w.clearance(w.cellX(4.9), w.cellY(1.0)), 0);
  EXPECT_GE(w.clearance(w.cellX(3.5), w.cellY(2.0)), 10);
}

TEST(SimWorld, SenaWorldLoadsTheShippedMap) {
  const World w = loadWorld(kWorlds + "/sena.yaml");
  EXPECT_EQ(w.sizeX(), 1680);
  EXPECT_EQ(w.people().size(), 1u);
}

TEST(SimWorld, PersonWalksItsPathAndLoops) {
  Person p;
  p.speed = 1.0;
  p.path = {{0, 0}, {2, 0}, {2, 1}};
  p.loop = true;
  EXPECT_NEAR(p.at(1.0).x, 1.0, 1e-9);
  EXPECT_NEAR(p.at(2.5).y, 0.5, 1e-9);
  // loop: 2 + 1 + sqrt(5) long; back at the start after one lap
  const double lap = 3 + std::sqrt(5.0);
  EXPECT_NEAR(p.at(lap).x, 0.0, 1e-9);
  EXPECT_NEAR(p.at(lap + 0.5).x, 0.5, 1e-9);
  p.loop = false;
  EXPECT_NEAR(p.at(100).x, 2.0, 1e-9);
  EXPECT_NEAR(p.at(100).y, 1.0, 1e-9);
}

TEST(SimWorld, EmptyFileIsAnError) {
  const auto f = writeWorld("empty.yaml", "");
  const auto e = errorOf(f);
  EXPECT_NE(e.find(f), std::string::npos) << e;
  EXPECT_NE(e.find("empty"), std::string::npos) << e;
  const auto g = writeWorld("comments.yaml", "# nothing but a comment\n\n");
  EXPECT_NE(errorOf(g).find("empty"), std::string::npos);
}

TEST(SimWorld, TruncatedFileNamesTheLine) {
  const auto f = writeWorld("trunc.yaml", kMapLines +
                                              "features:\n"
                                              "  - type: step\n"
                                              "    rect: [1, 1, 2");
  const auto e = errorOf(f);
  EXPECT_NE(e.find(f + ":5:"), std::string::npos) << e;
  EXPECT_NE(e.find("missing ']'"), std::string::npos) << e;
  const auto g = writeWorld("trunc2.yaml", kMapLines + "features:\n");
  EXPECT_NE(errorOf(g).find("'features' has no value"), std::string::npos) << errorOf(g);
}

TEST(SimWorld, UnknownKeysAreNamedWithTheirLine) {
  const auto f = writeWorld("unknown.yaml", kMapLines + "wals: 2\n");
  const auto e = errorOf(f);
  EXPECT_NE(e.find(f + ":3:"), std::string::npos) << e;
  EXPECT_NE(e.find("unknown key 'wals'"), std::string::npos) << e;
  const auto g = writeWorld("unknown2.yaml", kMapLines +
                                                 "features:\n"
                                                 "  - type: hole\n"
                                                 "    rect: [1, 1, 2, 2]\n"
                                                 "    depth: 0.2\n"
                                                 "    height: 0.3\n");
  const auto e2 = errorOf(g);
  EXPECT_NE(e2.find(g + ":7:"), std::string::npos) << e2;
  EXPECT_NE(e2.find("unknown key 'height'"), std::string::npos) << e2;
  const auto h = writeWorld("badtype.yaml", kMapLines +
                                                "features:\n"
                                                "  - type: trampoline\n"
                                                "    rect: [1, 1, 2, 2]\n");
  EXPECT_NE(errorOf(h).find("'trampoline' is not one of"), std::string::npos) << errorOf(h);
}

TEST(SimWorld, BadNumbersAreNamed) {
  const auto f = writeWorld("badnum.yaml", kMapLines +
                                               "people:\n"
                                               "  - speed: fast\n"
                                               "    path: [[1, 1], [2, 2]]\n");
  const auto e = errorOf(f);
  EXPECT_NE(e.find(f + ":4:"), std::string::npos) << e;
  EXPECT_NE(e.find("'fast' is not a number"), std::string::npos) << e;
  const auto g = writeWorld("range.yaml", kMapLines +
                                              "features:\n"
                                              "  - type: stairs\n"
                                              "    rect: [1, 1, 2, 2]\n"
                                              "    direction: 0\n"
                                              "    steps: 2.5\n"
                                              "    rise: -0.17\n");
  EXPECT_NE(errorOf(g).find("whole number"), std::string::npos) << errorOf(g);
  const auto h = writeWorld("rect.yaml", kMapLines +
                                             "features:\n"
                                             "  - type: step\n"
                                             "    rect: [2, 2, 1, 1]\n"
                                             "    height: 0.1\n");
  EXPECT_NE(errorOf(h).find("x1 > x0"), std::string::npos) << errorOf(h);
}

TEST(SimWorld, MissingMapIsNamed) {
  const auto f = writeWorld("nomap.yaml", "features: []\n");
  EXPECT_NE(errorOf(f).find("missing key 'map'"), std::string::npos) << errorOf(f);
  const auto g = writeWorld("gone.yaml", "map: does_not_exist.gridmap.gz\n");
  const auto e = errorOf(g);
  EXPECT_NE(e.find(g + ":1:"), std::string::npos) << e;
  EXPECT_NE(e.find("does not exist"), std::string::npos) << e;
  const auto h = writeWorld("nores.yaml", "map: " + kWorlds + "/empty_room.png\n");
  EXPECT_NE(errorOf(h).find("needs 'resolution"), std::string::npos) << errorOf(h);
  EXPECT_NE(errorOf((scratch() / "absent.yaml").string()).find("no such world file"),
            std::string::npos);
}

TEST(SimWorld, TabsAndBadIndentationAreErrors) {
  const auto f = writeWorld("tab.yaml", kMapLines + "\tpeople: []\n");
  EXPECT_NE(errorOf(f).find("tab"), std::string::npos) << errorOf(f);
  const auto g = writeWorld("indent.yaml", kMapLines + "  stray: 1\n");
  EXPECT_NE(errorOf(g).find(":3:"), std::string::npos) << errorOf(g);
}

// ------------------------------------------- bounded by construction

TEST(SimWorld, HugeCoordinatesAndCountsAreRefusedBeforeRasterising) {
  const std::string far = writeWorld(
      "far.yaml", kMapLines + "features:\n  - type: step\n    rect: [0, 0, 1e9, 1e9]\n"
                              "    height: 0.1\n");
  EXPECT_NE(errorOf(far).find("far.yaml:5: features[0].rect: 1e9 is out of range"),
            std::string::npos)
      << errorOf(far);
  std::string poly = "[";
  for (int i = 0; i < 100000; ++i)
    poly += (i ? ", [" : "[") + std::to_string(i % 7) + ", " + std::to_string(i % 5) + "]";
  const std::string many = writeWorld(
      "many.yaml", kMapLines + "features:\n  - type: hole\n    polygon: " + poly +
                       "]\n    depth: 0.1\n");
  EXPECT_NE(errorOf(many).find("100000 points, at most"), std::string::npos) << errorOf(many);
  std::string feats = kMapLines + "features:\n";
  for (int i = 0; i < 1001; ++i) feats += "  - type: step\n    rect: [1, 1, 2, 2]\n    height: 0.01\n";
  const std::string lots = writeWorld("lots.yaml", feats);
  EXPECT_NE(errorOf(lots).find("1001 features, at most"), std::string::npos) << errorOf(lots);
}

TEST(SimWorld, FarAwayQueriesAreOutsideTheGridNotOverflow) {
  const World w = loadWorld(kWorlds + "/apartment.yaml");
  for (double x : {-1e300, -1e12, 1e12, 1e300, std::nan("")}) {
    EXPECT_EQ(w.floorAt(x, 4.0), 0.0) << x;
    EXPECT_EQ(w.floorAt(4.0, x), 0.0) << x;
    EXPECT_LT(w.cellX(x), w.sizeX() + 1);
    EXPECT_GE(w.cellX(x), -1);
  }
}
