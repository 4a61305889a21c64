// Rooms (named polygons) and places (named poses) on a map: the model, its
// YAML file, the checks, the current room, and goals by name (docs/places.md).
#pragma once

#include <carenav/common/errors.h>
#include <carenav/io/map_io.h>
#include <carenav/io/map_render.h>

#include <mrpt/math/TPoint2D.h>

#include <optional>
#include <string>
#include <vector>

namespace carenav::places {

using mrpt::maps::COccupancyGridMap2D;
using mrpt::math::TPoint2D;

/** What a place is for (HOBBIT's places, [Puente14, App. Sec. IV-D]). */
enum class PlaceKind { Place, UserSearch, ObjectSearch, Dock };
/** "place", "user-search", "object-search", "dock". */
const char* placeKindName(PlaceKind k);
/** Parses a kind name (exact, lower case); nullopt when unknown. */
std::optional<PlaceKind> parsePlaceKind(const std::string& s);

/** A named polygon in the map frame, metres; vertices in order, either
 *  orientation, closed implicitly (last joins first). */
struct Room {
  std::string name;
  std::vector<TPoint2D> polygon;
  std::string default_place;  ///< a place name, or empty
  int line = 0;               ///< line in the file it was read from (0: not read)
};

/** A named pose in the map frame. */
struct Place {
  std::string name;
  double x = 0, y = 0;
  double heading_deg = 0;  ///< 0 = +x, counter-clockwise
  PlaceKind kind = PlaceKind::Place;
  /** Room the place was explicitly assigned to; empty: the first room (in
   *  file order) whose polygon contains it. */
  std::string room;
  int line = 0;
};

/** The contents of a `.places.yaml` file. */
struct PlacesFile {
  std::vector<Room> rooms;
  std::vector<Place> places;

  const Room* findRoom(const std::string& name) const;    ///< case-insensitive
  const Place* findPlace(const std::string& name) const;  ///< case-insensitive
  Room* findRoom(const std::string& name);
  Place* findPlace(const std::string& name);
  /** Room a place belongs to: its explicit room, else the first room that
   *  contains it; nullptr when none. */
  const Room* roomOf(const Place& p) const;
  /** First room (in file order) containing (x, y); nullptr when none. */
  const Room* roomAt(double x, double y) const;

  /** Adds a room; throws InputError on a bad or duplicate name (rooms and
   *  places share one namespace) or a bad polygon. */
  void addRoom(const Room& r);
  /** Adds a place; throws InputError on a bad or duplicate name, a
   *  non-finite pose, or a `room` that does not exist or does not contain it. */
  void addPlace(const Place& p);
  /** Renames a room or place, updating references (default places, place
   *  rooms). Throws InputError when OLD is missing or NEW is taken/bad. */
  void rename(const std::string& old_name, const std::string& new_name);
  /** Removes a room (its places stay and lose their explicit room) or a
   *  place (a room naming it as default loses its default). */
  void remove(const std::string& name);
};

/** Names compare equal when they are equal after ASCII letters are folded to
 *  lower case; other bytes (UTF-8 sequences) must match exactly. */
bool sameName(const std::string& a, const std::string& b);
/** Empty when `name` is a valid name, else what is wrong: empty, leading or
 *  trailing blanks, control characters, '/' (separates room/place in goals),
 *  or invalid UTF-8. */
std::string nameProblem(const std::string& name);

/** Point in polygon by the crossing number, with points on an edge or a
 *  vertex (within `eps` metres) counted as inside. */
bool pointInPolygon(const std::vector<TPoint2D>& poly, double x, double y, double eps = 1e-9);
/** True when (x, y) lies on an edge or vertex (within eps). */
bool pointOnBoundary(const std::vector<TPoint2D>& poly, double x, double y, double eps = 1e-9);

/** Empty when the polygon is usable, else what is wrong: fewer than 3
 *  vertices, non-finite coordinates, no area. */
std::string polygonProblem(const std::vector<TPoint2D>& poly);

/** The places file next to a map: the map's extension (.gridmap.gz,
 *  .gridmap, .simplemap.gz, .simplemap, .yaml, .yml, .png, .pgm, .ppm) is
 *  replaced by ".places.yaml"; other names get ".places.yaml" appended. */
std::string placesPathForMap(const std::string& map_path);

/** Reads a places file. Throws InputError "FILE:LINE: what" for any defect:
 *  missing/empty file, no or wrong `format`, unknown or duplicated keys,
 *  bad numbers, bad polygons, bad or duplicate names, no final `end: true`
 *  (a truncated file). */
PlacesFile readPlacesFile(const std::string& path);
/** Parses text as if read from `origin` (tests). */
PlacesFile parsePlaces(const std::string& text, const std::string& origin);
/** The YAML text writePlacesFile writes. */
std::string placesToYaml(const PlacesFile& f);
/** Writes atomically: a temporary file next to `path`, then rename. Throws
 *  std::runtime_error when it cannot be written. */
void writePlacesFile(const PlacesFile& f, const std::string& path);

/** Parameters of checkPlaces. */
struct CheckParams {
  /** Free disc a user-search place needs to turn on the spot: the robot's
   *  circumscribed radius, metres. */
  double turn_radius = 0.35;
  io::OccupancyThresholds thresholds;
};

/** One problem found by checkPlaces. */
struct Problem {
  std::string kind;  ///< e.g. "place-outside-rooms", "rooms-overlap"
  std::string what;  ///< a sentence naming the rooms/places
};

/** Every defect of the rooms and places against the map: places outside
 *  every room or outside their explicit room, overlapping rooms, rooms with
 *  no free cell, self-intersecting rooms, default places that do not exist
 *  or lie outside their room, places not on a free cell, user-search places
 *  without a free disc of `turn_radius`. */
std::vector<Problem> checkPlaces(const PlacesFile& f, const COccupancyGridMap2D& map,
                                 const CheckParams& params = {});

/** A goal pose. */
struct Goal {
  double x = 0, y = 0, heading_deg = 0;
  std::string room, place;  ///< resolved names (place empty: room centre)
};

/** "room/place", "room" or "place" to a pose. A place gives its pose; a room
 *  gives its default place, else its most central free cell: the free cell
 *  whose centre lies inside the polygon and is farthest from every cell that
 *  is not free or lies outside the polygon (Euclidean distance transform);
 *  ties go to the lowest row, then column; heading 0. Throws InputError for
 *  an unknown name, a place not in the named room, or a room with no free
 *  cell. */
Goal resolveGoal(const PlacesFile& f, const COccupancyGridMap2D& map, const std::string& name,
                 const io::OccupancyThresholds& t = {});

/** What `where` reports. */
struct WhereResult {
  const Room* room = nullptr;  ///< first containing room
  const Place* nearest = nullptr;
  double distance = 0;  ///< to the nearest place, metres
};
WhereResult where(const PlacesFile& f, double x, double y);

/** Draws the map with translucent coloured rooms, their names, and places
 *  as arrows with names; saved as PNG. */
void renderPlacesPng(const PlacesFile& f, const COccupancyGridMap2D& map, const std::string& path,
                     io::RenderOptions options = {});

}  // namespace carenav::places
