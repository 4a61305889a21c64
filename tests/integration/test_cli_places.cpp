// carenav places ..., run as a user would, on the shipped SENA map and on a
// map the test converts from MRPT's localization_demo simplemap.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "cli_helpers.h"

using namespace carenav_test;
namespace fs = std::filesystem;

namespace {
const std::string kSenaMap = kSrc + "/maps/sena.gridmap.gz";
const std::string kSenaPlaces = kSrc + "/maps/sena.places.yaml";

fs::path placesDir(const std::string& name) {
  const auto d = scratch() / ("places_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

bool isPng(const fs::path& p) {
  return slurp(p).substr(0, 8) == std::string("\x89PNG\r\n\x1a\n", 8);
}
}  // namespace

TEST(CliPlaces, HelpForEverySubcommand) {
  for (const char* sub :
       {"add-room", "add-place", "rename", "remove", "list", "where", "check", "render", "goal"}) {
    const RunResult r = carenav({"places", sub, "--help"});
    EXPECT_EQ(r.code, 0) << sub;
    EXPECT_NE(r.out.find("Usage:"), std::string::npos) << sub;
  }
  EXPECT_EQ(carenav({"places"}).code, 2);
  EXPECT_EQ(carenav({"places", "list"}).code, 2);  // neither --map nor --file
}

TEST(CliPlaces, ShippedSenaPlacesAreClean) {
  ASSERT_TRUE(fs::exists(kSenaMap));
  ASSERT_TRUE(fs::exists(kSenaPlaces));
  RunResult r = carenav({"places", "check", "--map", kSenaMap});
  EXPECT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("no problem"), std::string::npos);
  r = carenav({"places", "check", "--map", kSenaMap, "--profile", kSrc + "/ini/hobbit.ini"});
  EXPECT_EQ(r.code, 0) << r.out << r.err;
  r = carenav({"places", "list", "--map", kSenaMap, "--json"});
  EXPECT_EQ(r.code, 0) << r.err;
  for (const char* kind : {"\"user-search\"", "\"dock\"", "\"object-search\""})
    EXPECT_NE(r.out.find(kind), std::string::npos) << kind;
  // A room with a default place, a place by name, and a room without one.
  r = carenav({"places", "goal", "west hall", "--map", kSenaMap});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out, "-14.000 -8.000 0.000\n");
  r = carenav({"places", "goal", "South hall/Dock", "--map", kSenaMap, "--json"});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("\"place\": \"Dock\""), std::string::npos) << r.out;
  r = carenav({"places", "goal", "Corridor south", "--map", kSenaMap, "--json"});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("\"place\": null"), std::string::npos) << r.out;
  r = carenav({"places", "where", "0,-16", "--map", kSenaMap});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("room: Corridor south"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("nearest place: Dock"), std::string::npos) << r.out;
  r = carenav({"places", "where", "-30,0", "--map", kSenaMap, "--json"});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("\"room\": null"), std::string::npos) << r.out;
  r = carenav({"places", "goal", "Kitchen", "--map", kSenaMap});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("no room or place"), std::string::npos) << r.err;
}

TEST(CliPlaces, EditCheckRenderOnAConvertedMap) {
  const auto d = placesDir("edit");
  const std::string map = (d / "loc.gridmap.gz").string();
  RunResult r = carenav({"map", "convert", kDatasets + "/localization_demo.simplemap.gz", map});
  ASSERT_EQ(r.code, 0) << r.err;
  // The grid's extent, for rooms that surely hold free cells.
  r = carenav({"map", "info", map});
  ASSERT_EQ(r.code, 0);
  const std::string places = (d / "loc.places.yaml").string();

  r = carenav({"-q", "places", "add-room", "Everything", "--rect=-100,-100,100,100", "--map", map});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::exists(places));
  r = carenav({"places", "add-room", "EVERYTHING", "--rect", "0,0,1,1", "--map", map});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("taken"), std::string::npos) << r.err;
  r = carenav({"places", "add-room", "Bad", "--polygon", "0,0 1,x 2,2", "--map", map});
  EXPECT_EQ(r.code, 2);
  r = carenav({"-q", "places", "add-place", "Centre", "--pose", "0,0,90", "--kind", "user-search",
               "--default", "--map", map});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("room \"Everything\""), std::string::npos) << r.out;
  r = carenav({"places", "add-place", "X", "--pose", "0,0", "--map", map});
  EXPECT_EQ(r.code, 2);
  r = carenav({"places", "add-place", "Y", "--pose", "0,0,0", "--kind", "sofa", "--map", map});
  EXPECT_EQ(r.code, 2);

  r = carenav({"-q", "places", "rename", "centre", "Middle", "--map", map});
  EXPECT_EQ(r.code, 0) << r.err;
  r = carenav({"places", "list", "--map", map});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("(default: Middle)"), std::string::npos) << r.out;
  r = carenav({"places", "goal", "everything", "--map", map, "--json"});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("\"place\": \"Middle\""), std::string::npos) << r.out;

  // A place far out on unknown cells: check lists it and exits 2.
  r = carenav({"-q", "places", "add-place", "Lost", "--pose", "99,99,0", "--map", map});
  EXPECT_EQ(r.code, 0) << r.err;
  r = carenav({"places", "check", "--map", map, "--radius", "0.3"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("\"Lost\""), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("problem"), std::string::npos) << r.err;
  r = carenav({"places", "check", "--map", map, "--json"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("\"problems\": ["), std::string::npos) << r.out;
  r = carenav({"-q", "places", "remove", "lost", "--map", map});
  EXPECT_EQ(r.code, 0) << r.err;

  const auto png = d / "places.png";
  r = carenav({"-q", "places", "render", "--map", map, "--out", png.string()});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(isPng(png));
}

TEST(CliPlaces, BrokenFilesExitTwoWithTheLine) {
  const auto d = placesDir("broken");
  const std::string file = (d / "p.places.yaml").string();
  std::string text = slurp(kSenaPlaces);
  ASSERT_GT(text.size(), 100u);
  {  // cut in the middle of a polygon line
    std::ofstream o(file, std::ios::binary);
    o << text.substr(0, text.find("polygon") + 20);
  }
  RunResult r = carenav({"places", "list", "--file", file});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(file + ":5:"), std::string::npos) << r.err;
  {
    std::ofstream o(file, std::ios::binary);
    o << "format: 1\nrooms:\n  - name: A\n    polygon: [[0, 0], [1, 0], [1, 1]]\n    "
         "colour: red\nend: true\n";
  }
  r = carenav({"places", "list", "--file", file});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(file + ":5: unknown key \"colour\""), std::string::npos) << r.err;
  { std::ofstream o(file, std::ios::binary); }
  r = carenav({"places", "where", "0,0", "--file", file});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("empty"), std::string::npos) << r.err;
  r = carenav({"places", "list", "--file", (d / "none.yaml").string()});
  EXPECT_EQ(r.code, 2);
  r = carenav(
      {"places", "check", "--map", (d / "none.gridmap.gz").string(), "--file", kSenaPlaces});
  EXPECT_EQ(r.code, 2);
}
