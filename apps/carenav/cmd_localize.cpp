// carenav localize --profile P --map M --rawlog R
//                  (--init x,y,deg[,sx,sy,sdeg] | --global | --in-room NAME) --out DIR [--ref
//                  GT.tum]
#include "commands.h"

#include <carenav/common/profile.h>
#include <carenav/localization/localize_job.h>
#include <carenav/places/places.h>
#include <carenav/places/places_report.h>

#include <iostream>

namespace carenav::app {

namespace {

struct LocalizeArgs {
  std::string profile, map, rawlog, out, init, ref, room, places_file;
  bool global = false;
  double map_resolution = 0.05;
  std::vector<std::string> sets;
};

void addLocalizeCommand(CLI::App& app, const GlobalOptions& g) {
  auto a = std::make_shared<LocalizeArgs>();
  auto* cmd = app.add_subcommand(
      "localize",
      "Localise a rawlog's robot on a known map: Monte Carlo localisation (KLD-adaptive "
      "particles, likelihood field) with recovery by random particles when the likelihood "
      "drops. Writes to --out: track.tum, track_cov.csv, map.png and summary.json.");
  cmd->add_option("--profile", a->profile, "Robot profile (ini/*.ini; [localization] section)")
      ->required();
  cmd->add_option("--map", a->map,
                  "Map: .gridmap(.gz), .simplemap(.gz), ROS .yaml, or what `carenav slam` wrote")
      ->required();
  cmd->add_option("--rawlog", a->rawlog, "MRPT rawlog with 2D scans and odometry")->required();
  cmd->add_option("--out", a->out, "Output folder (created)")->required();
  cmd->add_option("--init", a->init,
                  "Initial pose x,y,deg with optional standard deviations sx,sy,sdeg "
                  "(default 0.5,0.5,10)");
  cmd->add_flag("--global", a->global,
                "Global localisation: particles uniformly over the free space of the map");
  cmd->add_option("--in-room", a->room,
                  "Global localisation inside one room of the map's places file (carenav "
                  "places): particles over the free cells of that room only");
  cmd->add_option("--places", a->places_file,
                  "Places file for --in-room (default: the one beside --map, MAP.places.yaml)");
  cmd->add_option("--ref", a->ref, "Reference trajectory (TUM) to draw and to compute the ATE");
  cmd->add_option("--map-resolution", a->map_resolution,
                  "Cell size (m) of the grid built from a .simplemap (default 0.05)");
  cmd->add_option("--set", a->sets, "Override a profile value: section.key=value (repeatable)");
  cmd->callback([a, &g] {
    prepareOutputFolder(a->out);
    Profile p = Profile::load(a->profile);
    p.applyOverrides(a->sets);
    p.validate();
    localization::LocalizeJobOptions o;
    o.params = p.section<localization::LocalizationParams>("localization");
    o.map = a->map;
    o.rawlog = a->rawlog;
    o.out_dir = a->out;
    o.ref = a->ref;
    o.global = a->global;
    o.map_resolution = a->map_resolution;
    o.progress = !g.quiet;
    if (!a->init.empty()) o.init = localization::parseInitialPose(a->init);
    if (!a->room.empty()) {
      const places::RoomArea room = places::readRoomArea(
          a->places_file.empty() ? places::placesPathForMap(a->map) : a->places_file, a->room);
      o.region = {room.name, room.inside};
    }
    const auto r = localization::runLocalize(o);
    if (!g.quiet) {
      const auto& f = r.track.back();
      std::cerr << "[localize] " << r.scans << " scans, " << r.updates << " updates in "
                << r.seconds << " s; ";
      if (r.convergence_time)
        std::cerr << "converged after " << *r.convergence_time << " s (" << *r.convergence_updates
                  << " updates)";
      else if (r.convergence_updates)
        std::cerr << "converged after " << *r.convergence_updates << " updates ("
                  << *r.convergence_scans
                  << " scans; no time: scans before it repeat the timestamp of the scan before)";
      else
        std::cerr << "never converged";
      std::cerr << "; " << r.events.size() << " loss/recovery events, " << r.injections
                << " injections";
      if (r.rotate_enabled)
        std::cerr << ", " << r.rotate_requests.size() << " rotate-in-place requests";
      if (r.dead_reckoning_scans)
        std::cerr << ", " << r.dead_reckoning_scans
                  << " scans with too few returns in range (odometry alone there)";
      std::cerr << "\n[localize] final pose (" << f.x << ", " << f.y << ", " << f.yaw * 180 / M_PI
                << " deg)\n";
      if (r.ate_rmse) std::cerr << "[localize] ATE rmse " << *r.ate_rmse << " m\n";
      for (const auto& file : r.outputs) std::cerr << "[localize] wrote " << file << "\n";
    }
    if (r.rawlog_error)
      throw InputError(*r.rawlog_error + "; the track of the " + std::to_string(r.scans) +
                       " scans before it was saved in " + o.out_dir);
  });
}

}  // namespace

CARENAV_COMMAND(40, addLocalizeCommand);

}  // namespace carenav::app
