// carenav map info|convert and carenav import ros-map, run as a user would.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "cli_helpers.h"

using namespace carenav_test;
namespace fs = std::filesystem;

namespace {
const std::string kMalagaGrid = kDatasets + "/2006-MalagaCampus.gridmap.gz";
const std::string kLocSimple = kDatasets + "/localization_demo.simplemap.gz";
const std::string kFacSimple = kDatasets + "/malaga-cs-fac-building.simplemap.gz";

fs::path mapDir(const std::string& name) {
  const auto d = scratch() / ("map_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// Width and height from a PNG's IHDR chunk (bytes 16..23, big-endian).
std::pair<uint32_t, uint32_t> pngSize(const fs::path& p) {
  const std::string b = slurp(p);
  EXPECT_GE(b.size(), 24u);
  EXPECT_EQ(b.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << p;
  EXPECT_EQ(b.substr(12, 4), "IHDR");
  if (b.size() < 24) return {0, 0};
  auto be32 = [&](size_t i) {
    return (uint32_t(uint8_t(b[i])) << 24) | (uint32_t(uint8_t(b[i + 1])) << 16) |
           (uint32_t(uint8_t(b[i + 2])) << 8) | uint32_t(uint8_t(b[i + 3]));
  };
  return {be32(16), be32(20)};
}

struct Counts {
  uint64_t sx, sy, occupied, free, unknown;
};
Counts infoCounts(const std::string& map, const std::vector<std::string>& extra = {}) {
  std::vector<std::string> args{"map", "info", "--json", map};
  args.insert(args.end(), extra.begin(), extra.end());
  const RunResult r = carenav(args);
  EXPECT_EQ(r.code, 0) << r.err;
  return {jsonNumber(r.out, "size_x"), jsonNumber(r.out, "size_y"), jsonNumber(r.out, "occupied"),
          jsonNumber(r.out, "free"), jsonNumber(r.out, "unknown")};
}
}  // namespace

TEST(CliMap, HelpAndUsageErrors) {
  for (std::vector<std::string> args : {std::vector<std::string>{"map", "--help"},
                                        {"map", "info", "--help"},
                                        {"map", "convert", "--help"},
                                        {"import", "ros-map", "--help"}}) {
    const RunResult r = carenav(args);
    EXPECT_EQ(r.code, 0) << args[1];
    EXPECT_NE(r.out.find("Usage:"), std::string::npos) << r.out;
  }
  EXPECT_EQ(carenav({"map"}).code, 2);
  EXPECT_EQ(carenav({"map", "info"}).code, 2);
  EXPECT_EQ(carenav({"map", "convert", kMalagaGrid}).code, 2);
  EXPECT_EQ(carenav({"import", "ros-map", "x.yaml"}).code, 2);  // --out is required
}

TEST(CliMap, InfoOnMrptDatasets) {
  const RunResult text = carenav({"map", "info", kMalagaGrid});
  ASSERT_EQ(text.code, 0) << text.err;
  EXPECT_NE(text.out.find("kind: gridmap"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("resolution: 0.08 m"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("occupied"), std::string::npos);

  const Counts g = infoCounts(kMalagaGrid);
  EXPECT_EQ(g.sx, 1888u);  // as MRPT's own COccupancyGridMap2D reports it
  EXPECT_EQ(g.sy, 2738u);
  EXPECT_GT(g.occupied, 10000u);
  EXPECT_GT(g.free, 1000000u);
  EXPECT_EQ(g.occupied + g.free + g.unknown, g.sx * g.sy);

  for (const auto& sm : {kLocSimple, kFacSimple}) {
    SCOPED_TRACE(sm);
    const Counts s = infoCounts(sm);
    EXPECT_GT(s.sx, 100u);
    EXPECT_GT(s.sy, 100u);
    EXPECT_GT(s.occupied, 1000u);
    EXPECT_GT(s.free, 50000u);
  }
  // A coarser grid from the same simplemap has fewer cells.
  const Counts coarse = infoCounts(kLocSimple, {"--resolution", "0.2"});
  EXPECT_LT(coarse.sx * coarse.sy, infoCounts(kLocSimple).sx * infoCounts(kLocSimple).sy);
}

TEST(CliMap, ConvertGridmapToRosAndBackKeepsCounts) {
  const auto d = mapDir("roundtrip");
  const std::string yaml = (d / "campus.yaml").string();
  const std::string back = (d / "campus.gridmap.gz").string();
  RunResult r = carenav({"map", "convert", kMalagaGrid, yaml});
  ASSERT_EQ(r.code, 0) << r.err;
  ASSERT_TRUE(fs::exists(d / "campus.pgm"));
  const std::string y = slurp(yaml);
  EXPECT_NE(y.find("image: campus.pgm"), std::string::npos) << y;
  EXPECT_NE(y.find("resolution: 0.08"), std::string::npos) << y;
  EXPECT_NE(y.find("origin: [-10.0, -127.04, 0.0]"), std::string::npos) << y;
  EXPECT_EQ(slurp(d / "campus.pgm").substr(0, 2), "P5");

  r = carenav({"map", "convert", yaml, back});
  ASSERT_EQ(r.code, 0) << r.err;
  const Counts a = infoCounts(kMalagaGrid), b = infoCounts(yaml), c = infoCounts(back);
  for (const Counts& x : {b, c}) {
    EXPECT_EQ(x.sx, a.sx);
    EXPECT_EQ(x.sy, a.sy);
    EXPECT_EQ(x.occupied, a.occupied);
    EXPECT_EQ(x.free, a.free);
    EXPECT_EQ(x.unknown, a.unknown);
  }
  // Only the outputs remain (temporary files were renamed).
  EXPECT_EQ(std::distance(fs::directory_iterator(d), fs::directory_iterator()), 3);

  // Unknown output kinds are refused before any work.
  r = carenav({"map", "convert", kMalagaGrid, (d / "campus.txt").string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("campus.txt"), std::string::npos) << r.err;
}

TEST(CliMap, ImportRosMapWritesGridmapAndRejectsBrokenYaml) {
  const auto d = mapDir("import");
  // A small hand-made ROS map: 6 x 4 pixels, a black wall on the top row.
  std::string pgm = "P5\n# hand made\n6 4\n255\n";
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 6; ++c) pgm += static_cast<char>(r == 0 ? 0 : (c == 5 ? 205 : 254));
  std::ofstream(d / "room.pgm", std::ios::binary) << pgm;
  std::ofstream(d / "room.yaml") << "image: room.pgm\nresolution: 0.5\norigin: [-1.5, -1.0, 0.0]\n"
                                    "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
  const std::string out = (d / "room.gridmap.gz").string();
  RunResult r = carenav({"import", "ros-map", (d / "room.yaml").string(), "--out", out});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("size: 6 x 4 cells"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("origin: [-1.5, -1]"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("6 occupied, 15 free, 3 unknown"), std::string::npos) << r.out;
  ASSERT_TRUE(fs::exists(out));
  const Counts c = infoCounts(out);
  EXPECT_EQ(c.occupied, 6u);
  EXPECT_EQ(c.free, 15u);
  EXPECT_EQ(c.unknown, 3u);

  r = carenav({"import", "ros-map", "--json", (d / "room.yaml").string(), "--out", d.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(jsonNumber(r.out, "occupied"), 6u);
  EXPECT_NE(r.out.find("\"out\": \"" + out + "\""), std::string::npos) << r.out;

  // Broken YAML: exit 2, the message names the file, line and key; no output.
  std::ofstream(d / "broken.yaml") << "image: room.pgm\nresolution: -0.5\norigin: [0, 0, 0]\n";
  const std::string bad_out = (d / "broken.gridmap.gz").string();
  r = carenav({"import", "ros-map", (d / "broken.yaml").string(), "--out", bad_out});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("broken.yaml:2:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("resolution"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(bad_out));
  std::ofstream(d / "noimage.yaml") << "image: gone.pgm\nresolution: 0.5\norigin: [0, 0, 0]\n";
  r = carenav({"import", "ros-map", (d / "noimage.yaml").string(), "--out", bad_out});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("gone.pgm"), std::string::npos) << r.err;
  std::string cut = pgm.substr(0, pgm.size() - 5);
  std::ofstream(d / "cut.pgm", std::ios::binary) << cut;
  std::ofstream(d / "cut.yaml") << "image: cut.pgm\nresolution: 0.5\norigin: [0, 0, 0]\n";
  r = carenav({"import", "ros-map", (d / "cut.yaml").string(), "--out", bad_out});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("truncated"), std::string::npos) << r.err;
  std::ofstream(d / "empty.yaml") << "";
  r = carenav({"import", "ros-map", (d / "empty.yaml").string(), "--out", bad_out});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("empty"), std::string::npos) << r.err;
  r = carenav({"import", "ros-map", (d / "room.yaml").string(), "--out", (d / "x.yaml").string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(".gridmap"), std::string::npos) << r.err;
}

TEST(CliMap, WrongKindsOfMapFilesExit2) {
  RunResult r = carenav({"map", "info", kDatasets + "/localization_demo.rawlog"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("rawlog"), std::string::npos) << r.err;
  const auto d = mapDir("kinds");
  fs::copy_file(kLocSimple, d / "not_a_grid.gridmap.gz");
  r = carenav({"map", "info", (d / "not_a_grid.gridmap.gz").string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("CSimpleMap"), std::string::npos) << r.err;
  std::ofstream(d / "empty.gridmap.gz") << "";
  EXPECT_EQ(carenav({"map", "info", (d / "empty.gridmap.gz").string()}).code, 2);
  const std::string full = slurp(kMalagaGrid);
  std::ofstream(d / "cut.gridmap.gz", std::ios::binary) << full.substr(0, full.size() / 3);
  r = carenav({"map", "info", (d / "cut.gridmap.gz").string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("cut.gridmap.gz"), std::string::npos) << r.err;
}

TEST(CliMap, PngRendersHaveTheExpectedSize) {
  const auto d = mapDir("png");
  // The campus is wider than 800 cells: one pixel per cell.
  RunResult r = carenav({"map", "convert", kMalagaGrid, (d / "campus.png").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  auto [w, h] = pngSize(d / "campus.png");
  EXPECT_EQ(w, 1888u);
  EXPECT_EQ(h, 2738u);
  r = carenav({"map", "convert", "--pixels-per-cell", "2", kLocSimple, (d / "loc.png").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  const Counts loc = infoCounts(kLocSimple);
  std::tie(w, h) = pngSize(d / "loc.png");
  EXPECT_EQ(w, 2 * loc.sx);
  EXPECT_EQ(h, 2 * loc.sy);
  // A small map is enlarged to at least 800 pixels wide, whole cells.
  std::string pgm = "P5\n40 20\n255\n" + std::string(800, '\xfe');
  std::ofstream(d / "small.pgm", std::ios::binary) << pgm;
  r = carenav({"map", "convert", "--resolution", "0.1", (d / "small.pgm").string(),
               (d / "small.png").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  std::tie(w, h) = pngSize(d / "small.png");
  EXPECT_EQ(w, 800u);
  EXPECT_EQ(h, 400u);
}
