// carenav places add-room|add-place|rename|remove|list|where|check|render|goal
// Rooms and places on a map (docs/places.md); all logic in modules/places.
// This file: the command, add-room, rename and remove.
#include <carenav/places/places_edit.h>
#include <carenav/places/places_report.h>

#include <memory>

#include "places_args.h"

namespace carenav::app {

namespace {

/** `places add-room`: a room from its corners or a rectangle. */
void addAddRoom(CLI::App* cmd, const GlobalOptions& g) {
  struct AddRoomArgs {
    FileArgs f;
    std::string name, polygon, rect;
  };
  auto ar = std::make_shared<AddRoomArgs>();
  auto* add_room = cmd->add_subcommand(
      "add-room", "Add a room: a polygon in the map frame (metres) given by its corners in order");
  add_room->add_option("name", ar->name, "Room name (unique, case-insensitive)")->required();
  auto* poly_opt =
      add_room->add_option("--polygon", ar->polygon, "Corners \"x1,y1 x2,y2 x3,y3 ...\" (metres)");
  add_room->add_option("--rect", ar->rect, "Axis-aligned rectangle x0,y0,x1,y1 (metres)")
      ->excludes(poly_opt);
  addFileOptions(add_room, ar->f, false);
  add_room->callback([ar, &g] {
    if (ar->rect.empty() && ar->polygon.empty())
      throw InputError("add-room: give --polygon or --rect");
    places::Room r;
    r.name = ar->name;
    r.polygon = !ar->rect.empty() ? places::parseRect(ar->rect, "--rect")
                                  : places::parseCorners(ar->polygon, "--polygon corner");
    const std::string path = ar->f.placesPath();
    places::PlacesFile f = places::readPlacesFileOrEmpty(path);
    f.addRoom(r);
    savePlaces(f, path, g);
    std::cout << places::roomAddedText(r);
  });
}

/** `places rename / remove`: rename and remove, references following. */
void addRenameAndRemove(CLI::App* cmd, const GlobalOptions& g) {
  struct RenameArgs {
    FileArgs f;
    std::string old_name, new_name;
  };
  auto rn = std::make_shared<RenameArgs>();
  auto* rename = cmd->add_subcommand("rename", "Rename a room or place (references follow)");
  rename->add_option("old", rn->old_name, "Current name")->required();
  rename->add_option("new", rn->new_name, "New name")->required();
  addFileOptions(rename, rn->f, false);
  rename->callback([rn, &g] {
    const std::string path = rn->f.placesPath();
    places::PlacesFile f = places::readPlacesFile(path);
    f.rename(rn->old_name, rn->new_name);
    savePlaces(f, path, g);
    std::cout << places::renamedText(rn->old_name, rn->new_name);
  });

  struct RemoveArgs {
    FileArgs f;
    std::string name;
  };
  auto rm = std::make_shared<RemoveArgs>();
  auto* remove = cmd->add_subcommand(
      "remove", "Remove a room (its places stay) or a place (rooms lose it as default)");
  remove->add_option("name", rm->name, "Room or place name")->required();
  addFileOptions(remove, rm->f, false);
  remove->callback([rm, &g] {
    const std::string path = rm->f.placesPath();
    places::PlacesFile f = places::readPlacesFile(path);
    f.remove(rm->name);
    savePlaces(f, path, g);
    std::cout << places::removedText(rm->name);
  });
}

void addPlacesCommand(CLI::App& app, const GlobalOptions& g) {
  auto* cmd = app.add_subcommand(
      "places",
      "Rooms (named polygons) and places (named poses) on a map, kept in MAP's .places.yaml: "
      "edit, list, locate a point, check against the map, draw, and turn names into goals");
  cmd->require_subcommand(1);
  addAddRoom(cmd, g);
  addPlacesAddPlace(cmd, g);
  addRenameAndRemove(cmd, g);
  addPlacesList(cmd);
  addPlacesWhere(cmd);
  addPlacesCheck(cmd);
  addPlacesRender(cmd, g);
  addPlacesGoal(cmd);
}

}  // namespace

CARENAV_COMMAND(70, addPlacesCommand);

}  // namespace carenav::app
