// carenav places check|render: the rooms and places against their map, and
// drawn on it (modules/places).
#include <carenav/common/json.h>
#include <carenav/common/profile.h>
#include <carenav/common/robot.h>
#include <carenav/places/places_report.h>

#include <cmath>
#include <filesystem>
#include <memory>

#include "places_args.h"

namespace carenav::app {

namespace {

struct CheckArgs {
  FileArgs f;
  double radius = 0.35;
  std::string profile;
  bool json = false;
};

/** `check`: every problem against the map, then exit 2 when there is one. */
void runCheck(const CheckArgs& a) {
  places::CheckParams cp;
  cp.turn_radius =
      a.profile.empty()
          ? a.radius
          : Profile::load(a.profile).section<RobotParams>("robot").circumscribedRadius();
  if (!(cp.turn_radius > 0) || !std::isfinite(cp.turn_radius))
    throw InputError("--radius must be > 0 metres");
  const std::string path = a.f.placesPath();
  const places::PlacesFile f = places::readPlacesFile(path);
  const auto problems = places::checkPlaces(f, a.f.grid(), cp);
  std::cout << (a.json ? dumpJson(places::checkJson(path, a.f.map, cp.turn_radius, problems)) + "\n"
                       : places::checkText(f, path, problems));
  std::cout.flush();  // the list before the error line on a shared terminal
  if (!problems.empty()) throw InputError(places::checkFailureText(path, problems));
}

}  // namespace

/** `places check`: the rooms and places against the map; exit 2 on any problem. */
void addPlacesCheck(CLI::App* cmd) {
  auto a = std::make_shared<CheckArgs>();
  auto* check = cmd->add_subcommand(
      "check",
      "Check rooms and places against the map: places outside every room, overlapping rooms, "
      "rooms with no free cell, user-search places without a free disc to turn, places not on "
      "a free cell. Lists every problem; exit code 2 if there is any");
  addFileOptions(check, a->f, true);
  auto* radius_opt = check->add_option(
      "--radius", a->radius,
      "Free disc a user-search place needs, metres (the robot's circumscribed radius; "
      "default 0.35)");
  check
      ->add_option("--profile", a->profile,
                   "Robot profile: the radius is its [robot] footprint's circumscribed radius")
      ->excludes(radius_opt);
  check->add_flag("--json", a->json, "Print JSON");
  check->callback([a] { runCheck(*a); });
}

/** `places render`: the map with its rooms and places as a PNG. */
void addPlacesRender(CLI::App* cmd, const GlobalOptions& g) {
  struct RenderArgs {
    FileArgs f;
    std::string out;
    bool crop = false;
  };
  auto a = std::make_shared<RenderArgs>();
  auto* render = cmd->add_subcommand(
      "render", "Draw the map with translucent rooms, their names, and places as arrows");
  addFileOptions(render, a->f, true);
  render->add_option("--out", a->out, "PNG file to write")->required();
  render->add_flag("--crop", a->crop, "Crop to the known cells plus 1 m");
  render->callback([a, &g] {
    prepareOutputFile(a->out);
    const places::PlacesFile f = places::readPlacesFile(a->f.placesPath());
    io::RenderOptions ro;
    ro.crop_to_known = a->crop;
    ro.title = "rooms and places: " + std::filesystem::path(a->f.map).filename().string();
    places::renderPlacesPng(f, a->f.grid(), a->out, ro);
    if (!g.quiet) std::cerr << "[places] wrote " << a->out << "\n";
  });
}

}  // namespace carenav::app
