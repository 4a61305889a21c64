// carenav demo: the main job on embedded defaults.
#include "commands.h"

#include <carenav/common/errors.h>
#include <carenav/io/map_io.h>
#include <carenav/io/rawlog_info.h>
#include <carenav/runtime/scenario.h>
#include <carenav/places/places.h>
#include <carenav/slam/slam_job.h>

#include <filesystem>
#include <fstream>
#include <iostream>

namespace carenav::app {

namespace {
void addDemoCommand(CLI::App& app, const GlobalOptions& g) {
  auto* cmd = app.add_subcommand(
      "demo",
      "Run the main job on embedded defaults, on MRPT's real SENA rawlog (a loop through the "
      "Telecom faculty of the University of Malaga, laser + odometry): summarise the rawlog, "
      "then build its map with icp-graph SLAM (loop closure) and write the map as PNG (with the "
      "trajectory), ROS map_server YAML+PGM, MRPT gridmap and simplemap, TUM trajectory and "
      "summary.json; then annotate that map with the rooms and places of the SENA building "
      "(map.places.yaml), check them against the map, say which room the robot ended in, and "
      "draw them (map_places.png); last, in the simulator on that map, the ISR-AIWALKER "
      "walker is pushed by a scripted user from the start of the log to the place \"Dock\" "
      "(user-intent DWA, safety supervisor): walk/run.png, navlog.csv, summary.json.");
  struct Args {
    std::string rawlog, out = "carenav-demo";
  };
  auto a = std::make_shared<Args>();
  cmd->add_option("--rawlog", a->rawlog, "Rawlog to use instead of MRPT's SENA dataset");
  cmd->add_option("--out", a->out, "Output folder")->capture_default_str();
  cmd->callback([a, &g] {
    prepareOutputFolder(a->out);
    std::string path = a->rawlog;
    if (path.empty()) {
      path = mrptDatasetsDir() + "/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog";
      if (!std::filesystem::exists(path))
        throw InputError(path +
                         ": MRPT's dataset is missing; install Debian's mrpt-common "
                         "(scripts/setup.sh does) or set CARENAV_MRPT_DATASETS");
    }
    if (!g.quiet) std::cerr << "[demo] step 1/4: rawlog summary of " << path << "\n";
    const io::RawlogInfo ri = io::summarizeRawlog(path, !g.quiet);
    std::cout << ri.toText() << std::flush;
    if (ri.error) throw InputError(*ri.error);

    if (!g.quiet) std::cerr << "[demo] step 2/4: icp-graph SLAM into " << a->out << "\n";
    slam::SlamJobOptions o;  // embedded defaults: SlamParams{}, IcpParams{}
    o.rawlog = path;
    o.out_dir = a->out;
    o.method = "icp-graph";
    o.progress = !g.quiet;
    const slam::SlamJobResult r = slam::runSlam(o);
    std::cout << "\nmap:                " << r.steps << " scans, " << r.stats.keyframes
              << " keyframes, " << r.stats.loop_closures << " loop closures, " << r.seconds
              << " s\n"
              << "final pose:         " << r.final_pose.asString() << "\n";
    for (const auto& f : r.outputs) std::cout << "wrote:              " << f << "\n";

    // Rooms and places: the shipped annotation of the SENA building, which
    // fits maps built from this rawlog (same start frame).
    if (!a->rawlog.empty()) return;  // another rawlog: another building
    if (!g.quiet) std::cerr << "[demo] step 3/4: rooms and places on the map\n";
    namespace fs = std::filesystem;
    const std::string map_yaml = (fs::path(a->out) / "map.yaml").string();
    const places::PlacesFile pf = places::parsePlaces(senaPlacesYaml(), "maps/sena.places.yaml");
    const std::string pf_path = places::placesPathForMap(map_yaml);
    places::writePlacesFile(pf, pf_path);
    const auto grid = io::loadGridMap(map_yaml);
    const auto problems = places::checkPlaces(pf, grid);
    std::cout << "\nrooms and places:   " << pf.rooms.size() << " rooms, " << pf.places.size()
              << " places, " << problems.size() << " problems against the map\n";
    for (const auto& p : problems) std::cout << "  problem: " << p.what << "\n";
    const auto w = places::where(pf, r.final_pose.x(), r.final_pose.y());
    std::cout << "robot ends in:      " << (w.room ? w.room->name : std::string("no room"));
    if (w.nearest) std::cout << ", " << w.distance << " m from \"" << w.nearest->name << "\"";
    std::cout << "\n";
    const std::string png = (fs::path(a->out) / "map_places.png").string();
    io::RenderOptions ro;
    ro.crop_to_known = true;
    ro.title = "carenav demo: rooms and places of the SENA map";
    places::renderPlacesPng(pf, grid, png, ro);
    std::cout << "wrote:              " << pf_path << "\nwrote:              " << png << "\n";

    // The walker in the simulator on this map: a user walks from where the
    // log starts to the Dock, the walker keeps them safe.
    if (!g.quiet) std::cerr << "[demo] step 4/4: the walker pushed to the Dock, simulated\n";
    const fs::path prof_dir = fs::path(a->out) / "profile";
    fs::create_directories(prof_dir);
    std::ofstream(prof_dir / "defaults.ini") << defaultsIni();
    std::ofstream(prof_dir / "isr-aiwalker.ini") << walkerIni();
    std::ofstream(fs::path(a->out) / "world.yaml")
        << "# carenav world (docs/simulate.md): the demo's map, walls only.\nformat: 1\n"
           "map: map.gridmap.gz\n";
    std::ofstream(fs::path(a->out) / "walk.yaml")
        << "# carenav navigation scenario (docs/navigate.md), written by carenav demo.\n"
           "format: 1\nworld: world.yaml\nprofile: profile/isr-aiwalker.ini\n"
           "places: map.places.yaml\nstart: [0, 0, 0]\ngoal: \"Dock\"\nduration: 200\n"
           "end: true\n";
    navigation::RunOptions ro2;
    ro2.out_dir = (fs::path(a->out) / "walk").string();
    ro2.progress = !g.quiet;
    const auto nav = navigation::runScenario(
        navigation::readScenario((fs::path(a->out) / "walk.yaml").string()), ro2);
    std::cout << "\nwalker to the Dock: " << (nav.success ? "reached" : "NOT reached") << " ("
              << nav.outcome << "), " << nav.path_length_m << " m in " << nav.duration_s << " s, "
              << nav.collisions << " collisions, minimum clearance " << nav.min_clearance_m
              << " m\n";
    for (const auto& f : nav.outputs) std::cout << "wrote:              " << f << "\n";
  });
}
}  // namespace

CARENAV_COMMAND(200, addDemoCommand);

}  // namespace carenav::app
