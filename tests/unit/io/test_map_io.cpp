// Map input/output: ROS map_server YAML + PGM both ways, MRPT gridmaps and
// simplemaps, bare images, renders, and every malformed input a user can
// hand in.
#include <carenav/io/map_io.h>
#include <carenav/io/map_render.h>

#include <gtest/gtest.h>
#include <mrpt/img/CImage.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

using namespace carenav;
using namespace carenav::io;
namespace fs = std::filesystem;

namespace {
const std::string kMrptData = CARENAV_MRPT_DATASETS;
const std::string kMalaga = kMrptData + "/2006-MalagaCampus.gridmap.gz";
const std::string kLocSimplemap = kMrptData + "/localization_demo.simplemap.gz";
const std::string kLocRawlog = kMrptData + "/localization_demo.rawlog";

fs::path mapScratch(const std::string& sub) {
  auto d = fs::temp_directory_path() / ("carenav_map_io_" + std::to_string(::getpid())) / sub;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::string slurpFile(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

void putFile(const fs::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary) << bytes;
}

// A 40 x 30 grid whose cell classes follow a pattern: occupied, free and
// unknown cells all present, and no symmetry that would hide a flipped axis.
CellClass patternClass(int cx, int cy) {
  const int k = (cx * 7 + cy * 13 + cx * cy) % 5;
  return k == 0 ? CellClass::Occupied : k < 3 ? CellClass::Free : CellClass::Unknown;
}
float pFree(CellClass k) {
  return k == CellClass::Occupied ? 0.f : k == CellClass::Free ? 1.f : 0.5f;
}

COccupancyGridMap2D patternGrid(double x0, double y0, double res, int sx = 40, int sy = 30) {
  COccupancyGridMap2D g = makeGrid(x0, y0, res, sx, sy);
  for (int cy = 0; cy < sy; ++cy)
    for (int cx = 0; cx < sx; ++cx) g.setCell(cx, cy, pFree(patternClass(cx, cy)));
  return g;
}

void expectSameClasses(const COccupancyGridMap2D& a, const COccupancyGridMap2D& b) {
  ASSERT_EQ(a.getSizeX(), b.getSizeX());
  ASSERT_EQ(a.getSizeY(), b.getSizeY());
  size_t differ = 0;
  for (unsigned cy = 0; cy < a.getSizeY(); ++cy)
    for (unsigned cx = 0; cx < a.getSizeX(); ++cx)
      if (classifyCell(a.getCell(cx, cy)) != classifyCell(b.getCell(cx, cy))) ++differ;
  EXPECT_EQ(differ, 0u);
}

// Expects an InputError whose message holds every one of `parts`.
void expectInputError(const std::function<void()>& f, const std::vector<std::string>& parts) {
  try {
    f();
    ADD_FAILURE() << "no InputError; expected one mentioning " << parts.front();
  } catch (const InputError& e) {
    const std::string msg = e.what();
    for (const auto& p : parts)
      EXPECT_NE(msg.find(p), std::string::npos) << "'" << p << "' not in: " << msg;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not an InputError: " << e.what();
  }
}

struct Pgm {
  std::string magic;
  size_t w = 0, h = 0, maxval = 0;
  std::string pixels;
};
Pgm parsePgm(const std::string& bytes) {
  Pgm p;
  std::istringstream is(bytes);
  is >> p.magic;
  std::string tok;
  std::vector<size_t> nums;
  while (nums.size() < 3 && is >> tok) {
    if (tok[0] == '#') {
      std::getline(is, tok);
      continue;
    }
    nums.push_back(std::stoul(tok));
  }
  p.w = nums.at(0);
  p.h = nums.at(1);
  p.maxval = nums.at(2);
  is.get();  // the single blank after maxval
  p.pixels = bytes.substr(static_cast<size_t>(is.tellg()));
  return p;
}

std::string pgmP5(size_t w, size_t h, const std::vector<uint8_t>& px, int maxval = 255) {
  std::string s =
      "P5\n" + std::to_string(w) + " " + std::to_string(h) + "\n" + std::to_string(maxval) + "\n";
  s.append(px.begin(), px.end());
  return s;
}

std::string rosYaml(const std::string& image, const std::string& extra = "",
                    const std::string& resolution = "0.1",
                    const std::string& origin = "[-1.0, -2.0, 0.0]") {
  return "image: " + image + "\nresolution: " + resolution + "\norigin: " + origin +
         "\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n" + extra;
}
}  // namespace

// ------------------------------------------------------------ write/read ROS

TEST(MapIo, RosRoundTripKeepsClassesResolutionAndOriginExactly) {
  const auto dir = mapScratch("roundtrip");
  // -10.025 is not a multiple of the resolution: MRPT's setSize would move it.
  for (const auto& [x0, y0, res] : {std::tuple{-10.025, 3.01, 0.05}, std::tuple{-1.0, -2.0, 0.1},
                                    std::tuple{123.456, -78.9, 0.025}}) {
    SCOPED_TRACE(x0);
    const COccupancyGridMap2D g = patternGrid(x0, y0, res);
    EXPECT_NEAR(g.getXMin(), x0, 1e-5);  // makeGrid kept the corner (to float precision)
    const std::string yaml = (dir / "map.yaml").string();
    writeRosMap(g, yaml);
    const COccupancyGridMap2D r = readRosMap(yaml);
    expectSameClasses(g, r);
    EXPECT_NEAR(r.getResolution(), g.getResolution(), 1e-9);
    EXPECT_NEAR(r.getXMin(), g.getXMin(), 1e-9);
    EXPECT_NEAR(r.getYMin(), g.getYMin(), 1e-9);
    const GridStats a = gridStats(g), b = gridStats(r);
    EXPECT_EQ(a.occupied, b.occupied);
    EXPECT_EQ(a.free, b.free);
    EXPECT_EQ(a.unknown, b.unknown);
    EXPECT_GT(a.occupied, 100u);
    EXPECT_GT(a.free, 100u);
    EXPECT_GT(a.unknown, 100u);
  }
  // Nothing but the two files: the temporaries were renamed away.
  size_t files = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    ++files;
    EXPECT_TRUE(e.path().filename() == "map.yaml" || e.path().filename() == "map.pgm") << e.path();
  }
  EXPECT_EQ(files, 2u);
}

TEST(MapIo, PgmFirstRowIsTheTopOfTheMapAndYamlFollowsMapServer) {
  const auto dir = mapScratch("toprow");
  COccupancyGridMap2D g = makeGrid(-1.0, -2.0, 0.1, 20, 10, 1.0f);  // all free
  // One occupied cell at (0.55, -1.15): column 15, grid row 8 (from y_min);
  // in the image, whose first row is y_max, that is row 10 - 1 - 8 = 1.
  g.setPos(0.55f, -1.15f, 0.0f);
  g.setCell(0, 0, 0.5f);  // lower-left cell unknown: last row, first column
  writeRosMap(g, (dir / "top.yaml").string());

  const Pgm p = parsePgm(slurpFile(dir / "top.pgm"));
  EXPECT_EQ(p.magic, "P5");
  EXPECT_EQ(p.w, 20u);
  EXPECT_EQ(p.h, 10u);
  EXPECT_EQ(p.maxval, 255u);
  ASSERT_EQ(p.pixels.size(), 200u);
  for (size_t r = 0; r < 10; ++r)
    for (size_t c = 0; c < 20; ++c) {
      const auto v = static_cast<uint8_t>(p.pixels[r * 20 + c]);
      if (r == 1 && c == 15)
        EXPECT_EQ(v, 0) << "occupied cell is black";
      else if (r == 9 && c == 0)
        EXPECT_EQ(v, 205) << "unknown cell is 205";
      else
        EXPECT_EQ(v, 254) << "free cell at row " << r << " col " << c;
    }

  const std::string y = slurpFile(dir / "top.yaml");
  EXPECT_NE(y.find("image: top.pgm\n"), std::string::npos) << y;
  EXPECT_NE(y.find("resolution: 0.1\n"), std::string::npos) << y;
  EXPECT_NE(y.find("origin: [-1.0, -2.0, 0.0]\n"), std::string::npos) << y;
  EXPECT_NE(y.find("negate: 0\n"), std::string::npos) << y;
  EXPECT_NE(y.find("occupied_thresh: 0.65\n"), std::string::npos) << y;
  EXPECT_NE(y.find("free_thresh: 0.196\n"), std::string::npos) << y;

  const RosMapYaml parsed = readRosMapYaml((dir / "top.yaml").string());
  EXPECT_EQ(parsed.image, "top.pgm");
  EXPECT_EQ(parsed.image_path, (dir / "top.pgm").string());
  EXPECT_DOUBLE_EQ(parsed.origin_x, -1.0);
  EXPECT_DOUBLE_EQ(parsed.origin_y, -2.0);
  EXPECT_FALSE(parsed.negate);

  // Read back, the occupied cell is where it was, in metres.
  const COccupancyGridMap2D r = readRosMap((dir / "top.yaml").string());
  EXPECT_EQ(classifyCell(r.getPos(0.55f, -1.15f)), CellClass::Occupied);
  EXPECT_EQ(classifyCell(r.getPos(0.55f, -1.95f)), CellClass::Free);
}

// ------------------------------------------------------------ read ROS inputs

TEST(MapIo, ReadsHandWrittenMapsLikeMapServer) {
  const auto dir = mapScratch("handwritten");
  // P2 (ASCII) with comments and a maxval of 15: values are rescaled to 0..255.
  putFile(dir / "a.pgm", "P2\n# made by hand\n3 2\n# maxval next\n15\n0 15 12\n  3 8 15\n");
  putFile(
      dir / "a.yaml",
      "# a comment line\nimage: \"a.pgm\"   # quoted\nresolution: 0.5\norigin:\n  - 10\n  - 20\n"
      "  - 0\nextra_key: ignored\n");
  COccupancyGridMap2D g = readRosMap((dir / "a.yaml").string());
  ASSERT_EQ(g.getSizeX(), 3u);
  ASSERT_EQ(g.getSizeY(), 2u);
  EXPECT_DOUBLE_EQ(g.getXMin(), 10.0);
  EXPECT_DOUBLE_EQ(g.getYMin(), 20.0);
  // Top image row -> grid row 1. 0 -> occupied, 15 (=255) -> free,
  // 12 (=204: p_occ 0.2) -> unknown, 3 (=51: p_occ 0.8) -> occupied, 8 (=136) unknown.
  EXPECT_EQ(classifyCell(g.getCell(0, 1)), CellClass::Occupied);
  EXPECT_EQ(classifyCell(g.getCell(1, 1)), CellClass::Free);
  EXPECT_EQ(classifyCell(g.getCell(2, 1)), CellClass::Unknown);
  EXPECT_EQ(classifyCell(g.getCell(0, 0)), CellClass::Occupied);
  EXPECT_EQ(classifyCell(g.getCell(1, 0)), CellClass::Unknown);
  EXPECT_EQ(classifyCell(g.getCell(2, 0)), CellClass::Free);

  // negate: 1 swaps black and white.
  putFile(dir / "n.yaml", "image: a.pgm\nresolution: 0.5\norigin: [0, 0, 0]\nnegate: 1\n");
  g = readRosMap((dir / "n.yaml").string());
  EXPECT_EQ(classifyCell(g.getCell(0, 1)), CellClass::Free);
  EXPECT_EQ(classifyCell(g.getCell(1, 1)), CellClass::Occupied);

  // scale: cells between the thresholds keep a graded value.
  putFile(dir / "s.pgm", pgmP5(3, 1, {0, 150, 255}));
  putFile(dir / "s.yaml", "image: s.pgm\nresolution: 1\norigin: [0, 0, 0]\nmode: scale\n");
  g = readRosMap((dir / "s.yaml").string());
  const double occ = (255.0 - 150) / 255, ratio = (occ - 0.196) / (0.65 - 0.196);
  EXPECT_NEAR(1.0 - g.getCell(1, 0), (1 + 98 * ratio) / 100, 0.03);
  EXPECT_EQ(classifyCell(g.getCell(0, 0)), CellClass::Occupied);
  EXPECT_EQ(classifyCell(g.getCell(2, 0)), CellClass::Free);
  // trinary (the default): the same pixel is unknown.
  putFile(dir / "t.yaml", "image: s.pgm\nresolution: 1\norigin: [0, 0, 0]\n");
  EXPECT_FLOAT_EQ(readRosMap((dir / "t.yaml").string()).getCell(1, 0), 0.5f);

  // raw: the value is the occupancy percentage; above 100 unknown.
  putFile(dir / "r.pgm", pgmP5(3, 1, {0, 100, 255}));
  putFile(dir / "r.yaml", "image: r.pgm\nresolution: 1\norigin: [0, 0, 0]\nmode: raw\n");
  g = readRosMap((dir / "r.yaml").string());
  EXPECT_EQ(classifyCell(g.getCell(0, 0)), CellClass::Free);
  EXPECT_EQ(classifyCell(g.getCell(1, 0)), CellClass::Occupied);
  EXPECT_FLOAT_EQ(g.getCell(2, 0), 0.5f);
}

TEST(MapIo, ReadsPngMaps) {
  const auto dir = mapScratch("png");
  mrpt::img::CImage img(4, 2, mrpt::img::CH_RGB);
  img.filledRectangle(0, 0, 3, 1, mrpt::img::TColor(254, 254, 254));
  img.setPixel(3, 0, 0x000000);  // top-right black: occupied at grid (3, 1)
  img.setPixel(0, 1, 0xCDCDCD);  // bottom-left 205: unknown at grid (0, 0)
  ASSERT_TRUE(img.saveToFile((dir / "m.png").string()));
  putFile(dir / "m.yaml", "image: m.png\nresolution: 0.2\norigin: [1.5, 2.5, 0.0]\n");
  const COccupancyGridMap2D g = readRosMap((dir / "m.yaml").string());
  ASSERT_EQ(g.getSizeX(), 4u);
  ASSERT_EQ(g.getSizeY(), 2u);
  EXPECT_EQ(classifyCell(g.getCell(3, 1)), CellClass::Occupied);
  EXPECT_EQ(classifyCell(g.getCell(0, 0)), CellClass::Unknown);
  EXPECT_EQ(classifyCell(g.getCell(1, 0)), CellClass::Free);
  EXPECT_EQ(gridStats(g).occupied, 1u);

  // A bare image through loadGridMap needs its resolution.
  expectInputError([&] { loadGridMap((dir / "m.png").string()); }, {"m.png", "resolution"});
  MapLoadOptions o;
  o.image_resolution = 0.2;
  o.image_origin_x = 1.5;
  const COccupancyGridMap2D b = loadGridMap((dir / "m.png").string(), o);
  EXPECT_EQ(b.getSizeX(), 4u);
  EXPECT_DOUBLE_EQ(b.getXMin(), 1.5);
  EXPECT_EQ(classifyCell(b.getCell(3, 1)), CellClass::Occupied);
}

TEST(MapIo, RotatedOriginIsResampled) {
  const auto dir = mapScratch("rotated");
  // 4 x 2 image, all free but the top-right pixel (image column 3, row 0 =
  // local x in [3,4), y in [1,2)). A yaw of +90 deg maps local (x, y) to
  // (-y, x): the occupied cell lands at x in [-2,-1), y in [3,4).
  putFile(dir / "r.pgm", pgmP5(4, 2, {254, 254, 254, 0, 254, 254, 254, 254}));
  putFile(dir / "r.yaml", "image: r.pgm\nresolution: 1\norigin: [0, 0, 1.5707963267948966]\n");
  const COccupancyGridMap2D g = readRosMap((dir / "r.yaml").string());
  EXPECT_EQ(g.getSizeX(), 2u);
  EXPECT_EQ(g.getSizeY(), 4u);
  EXPECT_NEAR(g.getXMin(), -2.0, 1e-6);
  EXPECT_NEAR(g.getYMin(), 0.0, 1e-6);
  EXPECT_EQ(classifyCell(g.getPos(-1.5f, 3.5f)), CellClass::Occupied);
  const GridStats s = gridStats(g);
  EXPECT_EQ(s.occupied, 1u);
  EXPECT_EQ(s.free, 7u);
}

// ------------------------------------------------------------ malformed ROS

TEST(MapIo, MalformedRosMapsAreInputErrorsNamingFileAndProblem) {
  const auto dir = mapScratch("malformed");
  putFile(dir / "ok.pgm", pgmP5(2, 2, {0, 254, 205, 254}));
  auto yamlCase = [&](const std::string& name, const std::string& text,
                      const std::vector<std::string>& parts) {
    SCOPED_TRACE(name);
    const auto p = (dir / name).string();
    putFile(p, text);
    std::vector<std::string> all = parts;
    all.push_back(p);
    expectInputError([&] { readRosMap(p); }, all);
  };
  yamlCase("no_res.yaml", "image: ok.pgm\norigin: [0, 0, 0]\n", {"missing key 'resolution'"});
  yamlCase("no_image_key.yaml", "resolution: 0.1\norigin: [0, 0, 0]\n", {"missing key 'image'"});
  yamlCase("no_origin.yaml", "image: ok.pgm\nresolution: 0.1\n", {"missing key 'origin'"});
  yamlCase("neg_res.yaml", rosYaml("ok.pgm", "", "-0.05"), {":2:", "'resolution' must be > 0"});
  yamlCase("zero_res.yaml", rosYaml("ok.pgm", "", "0"), {":2:", "'resolution' must be > 0"});
  yamlCase("tiny_res.yaml", rosYaml("ok.pgm", "", "1e-300"), {":2:", "within [0.001, 100]"});
  yamlCase("huge_res.yaml", rosYaml("ok.pgm", "", "1e9"), {":2:", "within [0.001, 100]"});
  yamlCase("text_res.yaml", rosYaml("ok.pgm", "", "fine"), {":2:", "must be a number", "fine"});
  yamlCase("origin2.yaml", rosYaml("ok.pgm", "", "0.1", "[1, 2]"), {":3:", "3 numbers"});
  yamlCase("origin_text.yaml", rosYaml("ok.pgm", "", "0.1", "here"), {":3:", "3 numbers"});
  yamlCase("missing_image.yaml", rosYaml("nowhere.pgm"), {":1:", "nowhere.pgm", "not found"});
  yamlCase("empty.yaml", "", {"empty file"});
  yamlCase("comments_only.yaml", "# nothing here\n\n", {"empty file"});
  yamlCase("dup.yaml", rosYaml("ok.pgm", "resolution: 0.2\n"),
           {":7:", "duplicate key 'resolution'", "line 2"});
  yamlCase("garbage.yaml", "image: ok.pgm\nthis is not yaml\n", {":2:", "expected 'key: value'"});
  yamlCase("binary.yaml", std::string("\x1f\x8b\x08\0\0\0", 6), {"binary data"});
  yamlCase("negate.yaml", "image: ok.pgm\nresolution: 1\norigin: [0, 0, 0]\nnegate: 7\n",
           {":4:", "'negate' must be 0 or 1"});
  yamlCase("mode.yaml", rosYaml("ok.pgm", "mode: fancy\n"),
           {":7:", "'mode' must be trinary, scale or raw"});
  yamlCase(
      "thresh.yaml",
      "image: ok.pgm\nresolution: 1\norigin: [0,0,0]\noccupied_thresh: 0.1\nfree_thresh: 0.5\n",
      {"'free_thresh' must not exceed 'occupied_thresh'"});
  yamlCase("unterminated.yaml", rosYaml("ok.pgm", "", "0.1", "[1, 2, 3"), {":3:", "unterminated"});

  // Image defects: the message names the image and the YAML that points to it.
  auto imageCase = [&](const std::string& name, const std::string& bytes,
                       const std::vector<std::string>& parts) {
    SCOPED_TRACE(name);
    putFile(dir / name, bytes);
    const auto y = (dir / (name + ".yaml")).string();
    putFile(y, rosYaml(name));
    std::vector<std::string> all = parts;
    all.push_back((dir / name).string());
    all.push_back(y);
    expectInputError([&] { readRosMap(y); }, all);
  };
  std::string truncated = pgmP5(10, 10, std::vector<uint8_t>(100, 254));
  truncated.resize(truncated.size() - 37);
  imageCase("trunc.pgm", truncated, {"truncated pixel data", "63 bytes", "10 x 10 = 100"});
  imageCase("magic.pgm", "XY\n2 2\n255\n0000", {"bad magic 'XY"});
  imageCase("p1.pgm", "P1\n2 2\n0 1 1 0\n", {"bad magic 'P1"});
  imageCase("empty.pgm", "", {"empty file"});
  imageCase("maxval.pgm", pgmP5(2, 2, {0, 0, 0, 0, 0, 0, 0, 0}, 65535), {"maxval 65535 > 255"});
  imageCase("header.pgm", "P5\n2\n", {"truncated header"});
  imageCase("badsize.pgm", "P5\n2 x\n255\n", {"bad height"});
  imageCase("zerosize.pgm", "P5\n0 2\n255\n", {"empty"});
  imageCase("huge.pgm", "P5\n900000 900000\n255\n", {"too large"});
  imageCase("ascii_short.pgm", "P2\n2 2\n255\n0 1 2\n", {"truncated pixel data", "2 x 2 = 4"});
  imageCase("ascii_gap.pgm", "P2\n2 2\n255\n0 1     2\n", {"truncated pixel data", "3 of 4"});
  // Declared sizes are checked against the bytes there before any allocation.
  imageCase("big_small.pgm", "P5\n10000 10000\n255\n" + std::string(10, '\0'),
            {"truncated pixel data", "10 bytes", "10000 x 10000"});
  imageCase("big_ascii.pgm", "P2\n10000 10000\n255\n0 0 0\n", {"truncated pixel data"});
  imageCase("over.pgm", "P5\n20000 20000\n255\n", {"too large", "134217728 pixels"});
  std::string ihdr("\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR\0\x02\0\0\0\x02\0\0", 24);
  imageCase("huge.png", ihdr + std::string(40, '\0') + "IEND", {"image size 131072 x 131072"});
  imageCase("ascii_over.pgm", "P2\n2 2\n15\n0 1 2 99\n", {"pixel value 99 > maxval 15"});
  imageCase("fake.png", "not a png at all", {"not a PNG"});
  mrpt::img::CImage noise(64, 64, mrpt::img::CH_GRAY);
  for (int v = 0; v < 64; ++v)
    for (int u = 0; u < 64; ++u) noise.setPixel(u, v, (u * 37 + v * 101) % 256);
  ASSERT_TRUE(noise.saveToFile((dir / "whole.png").string()));
  const std::string png = slurpFile(dir / "whole.png");
  imageCase("half.png", png.substr(0, png.size() / 2), {"cannot decode"});
}

// ------------------------------------------------------------ MRPT maps

TEST(MapIo, ReadsMrptMalagaCampusGridmap) {
  const COccupancyGridMap2D g = loadGridMap(kMalaga);
  const GridStats s = gridStats(g);
  EXPECT_GT(s.size_x, 100u);
  EXPECT_GT(s.size_y, 100u);
  EXPECT_GT(s.resolution, 0.0);
  EXPECT_GT(s.occupied, 5000u);
  EXPECT_GT(s.free, 50000u);
  EXPECT_EQ(s.occupied + s.free + s.unknown, s.size_x * s.size_y);
  // It survives our own gridmap writer unchanged, cell for cell.
  const auto dir = mapScratch("malaga");
  saveGridMap(g, (dir / "m.gridmap.gz").string());
  const COccupancyGridMap2D r = loadGridMap((dir / "m.gridmap.gz").string());
  EXPECT_EQ(r.getRawMap(), g.getRawMap());
  EXPECT_EQ(r.getXMin(), g.getXMin());
  saveGridMap(g, (dir / "plain.gridmap").string());
  EXPECT_EQ(loadGridMap((dir / "plain.gridmap").string()).getRawMap(), g.getRawMap());
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 2);
  // And through ROS and back, the classes stay.
  writeRosMap(g, (dir / "m.yaml").string());
  expectSameClasses(g, readRosMap((dir / "m.yaml").string()));
}

TEST(MapIo, BuildsGridFromMrptSimplemap) {
  MapLoadOptions o;
  o.simplemap_resolution = 0.1;
  const COccupancyGridMap2D g = loadGridMap(kLocSimplemap, o);
  const GridStats s = gridStats(g);
  EXPECT_NEAR(s.resolution, 0.1, 1e-6);
  EXPECT_GT(s.size_x, 50u);
  EXPECT_GT(s.size_y, 50u);
  EXPECT_GT(s.occupied, 500u);
  EXPECT_GT(s.free, 5000u);
}

TEST(MapIo, WrongKindsOfFileAreInputErrors) {
  const auto dir = mapScratch("kinds");
  expectInputError([&] { loadGridMap(kLocRawlog); }, {kLocRawlog, "is a rawlog, not a map"});
  // A rawlog under a map's name: the message says what it holds.
  fs::copy_file(kLocRawlog, dir / "fake.gridmap");
  expectInputError(
      [&] { loadGridMap((dir / "fake.gridmap").string()); },
      {"fake.gridmap", "holds mrpt::obs::", "looks like a rawlog", "expected an MRPT gridmap"});
  fs::copy_file(kLocSimplemap, dir / "sm.gridmap.gz");
  expectInputError(
      [&] { loadGridMap((dir / "sm.gridmap.gz").string()); },
      {"sm.gridmap.gz", "holds mrpt::maps::CSimpleMap", "expected an MRPT gridmap", ".simplemap"});
  fs::copy_file(kMalaga, dir / "g.simplemap.gz");
  expectInputError([&] { loadGridMap((dir / "g.simplemap.gz").string()); },
                   {"holds mrpt::maps::COccupancyGridMap2D", "expected an MRPT simplemap"});
  putFile(dir / "empty.gridmap.gz", "");
  expectInputError([&] { loadGridMap((dir / "empty.gridmap.gz").string()); }, {"empty file"});
  // Truncated: half of the uncompressed object.
  std::string raw;
  {
    mrpt::io::CFileGZInputStream in(kMalaga);
    char buf[65536];
    size_t n;
    while ((n = in.Read(buf, sizeof buf)) > 0) raw.append(buf, n);
  }
  putFile(dir / "half.gridmap", raw.substr(0, raw.size() / 2));
  expectInputError([&] { loadGridMap((dir / "half.gridmap").string()); },
                   {"half.gridmap", "truncated"});
  putFile(dir / "junk.gridmap", std::string(4096, '\x42'));
  expectInputError([&] { loadGridMap((dir / "junk.gridmap").string()); }, {"junk.gridmap"});
  putFile(dir / "what.bin", "hello");
  expectInputError([&] { loadGridMap((dir / "what.bin").string()); },
                   {"what.bin", "unknown map format"});
  expectInputError([&] { loadGridMap((dir / "none.yaml").string()); },
                   {"none.yaml", "no such file"});
  expectInputError([&] { saveMapByExtension(makeGrid(0, 0, 1, 2, 2), (dir / "x.txt").string()); },
                   {"x.txt", ".gridmap.gz"});
  expectInputError([&] { writeRosMap(makeGrid(0, 0, 1, 2, 2), (dir / "no/such/x.yaml").string()); },
                   {"does not exist"});
}

// ------------------------------------------------------------ render

TEST(MapIo, RenderDrawsClassesNorthUpOverlaysAndUpscales) {
  COccupancyGridMap2D g = makeGrid(0, 0, 0.1, 40, 20, 1.0f);  // 4 x 2 m, free
  for (int cx = 0; cx < 40; ++cx) g.setCell(cx, 19, 0.0f);    // wall along the top (max y)
  for (int cy = 0; cy < 5; ++cy) g.setCell(0, cy, 0.5f);      // unknown at the lower left
  RenderOptions o;
  Overlay traj;
  traj.points = {{0.5, 1.0}, {3.5, 1.0}};
  traj.colour = {255, 0, 0};
  traj.thickness = 3;
  o.overlays.push_back(traj);
  RenderGeometry geo;
  const mrpt::img::CImage img = renderGridMap(g, o, &geo);
  // 40 cells upscaled to >= 800 px: 20 px per cell.
  EXPECT_EQ(img.getWidth(), 800u);
  EXPECT_EQ(img.getHeight(), 400u);
  EXPECT_NEAR(geo.pixels_per_metre, 200.0, 1e-4);
  auto grey = [&](int u, int v) { return *img.ptr<uint8_t>(u, v); };
  EXPECT_EQ(grey(400, 5), 0) << "the wall (max y) is at the top";
  EXPECT_EQ(grey(400, 395), 255) << "free at the bottom";
  EXPECT_EQ(grey(5, 350), 190) << "unknown grey at the lower left";
  EXPECT_EQ(grey(200, 100), 255);
  // The trajectory at y = 1 m is the middle row, in red (PNG channel order
  // is checked by saving and reloading).
  const auto dir = mapScratch("render");
  const std::string png = (dir / "r.png").string();
  renderGridMapPng(g, png, o);
  mrpt::img::CImage back;
  ASSERT_TRUE(back.loadFromFile(png, 1));
  EXPECT_EQ(back.getWidth(), 800u);
  const uint8_t* p = back.ptr<uint8_t>(geo.px(2.0), geo.py(1.0));
  // OpenCV's order is BGR.
  EXPECT_EQ(p[0], 0);
  EXPECT_EQ(p[1], 0);
  EXPECT_EQ(p[2], 255);
  EXPECT_EQ(slurpFile(png).substr(1, 3), "PNG");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
}
