// carenav slam --profile P --rawlog R [--method icp|icp-graph|rbpf] --out DIR
#include "commands.h"

#include <carenav/common/profile.h>
#include <carenav/slam/slam_job.h>

#include <mrpt/config/CConfigFile.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/serialization/CArchive.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

namespace carenav::app {

namespace {

struct SlamArgs {
  std::string profile, rawlog, out, method, resume, resume_pose;
  std::vector<std::string> sets;
};

/** True for MRPT's own icp-slam / rbpf-slam INI files. */
bool isMrptAppIni(const std::string& path) {
  std::ifstream f(path);
  std::string line;
  while (std::getline(f, line))
    if (line.find("[MappingApplication]") != std::string::npos) return true;
  return false;
}

mrpt::poses::CPose2D parsePose(const std::string& text) {
  double x, y, deg;
  char c1, c2;
  std::istringstream is(text);
  if (!(is >> x >> c1 >> y >> c2 >> deg) || c1 != ',' || c2 != ',')
    throw InputError("--resume-pose '" + text + "': expected x,y,deg");
  return mrpt::poses::CPose2D(x, y, deg * M_PI / 180);
}

mrpt::maps::CSimpleMap loadSimpleMap(const std::string& path) {
  if (!std::filesystem::exists(path)) throw InputError(path + ": map to resume not found");
  mrpt::maps::CSimpleMap sm;
  try {
    mrpt::io::CFileGZInputStream f(path);
    auto arch = mrpt::serialization::archiveFrom(f);
    arch >> sm;
  } catch (const std::exception& e) {
    std::string w = e.what();
    throw InputError(path + ": not an MRPT .simplemap (" + w.substr(0, w.find('\n')) +
                     "); --resume takes the map.simplemap a previous `carenav slam` wrote");
  }
  if (sm.empty()) throw InputError(path + ": the map to resume is empty");
  return sm;
}

void addSlamCommand(CLI::App& app, const GlobalOptions& g) {
  auto a = std::make_shared<SlamArgs>();
  auto* cmd = app.add_subcommand(
      "slam",
      "Build a map from a rawlog: 2D laser scans (or virtual scans) with or without odometry. "
      "Writes to --out: map.simplemap, map.gridmap.gz, map.yaml + map.pgm (ROS map_server), "
      "map.png (with the trajectory), trajectory.tum and summary.json. A truncated rawlog "
      "still writes the map of what was read, then exits 2.");
  cmd->add_option("--profile", a->profile,
                  "Robot profile (ini/*.ini; [slam], [icp], [rbpf] sections) or an MRPT "
                  "icp-slam/rbpf-slam INI ([MappingApplication], [ICP], ...)")
      ->required();
  cmd->add_option("--rawlog", a->rawlog, "MRPT rawlog (either form, plain or gzip)")->required();
  cmd->add_option("--out", a->out, "Output folder (created)")->required();
  cmd->add_option("--method", a->method,
                  "icp | icp-graph | rbpf (default: the profile's slam.method)");
  cmd->add_option("--set", a->sets, "Override a profile value: section.key=value (repeatable)");
  cmd->add_option("--resume", a->resume,
                  "Extend a map: the map.simplemap of an earlier run (the new scans join it)");
  cmd->add_option("--resume-pose", a->resume_pose,
                  "Pose x,y,deg where the new rawlog starts in the resumed map (default: the "
                  "last pose of that map)");
  cmd->callback([a, &g] {
    prepareOutputFolder(a->out);
    slam::SlamJobOptions o;
    o.rawlog = a->rawlog;
    o.out_dir = a->out;
    o.progress = !g.quiet;
    std::unique_ptr<mrpt::config::CConfigFile> mrpt_ini;
    if (isMrptAppIni(a->profile)) {
      if (!a->sets.empty())
        throw InputError("--set applies to carenav profiles; edit the MRPT INI instead");
      mrpt_ini = std::make_unique<mrpt::config::CConfigFile>(a->profile);
      o.mapper.mrpt_ini = mrpt_ini.get();
      const bool rbpf = mrpt_ini->keyExists("MappingApplication", "PF_algorithm") ||
                        mrpt_ini->keyExists("MappingApplication", "sampleSize");
      o.method = a->method.empty() ? (rbpf ? "rbpf" : "icp") : a->method;
    } else {
      Profile p = Profile::load(a->profile);
      p.applyOverrides(a->sets);
      p.validate();
      o.mapper.slam = p.section<slam::SlamParams>("slam");
      o.mapper.icp = p.section<slam::IcpParams>("icp");
      o.mapper.rbpf = p.section<slam::RbpfParams>("rbpf");
      o.method = a->method.empty() ? o.mapper.slam.method : a->method;
    }
    if (!a->resume.empty()) {
      o.mapper.resume_map = loadSimpleMap(a->resume);
      const auto& last = o.mapper.resume_map->get(o.mapper.resume_map->size() - 1);
      o.mapper.start_pose = a->resume_pose.empty()
                                ? mrpt::poses::CPose2D(std::get<0>(last)->getMeanVal())
                                : parsePose(a->resume_pose);
    } else if (!a->resume_pose.empty()) {
      throw InputError("--resume-pose needs --resume");
    }
    const slam::SlamJobResult r = slam::runSlam(o);
    if (!g.quiet) {
      const auto& s = r.stats;
      std::cerr << "[slam] " << o.method << ": " << r.steps << " scans in " << r.seconds << " s ("
                << (r.steps ? 1000 * r.seconds / r.steps : 0) << " ms/scan), " << s.inserted
                << " in the map";
      if (o.method == "icp-graph")
        std::cerr << ", " << s.keyframes << " keyframes, " << s.loop_closures
                  << " loop closures of " << s.loop_candidates << " tried";
      std::cerr << "\n";
      if (s.restamped)
        std::cerr << "[slam] warning: " << s.restamped << " of " << r.steps
                  << " scans did not advance in time (the log repeats its timestamps); MRPT's "
                     "builder got them 1 ms after the scan before, trajectory.tum keeps the "
                     "log's times (evaluate with carenav eval --by-index)\n";
      std::cerr << "[slam] final pose " << r.final_pose.asString() << "\n";
      for (const auto& f : r.outputs) std::cerr << "[slam] wrote " << f << "\n";
    }
    if (r.rawlog_error)
      throw InputError(*r.rawlog_error + "; the map of the " + std::to_string(r.steps) +
                       " scans before it was saved in " + o.out_dir);
  });
}

}  // namespace

CARENAV_COMMAND(30, addSlamCommand);

}  // namespace carenav::app
