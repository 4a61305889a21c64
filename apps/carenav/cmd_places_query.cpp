// carenav places list|where|goal: answers from a places file (and, for goal,
// its map); their text and JSON are in modules/places (places_report.h).
#include <carenav/common/json.h>
#include <carenav/places/places_edit.h>
#include <carenav/places/places_report.h>

#include <memory>

#include "places_args.h"

namespace carenav::app {

namespace {

/** stdout: the answer as JSON (one line) or as text. */
void answer(bool json, const Json& j, const std::string& text) {
  std::cout << (json ? dumpJson(j) + "\n" : text);
}

}  // namespace

/** `places list`: every room and its places. */
void addPlacesList(CLI::App* cmd) {
  struct ListArgs {
    FileArgs f;
    bool json = false;
  };
  auto a = std::make_shared<ListArgs>();
  auto* list = cmd->add_subcommand("list", "List rooms and the places in each");
  addFileOptions(list, a->f, false);
  list->add_flag("--json", a->json, "Print JSON");
  list->callback([a] {
    const std::string path = a->f.placesPath();
    const places::PlacesFile f = places::readPlacesFile(path);
    answer(a->json, places::listJson(f, path), places::listText(f, path));
  });
}

/** `places where`: the room at a point and the nearest place. */
void addPlacesWhere(CLI::App* cmd) {
  struct WhereArgs {
    FileArgs f;
    std::string at;
    bool json = false;
  };
  auto a = std::make_shared<WhereArgs>();
  auto* where = cmd->add_subcommand(
      "where",
      "The room containing a point and the nearest place (write a negative x as "
      "`where -- -1.5,2`)");
  where->add_option("point", a->at, "x,y in the map frame (metres)")->required();
  addFileOptions(where, a->f, false);
  where->add_flag("--json", a->json, "Print JSON");
  where->callback([a] {
    const auto v = places::parseNumbers(a->at, "point", 2);
    const places::PlacesFile f = places::readPlacesFile(a->f.placesPath());
    const places::WhereResult w = places::where(f, v[0], v[1]);
    answer(a->json, places::whereJson(v[0], v[1], w), places::whereText(w));
  });
}

/** `places goal`: a name to a goal pose. */
void addPlacesGoal(CLI::App* cmd) {
  struct GoalArgs {
    FileArgs f;
    std::string name;
    bool json = false;
  };
  auto a = std::make_shared<GoalArgs>();
  auto* goal = cmd->add_subcommand(
      "goal",
      "The goal pose of \"room/place\", \"place\" or \"room\" (its default place, else its most "
      "central free cell): prints x y heading_deg");
  goal->add_option("name", a->name, "room/place, place or room")->required();
  addFileOptions(goal, a->f, true);
  goal->add_flag("--json", a->json, "Print JSON");
  goal->callback([a] {
    const places::PlacesFile f = places::readPlacesFile(a->f.placesPath());
    const places::Goal r = places::resolveGoal(f, a->f.grid(), a->name);
    answer(a->json, places::goalJson(a->name, r), places::goalText(r));
  });
}

}  // namespace carenav::app
