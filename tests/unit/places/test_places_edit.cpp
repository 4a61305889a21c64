// Editing a places file from command-line text (places_edit.h) and the edit
// messages of places_report.h.
#include <carenav/places/places_edit.h>
#include <carenav/places/places_report.h>

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

using namespace carenav;
using namespace carenav::places;
namespace fs = std::filesystem;

namespace {

/** The message of the InputError `f` throws ("" when it throws none). */
template <class F>
std::string inputError(F f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

PlacesFile oneRoom() {
  PlacesFile f;
  Room r;
  r.name = "Lab";
  r.polygon = parseRect("0,0,4,3", "--rect");
  f.addRoom(r);
  return f;
}

}  // namespace

TEST(PlacesEdit, ParseNumbersTakesExactlyCountFiniteNumbers) {
  EXPECT_EQ(parseNumbers("1.5,-2,90", "--pose", 3), (std::vector<double>{1.5, -2, 90}));
  EXPECT_EQ(parseNumbers(" 1,2", "point", 2), (std::vector<double>{1, 2}));  // blank before
  EXPECT_EQ(inputError([] { parseNumbers("1,2,3", "--rect", 4); }),
            "--rect \"1,2,3\": expected 4 numbers separated by commas");
  EXPECT_EQ(inputError([] { parseNumbers("1,2,", "point", 2); }),
            "point \"1,2,\": expected 2 numbers separated by commas");
  EXPECT_EQ(inputError([] { parseNumbers("1 ,2", "point", 2); }),
            "point \"1 ,2\": \"1 \" is not a finite number");
  EXPECT_EQ(inputError([] { parseNumbers("1,,2", "point", 3); }),
            "point \"1,,2\": \"\" is not a finite number");
  for (const char* bad : {"x,1", "nan,1", "1e999,1", "inf,1", "1x,1"})
    EXPECT_NE(inputError([&] { parseNumbers(bad, "p", 2); }).find("is not a finite number"),
              std::string::npos)
        << bad;
}

TEST(PlacesEdit, RectangleAndCornersBecomePolygons) {
  const auto rect = parseRect("0,1,4,3", "--rect");
  ASSERT_EQ(rect.size(), 4u);
  EXPECT_EQ(rect[1], TPoint2D(4, 1));
  EXPECT_EQ(rect[3], TPoint2D(0, 3));
  const auto poly = parseCorners("0,0  5,0 5,2", "--polygon corner");
  ASSERT_EQ(poly.size(), 3u);
  EXPECT_EQ(poly[2], TPoint2D(5, 2));
  EXPECT_TRUE(parseCorners("", "--polygon corner").empty());
  EXPECT_EQ(inputError([] { parseCorners("0,0 1", "--polygon corner"); }),
            "--polygon corner \"1\": expected 2 numbers separated by commas");
}

TEST(PlacesEdit, AMissingFileReadsEmptyAndAnExistingOneAsWritten) {
  const auto dir =
      fs::temp_directory_path() / ("carenav_places_edit_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string path = (dir / "x.places.yaml").string();
  fs::remove(path);
  EXPECT_TRUE(readPlacesFileOrEmpty(path).rooms.empty());
  writePlacesFile(oneRoom(), path);
  EXPECT_EQ(readPlacesFileOrEmpty(path).rooms.at(0).name, "Lab");
  fs::remove_all(dir);
}

TEST(PlacesEdit, AddPlaceToRoomReturnsItsRoomAndSetsTheDefault) {
  PlacesFile f = oneRoom();
  Place p;
  p.name = "Desk";
  p.x = 1, p.y = 1;
  const Room* room = addPlaceToRoom(f, p, true);
  ASSERT_NE(room, nullptr);
  EXPECT_EQ(room->name, "Lab");
  EXPECT_EQ(f.rooms[0].default_place, "Desk");
  EXPECT_EQ(placeAddedText(p, room), "place \"Desk\" added in room \"Lab\"\n");

  p.name = "Far";
  p.x = 10;
  EXPECT_EQ(addPlaceToRoom(f, p, false), nullptr);
  EXPECT_EQ(placeAddedText(p, nullptr), "place \"Far\" added in no room\n");
  p.name = "Farther";
  EXPECT_EQ(inputError([&] { addPlaceToRoom(f, p, true); }),
            "--default: place \"Farther\" lies in no room");
}

TEST(PlacesReport, EditAndCheckFailureTexts) {
  EXPECT_EQ(roomAddedText(oneRoom().rooms[0]), "room \"Lab\" added (4 corners)\n");
  EXPECT_EQ(renamedText("a", "b"), "\"a\" renamed to \"b\"\n");
  EXPECT_EQ(removedText("a"), "\"a\" removed\n");
  EXPECT_EQ(checkFailureText("f.yaml", std::vector<Problem>(1)), "f.yaml: 1 problem");
  EXPECT_EQ(checkFailureText("f.yaml", std::vector<Problem>(3)), "f.yaml: 3 problems");
}
