// What the `carenav places` subcommands share: the places file and map
// options, and writing the file back (cmd_places*.cpp).
#pragma once

#include <carenav/common/errors.h>
#include <carenav/io/map_io.h>
#include <carenav/places/places.h>

#include <iostream>
#include <string>

#include "commands.h"

namespace carenav::app {

/** --map and --file. */
struct FileArgs {
  std::string map, file;
  /** The places file: --file, else the one beside --map. */
  std::string placesPath() const {
    if (!file.empty()) return file;
    if (map.empty()) throw InputError("give --map MAP (its places file is used) or --file FILE");
    return places::placesPathForMap(map);
  }
  io::COccupancyGridMap2D grid() const {
    if (map.empty()) throw InputError("--map MAP is required by this command");
    return io::loadGridMap(map);
  }
};

inline void addFileOptions(CLI::App* sub, FileArgs& a, bool map_required) {
  auto* o = sub->add_option("--map", a.map,
                            "Map (.gridmap(.gz), .simplemap(.gz), ROS .yaml); its places file is "
                            "MAP with the extension replaced by .places.yaml");
  if (map_required) o->required();
  sub->add_option("--file", a.file, "Places file to use instead of the one beside the map");
}

/** Writes the places file and says so on stderr (unless -q). */
inline void savePlaces(const places::PlacesFile& f, const std::string& path,
                       const GlobalOptions& g) {
  places::writePlacesFile(f, path);
  if (!g.quiet) std::cerr << "[places] wrote " << path << "\n";
}

// The subcommands not in cmd_places.cpp, each in a file of its own group.
/** `add-place`: a pose, or where a rawlog ends (cmd_places_add_place.cpp). */
void addPlacesAddPlace(CLI::App* cmd, const GlobalOptions& g);
/** `list`, `where`, `goal`: answers (cmd_places_query.cpp). */
void addPlacesList(CLI::App* cmd);
void addPlacesWhere(CLI::App* cmd);
void addPlacesGoal(CLI::App* cmd);
/** `check`, `render`: against the map (cmd_places_check.cpp). */
void addPlacesCheck(CLI::App* cmd);
void addPlacesRender(CLI::App* cmd, const GlobalOptions& g);

}  // namespace carenav::app
