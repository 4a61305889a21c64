// carenav demo: the main job on embedded defaults.
#include "commands.h"

#include <carenav/common/errors.h>
#include <carenav/io/rawlog_info.h>
#include <carenav/slam/slam_job.h>

#include <filesystem>
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
      "summary.json. Later stages (rooms, navigation) join as they land.");
  struct Args {
    std::string rawlog, out = "carenav-demo";
  };
  auto a = std::make_shared<Args>();
  cmd->add_option("--rawlog", a->rawlog, "Rawlog to use instead of MRPT's SENA dataset");
  cmd->add_option("--out", a->out, "Output folder")->capture_default_str();
  cmd->callback([a, &g] {
    std::string path = a->rawlog;
    if (path.empty()) {
      path = mrptDatasetsDir() + "/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog";
      if (!std::filesystem::exists(path))
        throw InputError(path +
                         ": MRPT's dataset is missing; install Debian's mrpt-common "
                         "(scripts/setup.sh does) or set CARENAV_MRPT_DATASETS");
    }
    if (!g.quiet) std::cerr << "[demo] step 1/2: rawlog summary of " << path << "\n";
    const io::RawlogInfo ri = io::summarizeRawlog(path, !g.quiet);
    std::cout << ri.toText() << std::flush;
    if (ri.error) throw InputError(*ri.error);

    if (!g.quiet) std::cerr << "[demo] step 2/2: icp-graph SLAM into " << a->out << "\n";
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
  });
}
}  // namespace

CARENAV_COMMAND(200, addDemoCommand);

}  // namespace carenav::app
