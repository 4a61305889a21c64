// carenav import carmen LOG[.gz] --out X.rawlog [--tum F | --no-tum] [--odometry SRC]
#include "commands.h"

#include <carenav/common/errors.h>
#include <carenav/io/carmen.h>

#include <iostream>

namespace carenav::app {

namespace {
void addImportCarmen(CLI::App& import_cmd, const GlobalOptions& g) {
  struct Args {
    io::CarmenImportOptions opt;
    std::string odometry = "auto";
    int64_t noise_seed = -1;
    std::vector<double> noise_model{0.05, 1.0, 0.02};
    bool no_tum = false;
    bool json = false;
    bool quiet = false;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = import_cmd.add_subcommand(
      "carmen",
      "Convert a CARMEN log (.log/.clf, plain or .gz; FLASER, RLASER, LASER3/4, RAWLASERk, "
      "ROBOTLASERk, ODOM, PARAM) to an MRPT rawlog (observation-only form, gzip) with the log's "
      "own timestamps, plus the robot poses of the log as a TUM trajectory (X.rawlog -> X.tum). "
      "Unknown message types are skipped and counted. A malformed line stops the import with "
      "exit 2 naming FILE:LINE; what was converted before it is written.");
  cmd->add_option("log", a->opt.input, "CARMEN log file (plain or gzip)")->required();
  cmd->add_option("-o,--out", a->opt.output,
                  "Rawlog to write (gzip-compressed whatever the name; written atomically)")
      ->required();
  auto* tum = cmd->add_option("--tum", a->opt.tum,
                              "TUM trajectory to write (default: --out with .tum instead of "
                              ".rawlog[.gz]); for corrected logs it is the SLAM reference");
  cmd->add_flag("--no-tum", a->no_tum, "Write no TUM trajectory")->excludes(tum);
  cmd->add_option("--odometry", a->odometry,
                  "Odometry source: auto (laser messages if they carry odometry, else ODOM "
                  "lines), laser (FLASER/RLASER odom fields, ROBOTLASER robot_pose: one reading "
                  "per scan at its time), odom (ODOM lines), none")
      ->check(CLI::IsMember({"auto", "laser", "odom", "none"}))
      ->capture_default_str();
  auto* noise = cmd->add_option(
      "--odometry-noise", a->noise_seed,
      "Replace the odometry by noisy odometry made from it, with this seed (same seed, same "
      "noise). For a corrected log, whose odometry fields are the reference poses, this is the "
      "odometry a real base would have given. Each increment between readings: length x (1 + "
      "5 % N), turn + N x sqrt((1 deg/m x length)^2 + (2 % x turn)^2); see --odometry-noise-model");
  noise->check(CLI::Range(int64_t{0}, int64_t{1} << 62));
  cmd->add_option("--odometry-noise-model", a->noise_model,
                  "Noise model of --odometry-noise: DIST_FRAC,DEG_PER_M,TURN_FRAC")
      ->delimiter(',')
      ->expected(3)
      ->needs(noise)
      ->capture_default_str();
  cmd->add_option("--max-range", a->opt.max_range,
                  "Maximum range in m for every scan; readings at or beyond it are invalid "
                  "(default 0: from the log, else 80 m)")
      ->check(CLI::Range(0.0, 1e6));
  cmd->add_option("--compression", a->opt.compression, "gzip level of the rawlog, 1..9")
      ->check(CLI::Range(1, 9))
      ->capture_default_str();
  cmd->add_flag("--json", a->json, "Print the summary as JSON");
  cmd->add_flag("-q,--quiet", a->quiet, "No progress and no notes on stderr (same as carenav -q)");
  cmd->footer(
      "Example:\n"
      "  carenav import carmen intel-corrected.log.gz --out intel.rawlog\n"
      "  carenav rawlog info intel.rawlog\n"
      "  carenav import carmen intel-corrected.log.gz --out intel-odo1.rawlog --odometry-noise 1\n"
      "See docs/import.md.");
  cmd->callback([a, &g] {
    prepareOutputFile(a->opt.output);
    if (!a->opt.tum.empty()) prepareOutputFile(a->opt.tum, "--tum");
    const bool quiet = g.quiet || a->quiet;
    a->opt.odometry = io::parseCarmenOdometry(a->odometry);
    if (a->noise_seed >= 0) {
      io::OdometryNoiseParams n;
      n.seed = static_cast<uint64_t>(a->noise_seed);
      n.dist_frac = a->noise_model[0];
      n.deg_per_m = a->noise_model[1];
      n.turn_frac = a->noise_model[2];
      a->opt.odometry_noise = n;
    }
    a->opt.write_tum = !a->no_tum;
    a->opt.progress = !quiet;
    auto report = [&](const io::CarmenImportStats& st) {
      std::cout << (a->json ? st.toJson() : st.toText()) << std::flush;
      if (!quiet) std::cerr << st.notesText() << std::flush;
    };
    try {
      report(io::importCarmen(a->opt));
    } catch (const io::CarmenImportError& e) {
      report(e.stats);  // what was written before the bad line
      throw;
    }
  });
}
}  // namespace

CARENAV_IMPORT(addImportCarmen);

}  // namespace carenav::app
