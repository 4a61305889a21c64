// carenav simulate --profile P --world W (--path "x,y ..." | --script FILE)
//                  --out X.rawlog [--start x,y,deg] [--seed N] [--duration S]
#include "commands.h"

#include <carenav/common/profile.h>
#include <carenav/sim/simulate_job.h>

#include <iostream>

namespace carenav::app {

namespace {

struct SimulateArgs {
  std::string profile, world, path, script, out, start;
  std::optional<int> seed;
  double duration = 0;
  std::vector<std::string> sets;
};

void addSimulateCommand(CLI::App& app, const GlobalOptions& g) {
  auto a = std::make_shared<SimulateArgs>();
  auto* cmd = app.add_subcommand(
      "simulate",
      "Drive a profile's robot through a simulated world (grid map + steps, stairs, holes, "
      "tables, ramps, walking people) and write an observation-only MRPT rawlog of its "
      "sensors and noisy odometry, the ground truth beside it (X.gt.tum) and a summary "
      "(X.summary.json). See docs/simulate.md.");
  cmd->add_option("--profile", a->profile,
                  "Robot profile (ini/*.ini): [robot] limits, [sensor.*] sensors, [sim] noise")
      ->required();
  cmd->add_option("--world", a->world, "World YAML (maps/worlds/*.yaml, docs/simulate.md)")
      ->required();
  cmd->add_option("--path", a->path,
                  "Waypoints \"x,y x,y ...\" (m, map frame) followed under the robot's limits");
  cmd->add_option("--script", a->script,
                  "Timed commands file: rows \"t v w\" (s, m/s, rad/s), each held until the next");
  cmd->add_option("--out", a->out, "Output rawlog X.rawlog or X.rawlog.gz")->required();
  cmd->add_option("--start", a->start,
                  "Start pose x,y,deg (default: the first waypoint facing the second; the "
                  "origin for --script)");
  cmd->add_option("--seed", a->seed, "Random seed (overrides [sim] seed)");
  cmd->add_option("--duration", a->duration,
                  "Simulated seconds at most (default: until the path is done, at most 3600 s; "
                  "for --script its last row's time)");
  cmd->add_option("--set", a->sets, "Override a profile value: section.key=value (repeatable)");
  cmd->callback([a, &g] {
    prepareOutputFile(a->out);
    if (a->path.empty() == a->script.empty())
      throw InputError("give exactly one of --path and --script");
    if (a->duration < 0) throw InputError("--duration must not be negative");
    Profile p = Profile::load(a->profile);
    p.applyOverrides(a->sets);
    p.validate();
    sim::SimulateOptions o;
    o.robot = p.section<RobotParams>("robot");
    o.sensors = loadSensors(p);
    o.params = p.section<sim::SimParams>("sim");
    if (a->seed) {
      if (*a->seed < 0) throw InputError("--seed must not be negative");
      o.params.seed = *a->seed;
    }
    o.world = a->world;
    if (!a->path.empty()) o.path = sim::parsePath(a->path);
    if (!a->script.empty()) o.script = sim::readCommandScript(a->script);
    if (!a->start.empty()) o.start = sim::parseStart(a->start);
    o.duration = a->duration;
    o.out = a->out;
    o.progress = !g.quiet;
    const auto r = sim::runSimulate(o);
    if (!g.quiet) {
      std::cerr << "[simulate] " << r.sim_seconds << " s simulated in " << r.wall_seconds << " s ("
                << (r.wall_seconds > 0 ? r.sim_seconds / r.wall_seconds : 0) << "x real time), "
                << r.frames << " frames, " << r.distance << " m, " << r.collisions
                << " bumper contacts\n";
      if (!o.path.empty() && !r.path_completed)
        std::cerr << "[simulate] warning: the path was not completed (" << r.waypoints_reached
                  << " of " << o.path.size() << " waypoints)\n";
      for (const auto& f : {r.rawlog, r.ground_truth, r.summary})
        std::cerr << "[simulate] wrote " << f << "\n";
    }
  });
}

}  // namespace

CARENAV_COMMAND(100, addSimulateCommand);

}  // namespace carenav::app
