// carenav places add-place NAME (--pose x,y,deg | --here --rawlog R [--init ..|--in-room ROOM])
// A place from its pose, or from where the robot is at the end of a rawlog.
#include <carenav/common/text.h>
#include <carenav/localization/pose_at_end.h>
#include <carenav/places/places_edit.h>
#include <carenav/places/places_report.h>

#include <cmath>
#include <memory>

#include "places_args.h"

namespace carenav::app {

namespace {

struct AddPlaceArgs {
  FileArgs f;
  std::string name, pose, kind = "place", room;
  bool make_default = false;
  // --here: the pose where localisation on a rawlog ends
  bool here = false;
  std::string rawlog, profile, init, in_room;
  std::vector<std::string> sets;
};

/** --here: localise the rawlog on the map (a converged final estimate). */
void setPoseHere(const AddPlaceArgs& a, const GlobalOptions& g, places::Place& p) {
  if (a.f.map.empty()) throw InputError("add-place --here: --map MAP is required");
  if (a.rawlog.empty()) throw InputError("add-place --here: --rawlog R is required");
  localization::LocalizeJobOptions o;
  o.params = localization::localizationParamsOf(a.profile, a.sets);
  o.map = a.f.map;
  o.rawlog = a.rawlog;
  o.progress = !g.quiet;
  if (!a.init.empty()) {
    o.init = localization::parseInitialPose(a.init);
  } else if (!a.in_room.empty()) {
    const places::RoomArea room = places::readRoomArea(a.f.placesPath(), a.in_room);
    o.region = {room.name, room.inside};
  } else {
    o.global = true;
  }
  const localization::EndPose e = localization::poseAtEnd(o);
  p.x = e.x, p.y = e.y, p.heading_deg = e.yaw * 180 / M_PI;
  if (!g.quiet)
    std::cerr << "[places] localised " << e.scans << " scans; the rawlog ends at ("
              << formatFixed(p.x) << ", " << formatFixed(p.y) << ", " << formatFixed(p.heading_deg)
              << " deg), spread " << formatFixed(e.spread) << " m\n";
}

void addOptions(CLI::App* sub, AddPlaceArgs& a) {
  sub->add_option("name", a.name, "Place name (unique, case-insensitive)")->required();
  auto* pose_opt = sub->add_option("--pose", a.pose, "x,y,heading_deg in the map frame");
  auto* here_opt = sub->add_flag(
      "--here", a.here,
      "The pose where the robot is at the end of --rawlog: localise the rawlog on --map "
      "(how a facilitator records a place by driving the robot there)");
  pose_opt->excludes(here_opt);
  sub->add_option("--rawlog", a.rawlog, "With --here: the rawlog that ends at the place");
  sub->add_option("--profile", a.profile,
                  "With --here: robot profile for localisation (its [localization] "
                  "section; default: the built-in defaults)");
  sub->add_option("--init", a.init,
                  "With --here: initial pose x,y,deg[,sx,sy,sdeg] of the rawlog (default: "
                  "global localisation, or --in-room)");
  sub->add_option("--in-room", a.in_room,
                  "With --here: the rawlog starts in this room of the places file");
  sub->add_option("--set", a.sets, "With --here: override a profile value s.k=v");
  sub->add_option("--kind", a.kind, "place (default), user-search, object-search, dock")
      ->check(CLI::IsMember({"place", "user-search", "object-search", "dock"}));
  sub->add_option("--room", a.room,
                  "Assign the place to this room (it must lie inside it); default: the "
                  "first room containing it");
  sub->add_flag("--default", a.make_default,
                "Make it the default place of its room (the goal for the room's name)");
  addFileOptions(sub, a.f, false);
}

}  // namespace

/** `places add-place`: a place from its pose, or from where a rawlog ends (--here). */
void addPlacesAddPlace(CLI::App* cmd, const GlobalOptions& g) {
  auto ap = std::make_shared<AddPlaceArgs>();
  auto* add_place = cmd->add_subcommand(
      "add-place",
      "Add a place: a pose x,y,heading (metres, degrees) with a kind; it belongs to the room "
      "that contains it, or to --room");
  addOptions(add_place, *ap);
  add_place->callback([ap, &g] {
    places::Place p;
    p.name = ap->name;
    if (ap->here) {
      setPoseHere(*ap, g, p);
    } else {
      if (ap->pose.empty()) throw InputError("add-place: give --pose x,y,deg or --here");
      if (!ap->rawlog.empty() || !ap->init.empty() || !ap->in_room.empty())
        throw InputError("add-place: --rawlog, --init and --in-room go with --here");
      const auto v = places::parseNumbers(ap->pose, "--pose", 3);
      p.x = v[0], p.y = v[1], p.heading_deg = v[2];
    }
    p.kind = *places::parsePlaceKind(ap->kind);
    p.room = ap->room;
    const std::string path = ap->f.placesPath();
    places::PlacesFile f = places::readPlacesFileOrEmpty(path);
    const places::Room* room = places::addPlaceToRoom(f, p, ap->make_default);
    savePlaces(f, path, g);
    std::cout << places::placeAddedText(p, room);
    if (!room && !g.quiet)
      std::cerr << "[places] warning: \"" << p.name << "\" lies outside every room\n";
  });
}

}  // namespace carenav::app
