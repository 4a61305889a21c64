// carenav places add-room|add-place|rename|remove|list|where|check|render|goal
// Rooms and places on a map (docs/places.md); all logic in modules/places.
#include <carenav/common/errors.h>
#include <carenav/common/json.h>
#include <carenav/common/profile.h>
#include <carenav/common/robot.h>
#include <carenav/io/map_io.h>
#include <carenav/localization/localize_job.h>
#include <carenav/places/places.h>
#include <carenav/places/places_report.h>

#include <array>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>

#include "commands.h"

namespace carenav::app {

namespace {

using places::PlacesFile;

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

void addFileOptions(CLI::App* sub, FileArgs& a, bool map_required) {
  auto* o = sub->add_option("--map", a.map,
                            "Map (.gridmap(.gz), .simplemap(.gz), ROS .yaml); its places file is "
                            "MAP with the extension replaced by .places.yaml");
  if (map_required) o->required();
  sub->add_option("--file", a.file, "Places file to use instead of the one beside the map");
}

std::vector<double> numbers(const std::string& text, const std::string& what, size_t count) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    errno = 0;
    const double d = std::strtod(item.c_str(), &end);
    if (item.empty() || end != item.c_str() + item.size() || errno == ERANGE || !std::isfinite(d))
      throw InputError(what + " \"" + text + "\": \"" + item + "\" is not a finite number");
    out.push_back(d);
  }
  if (out.size() != count || (!text.empty() && text.back() == ','))
    throw InputError(what + " \"" + text + "\": expected " + std::to_string(count) +
                     " numbers separated by commas");
  return out;
}

PlacesFile loadOrEmpty(const std::string& path) {
  if (!std::filesystem::exists(path)) return {};
  return places::readPlacesFile(path);
}

void save(const PlacesFile& f, const std::string& path, const GlobalOptions& g) {
  places::writePlacesFile(f, path);
  if (!g.quiet) std::cerr << "[places] wrote " << path << "\n";
}

/** The --in-room region of localisation. */
localization::LocalizeJobOptions::Region inRoom(const std::string& places_file,
                                                const std::string& name) {
  const places::RoomArea room = places::readRoomArea(places_file, name);
  return {room.name, room.inside};
}

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3f", v);
  return b;
}

/** add-place --here: localise the rawlog on the map; the final estimate,
 *  which must have converged, is the place's pose (x, y, degrees). */
template <class Args>
std::array<double, 3> poseAtEndOfRawlog(const Args& a, const GlobalOptions& g) {
  if (a.f.map.empty()) throw InputError("add-place --here: --map MAP is required");
  if (a.rawlog.empty()) throw InputError("add-place --here: --rawlog R is required");
  Profile prof = a.profile.empty() ? Profile::fromText("[localization]\n", "(embedded defaults)")
                                   : Profile::load(a.profile);
  prof.applyOverrides(a.sets);
  if (!a.profile.empty()) {
    prof.validate();
  } else {
    for (const auto& s : a.sets)
      if (s.rfind("localization.", 0) != 0)
        throw InputError("--set '" + s +
                         "': without --profile only localization.* values can be set");
  }
  localization::LocalizeJobOptions o;
  o.params = prof.section<localization::LocalizationParams>("localization");
  o.map = a.f.map;
  o.rawlog = a.rawlog;
  o.progress = !g.quiet;
  if (!a.init.empty())
    o.init = localization::parseInitialPose(a.init);
  else if (!a.in_room.empty())
    o.region = inRoom(a.f.placesPath(), a.in_room);
  else
    o.global = true;
  const auto r = localization::runLocalize(o);
  if (r.rawlog_error) throw InputError(*r.rawlog_error + " (add-place --here needs the whole log)");
  if (!r.converged_at_end) {
    std::ostringstream m;
    m << "add-place --here: localisation on " << a.rawlog << " has not converged at its end "
      << "(particle spread " << r.final_spread << " m); give --init or --in-room, or drive "
      << "longer before the place";
    throw std::runtime_error(m.str());
  }
  const auto& e = r.track.back();
  if (!g.quiet)
    std::cerr << "[places] localised " << r.scans << " scans; the rawlog ends at (" << fmt(e.x)
              << ", " << fmt(e.y) << ", " << fmt(e.yaw * 180 / M_PI) << " deg), spread "
              << fmt(r.final_spread) << " m\n";
  return {e.x, e.y, e.yaw * 180 / M_PI};
}

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
    places::Room r;
    r.name = ar->name;
    if (!ar->rect.empty()) {
      const auto v = numbers(ar->rect, "--rect", 4);
      r.polygon = {{v[0], v[1]}, {v[2], v[1]}, {v[2], v[3]}, {v[0], v[3]}};
    } else if (!ar->polygon.empty()) {
      std::stringstream ss(ar->polygon);
      std::string corner;
      while (ss >> corner) {
        const auto v = numbers(corner, "--polygon corner", 2);
        r.polygon.push_back({v[0], v[1]});
      }
    } else {
      throw InputError("add-room: give --polygon or --rect");
    }
    const std::string path = ar->f.placesPath();
    PlacesFile f = loadOrEmpty(path);
    f.addRoom(r);
    save(f, path, g);
    std::cout << "room \"" << r.name << "\" added (" << r.polygon.size() << " corners)\n";
  });
}

/** `places add-place`: a place from its pose, or from where a rawlog ends (--here). */
void addAddPlace(CLI::App* cmd, const GlobalOptions& g) {
  struct AddPlaceArgs {
    FileArgs f;
    std::string name, pose, kind = "place", room;
    bool make_default = false;
    // --here: the pose where localisation on a rawlog ends
    bool here = false;
    std::string rawlog, profile, init, in_room;
    std::vector<std::string> sets;
  };
  auto ap = std::make_shared<AddPlaceArgs>();
  auto* add_place = cmd->add_subcommand(
      "add-place",
      "Add a place: a pose x,y,heading (metres, degrees) with a kind; it belongs to the room "
      "that contains it, or to --room");
  add_place->add_option("name", ap->name, "Place name (unique, case-insensitive)")->required();
  auto* pose_opt = add_place->add_option("--pose", ap->pose, "x,y,heading_deg in the map frame");
  auto* here_opt = add_place->add_flag(
      "--here", ap->here,
      "The pose where the robot is at the end of --rawlog: localise the rawlog on --map "
      "(how a facilitator records a place by driving the robot there)");
  pose_opt->excludes(here_opt);
  add_place->add_option("--rawlog", ap->rawlog, "With --here: the rawlog that ends at the place");
  add_place->add_option("--profile", ap->profile,
                        "With --here: robot profile for localisation (its [localization] "
                        "section; default: the built-in defaults)");
  add_place->add_option("--init", ap->init,
                        "With --here: initial pose x,y,deg[,sx,sy,sdeg] of the rawlog (default: "
                        "global localisation, or --in-room)");
  add_place->add_option("--in-room", ap->in_room,
                        "With --here: the rawlog starts in this room of the places file");
  add_place->add_option("--set", ap->sets, "With --here: override a profile value s.k=v");
  add_place->add_option("--kind", ap->kind, "place (default), user-search, object-search, dock")
      ->check(CLI::IsMember({"place", "user-search", "object-search", "dock"}));
  add_place->add_option("--room", ap->room,
                        "Assign the place to this room (it must lie inside it); default: the "
                        "first room containing it");
  add_place->add_flag("--default", ap->make_default,
                      "Make it the default place of its room (the goal for the room's name)");
  addFileOptions(add_place, ap->f, false);
  add_place->callback([ap, &g] {
    places::Place p;
    p.name = ap->name;
    if (ap->here) {
      const auto pose = poseAtEndOfRawlog(*ap, g);
      p.x = pose[0], p.y = pose[1], p.heading_deg = pose[2];
    } else {
      if (ap->pose.empty()) throw InputError("add-place: give --pose x,y,deg or --here");
      if (!ap->rawlog.empty() || !ap->init.empty() || !ap->in_room.empty())
        throw InputError("add-place: --rawlog, --init and --in-room go with --here");
      const auto v = numbers(ap->pose, "--pose", 3);
      p.x = v[0], p.y = v[1], p.heading_deg = v[2];
    }
    p.kind = *places::parsePlaceKind(ap->kind);
    p.room = ap->room;
    const std::string path = ap->f.placesPath();
    PlacesFile f = loadOrEmpty(path);
    f.addPlace(p);
    const places::Room* room = f.roomOf(f.places.back());
    if (ap->make_default) {
      if (!room) throw InputError("--default: place \"" + p.name + "\" lies in no room");
      f.findRoom(room->name)->default_place = p.name;
    }
    save(f, path, g);
    std::cout << "place \"" << p.name << "\" added in "
              << (room ? "room \"" + room->name + "\"" : std::string("no room")) << "\n";
    if (!room && !g.quiet)
      std::cerr << "[places] warning: \"" << p.name << "\" lies outside every room\n";
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
    PlacesFile f = places::readPlacesFile(path);
    f.rename(rn->old_name, rn->new_name);
    save(f, path, g);
    std::cout << "\"" << rn->old_name << "\" renamed to \"" << rn->new_name << "\"\n";
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
    PlacesFile f = places::readPlacesFile(path);
    f.remove(rm->name);
    save(f, path, g);
    std::cout << "\"" << rm->name << "\" removed\n";
  });
}

/** `places list`: every room and its places. */
void addList(CLI::App* cmd) {
  struct ListArgs {
    FileArgs f;
    bool json = false;
  };
  auto ls = std::make_shared<ListArgs>();
  auto* list = cmd->add_subcommand("list", "List rooms and the places in each");
  addFileOptions(list, ls->f, false);
  list->add_flag("--json", ls->json, "Print JSON");
  list->callback([ls] {
    const std::string path = ls->f.placesPath();
    const PlacesFile f = places::readPlacesFile(path);
    std::cout << (ls->json ? dumpJson(places::listJson(f, path)) + "\n"
                           : places::listText(f, path));
  });
}

/** `places where`: the room at a point and the nearest place. */
void addWhere(CLI::App* cmd) {
  struct WhereArgs {
    FileArgs f;
    std::string at;
    bool json = false;
  };
  auto wh = std::make_shared<WhereArgs>();
  auto* where = cmd->add_subcommand(
      "where",
      "The room containing a point and the nearest place (write a negative x as "
      "`where -- -1.5,2`)");
  where->add_option("point", wh->at, "x,y in the map frame (metres)")->required();
  addFileOptions(where, wh->f, false);
  where->add_flag("--json", wh->json, "Print JSON");
  where->callback([wh] {
    const auto v = numbers(wh->at, "point", 2);
    const PlacesFile f = places::readPlacesFile(wh->f.placesPath());
    const places::WhereResult w = places::where(f, v[0], v[1]);
    std::cout << (wh->json ? dumpJson(places::whereJson(v[0], v[1], w)) + "\n"
                           : places::whereText(w));
  });
}

/** `places check`: the rooms and places against the map; exit 2 on any problem. */
void addCheck(CLI::App* cmd) {
  struct CheckArgs {
    FileArgs f;
    double radius = 0.35;
    std::string profile;
    bool json = false;
  };
  auto ck = std::make_shared<CheckArgs>();
  auto* check = cmd->add_subcommand(
      "check",
      "Check rooms and places against the map: places outside every room, overlapping rooms, "
      "rooms with no free cell, user-search places without a free disc to turn, places not on "
      "a free cell. Lists every problem; exit code 2 if there is any");
  addFileOptions(check, ck->f, true);
  auto* radius_opt = check->add_option(
      "--radius", ck->radius,
      "Free disc a user-search place needs, metres (the robot's circumscribed radius; "
      "default 0.35)");
  check
      ->add_option("--profile", ck->profile,
                   "Robot profile: the radius is its [robot] footprint's circumscribed radius")
      ->excludes(radius_opt);
  check->add_flag("--json", ck->json, "Print JSON");
  check->callback([ck] {
    places::CheckParams cp;
    cp.turn_radius = ck->radius;
    if (!ck->profile.empty()) {
      const Profile p = Profile::load(ck->profile);
      cp.turn_radius = p.section<RobotParams>("robot").circumscribedRadius();
    }
    if (!(cp.turn_radius > 0) || !std::isfinite(cp.turn_radius))
      throw InputError("--radius must be > 0 metres");
    const std::string path = ck->f.placesPath();
    const PlacesFile f = places::readPlacesFile(path);
    const auto grid = ck->f.grid();
    const auto problems = places::checkPlaces(f, grid, cp);
    std::cout << (ck->json
                      ? dumpJson(places::checkJson(path, ck->f.map, cp.turn_radius, problems)) +
                            "\n"
                      : places::checkText(f, path, problems));
    std::cout.flush();  // the list before the error line on a shared terminal
    if (!problems.empty())
      throw InputError(path + ": " + std::to_string(problems.size()) + " problem" +
                       (problems.size() == 1 ? "" : "s"));
  });
}

/** `places render`: the map with its rooms and places as a PNG. */
void addRender(CLI::App* cmd, const GlobalOptions& g) {
  struct RenderArgs {
    FileArgs f;
    std::string out;
    bool crop = false;
  };
  auto rd = std::make_shared<RenderArgs>();
  auto* render = cmd->add_subcommand(
      "render", "Draw the map with translucent rooms, their names, and places as arrows");
  addFileOptions(render, rd->f, true);
  render->add_option("--out", rd->out, "PNG file to write")->required();
  render->add_flag("--crop", rd->crop, "Crop to the known cells plus 1 m");
  render->callback([rd, &g] {
    prepareOutputFile(rd->out);
    const PlacesFile f = places::readPlacesFile(rd->f.placesPath());
    const auto grid = rd->f.grid();
    io::RenderOptions ro;
    ro.crop_to_known = rd->crop;
    ro.title = "rooms and places: " + std::filesystem::path(rd->f.map).filename().string();
    places::renderPlacesPng(f, grid, rd->out, ro);
    if (!g.quiet) std::cerr << "[places] wrote " << rd->out << "\n";
  });
}

/** `places goal`: a name to a goal pose. */
void addGoal(CLI::App* cmd) {
  struct GoalArgs {
    FileArgs f;
    std::string name;
    bool json = false;
  };
  auto gl = std::make_shared<GoalArgs>();
  auto* goal = cmd->add_subcommand(
      "goal",
      "The goal pose of \"room/place\", \"place\" or \"room\" (its default place, else its most "
      "central free cell): prints x y heading_deg");
  goal->add_option("name", gl->name, "room/place, place or room")->required();
  addFileOptions(goal, gl->f, true);
  goal->add_flag("--json", gl->json, "Print JSON");
  goal->callback([gl] {
    const PlacesFile f = places::readPlacesFile(gl->f.placesPath());
    const auto grid = gl->f.grid();
    const places::Goal r = places::resolveGoal(f, grid, gl->name);
    std::cout << (gl->json ? dumpJson(places::goalJson(gl->name, r)) + "\n" : places::goalText(r));
  });
}

void addPlacesCommand(CLI::App& app, const GlobalOptions& g) {
  auto* cmd = app.add_subcommand(
      "places",
      "Rooms (named polygons) and places (named poses) on a map, kept in MAP's .places.yaml: "
      "edit, list, locate a point, check against the map, draw, and turn names into goals");
  cmd->require_subcommand(1);
  addAddRoom(cmd, g);
  addAddPlace(cmd, g);
  addRenameAndRemove(cmd, g);
  addList(cmd);
  addWhere(cmd);
  addCheck(cmd);
  addRender(cmd, g);
  addGoal(cmd);
}

}  // namespace

CARENAV_COMMAND(70, addPlacesCommand);

}  // namespace carenav::app
