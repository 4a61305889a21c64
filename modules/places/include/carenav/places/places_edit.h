// Editing a places file from the command line: numbers, rectangles, polygons
// and poses given as text; a file read or started empty; a place added with
// its room's default.
#pragma once

#include <carenav/places/places.h>

#include <string>
#include <vector>

namespace carenav::places {

/** Exactly `count` finite numbers separated by commas ("1.5,-2,90"). Throws
 *  InputError `WHAT "TEXT": "ITEM" is not a finite number` or `WHAT "TEXT":
 *  expected COUNT numbers separated by commas` (`what` names the option). */
std::vector<double> parseNumbers(const std::string& text, const std::string& what, size_t count);

/** The four corners of the axis-aligned rectangle "x0,y0,x1,y1", in order.
 *  Throws like parseNumbers. */
std::vector<TPoint2D> parseRect(const std::string& text, const std::string& what);

/** Corners "x1,y1 x2,y2 ..." separated by blanks (none: an empty polygon).
 *  Throws like parseNumbers for each corner. */
std::vector<TPoint2D> parseCorners(const std::string& text, const std::string& what);

/** The places file at `path`, or an empty one when there is no such file. */
PlacesFile readPlacesFileOrEmpty(const std::string& path);

/** Adds `p` and returns the room it belongs to (nullptr: none). With
 *  `make_default` the place becomes its room's default place; throws
 *  InputError `--default: place "NAME" lies in no room` when it has none. */
const Room* addPlaceToRoom(PlacesFile& f, const Place& p, bool make_default);

}  // namespace carenav::places
