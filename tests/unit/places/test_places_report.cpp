// What `carenav places` prints, from the library: JSON shapes and the named
// room as an area.
#include <carenav/common/json.h>
#include <carenav/places/places_report.h>

#include <gtest/gtest.h>

using namespace carenav;
using namespace carenav::places;

namespace {

const std::string kSena = std::string(CARENAV_SOURCE_DIR) + "/maps/sena.places.yaml";

}  // namespace

TEST(PlacesReport, ListJsonHasEveryRoomAndPlaceWithNullsForNone) {
  const PlacesFile f = readPlacesFile(kSena);
  const Json j = listJson(f, kSena);
  ASSERT_EQ(j.at("rooms").size(), f.rooms.size());
  ASSERT_EQ(j.at("places").size(), f.places.size());
  EXPECT_EQ(j.at("rooms")[0].at("name"), "Corridor north");
  EXPECT_EQ(j.at("rooms")[0].at("polygon")[1], Json::array({5.0, 2.5}));
  EXPECT_TRUE(j.at("rooms")[0].at("default_place").is_null());
  EXPECT_EQ(j.at("rooms")[3].at("default_place"), "West corridor");
  EXPECT_EQ(j.at("places")[0].at("kind"), "dock");
  EXPECT_EQ(j.at("places")[0].at("room"), "South hall");
}

TEST(PlacesReport, WhereOutsideEveryRoomIsNullInJsonAndNoneInText) {
  const PlacesFile f = readPlacesFile(kSena);
  const WhereResult w = where(f, 1000, 1000);
  const Json j = whereJson(1000, 1000, w);
  EXPECT_TRUE(j.at("room").is_null());
  EXPECT_EQ(j.at("nearest_place"), "Notice board");
  EXPECT_EQ(whereText(w).rfind("room: (none)\n", 0), 0u);
  const Json empty = whereJson(0, 0, where(PlacesFile{}, 0, 0));
  EXPECT_TRUE(empty.at("nearest_place").is_null());
  EXPECT_TRUE(empty.at("distance").is_null());
}

TEST(PlacesReport, RoomAreaContainsItsPointsAndAMissingRoomNamesTheRooms) {
  const RoomArea a = readRoomArea(kSena, "west HALL");
  EXPECT_EQ(a.name, "West hall");
  EXPECT_TRUE(a.inside(-15, -5));
  EXPECT_FALSE(a.inside(0, 0));
  try {
    readRoomArea(kSena, "attic");
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string w = e.what();
    EXPECT_EQ(w.rfind(kSena + ": no room named 'attic' (rooms: Corridor north, ", 0), 0u) << w;
  }
}
