// What `carenav places` prints: each answer as JSON (`--json`) and as text,
// and a named room as an area to test points against.
#pragma once

#include <carenav/common/json_fwd.h>
#include <carenav/places/places.h>

#include <functional>
#include <string>
#include <vector>

namespace carenav::places {

/** `list`: every room (polygon, default place) and place (pose, kind, room). */
Json listJson(const PlacesFile& f, const std::string& path);
std::string listText(const PlacesFile& f, const std::string& path);

/** `where`: the room at (x, y) and the nearest place (null when none). */
Json whereJson(double x, double y, const WhereResult& w);
std::string whereText(const WhereResult& w);

/** `check`: the problems against the map; the text says "no problem" when
 *  there is none. */
Json checkJson(const std::string& path, const std::string& map, double turn_radius,
               const std::vector<Problem>& problems);
std::string checkText(const PlacesFile& f, const std::string& path,
                      const std::vector<Problem>& problems);

/** `goal`: the pose of `name` (text: "x y heading_deg"). */
Json goalJson(const std::string& name, const Goal& g);
std::string goalText(const Goal& g);

/** `check`'s error when there are problems: "FILE: N problem(s)". */
std::string checkFailureText(const std::string& path, const std::vector<Problem>& problems);

/** The edits: `room "NAME" added (N corners)`, `place "NAME" added in room
 *  "ROOM"` (or "in no room"), `"OLD" renamed to "NEW"`, `"NAME" removed`;
 *  each one line. */
std::string roomAddedText(const Room& r);
std::string placeAddedText(const Place& p, const Room* room);
std::string renamedText(const std::string& old_name, const std::string& new_name);
std::string removedText(const std::string& name);

/** A room of a places file as an area: its name and whether a point lies
 *  inside (edges included). */
struct RoomArea {
  std::string name;
  std::function<bool(double x, double y)> inside;
};
/** The named room (case-insensitive) of a places file. Throws InputError
 *  "FILE: no room named 'NAME' (rooms: ...)" when it has none of that name. */
RoomArea readRoomArea(const std::string& places_file, const std::string& name);

}  // namespace carenav::places
