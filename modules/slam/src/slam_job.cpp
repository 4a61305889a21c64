#include <carenav/common/json.h>
#include <carenav/common/progress.h>
#include <carenav/io/map_io.h>
#include <carenav/io/map_render.h>
#include <carenav/slam/slam_job.h>

#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;

namespace carenav::slam {

mrpt::maps::COccupancyGridMap2D gridFromSimpleMap(const mrpt::maps::CSimpleMap& sm,
                                                  double resolution) {
  mrpt::maps::COccupancyGridMap2D grid(-10, 10, -10, 10, static_cast<float>(resolution));
  grid.insertionOptions.maxDistanceInsertion = 30;
  for (size_t i = 0; i < sm.size(); ++i) {
    const auto& [pdf, sf] = sm.get(i);
    if (!pdf || !sf) continue;
    const mrpt::poses::CPose3D pose = pdf->getMeanVal();
    sf->insertObservationsInto(grid, pose);
  }
  return grid;
}

namespace {

void writeSimpleMap(const mrpt::maps::CSimpleMap& sm, const std::string& path) {
  const std::string tmp = path + ".tmp";
  {
    mrpt::io::CFileGZOutputStream f(tmp);
    auto arch = mrpt::serialization::archiveFrom(f);
    arch << sm;
  }
  fs::rename(tmp, path);
}

void writePicture(const mrpt::maps::COccupancyGridMap2D& grid, const io::Trajectory2D& traj,
                  const std::string& title, const std::string& path) {
  io::RenderOptions ro;
  ro.crop_to_known = true;
  ro.title = title;
  io::Overlay track;
  for (const auto& p : traj) track.points.push_back({p.x, p.y});
  track.colour = {220, 30, 30};
  track.thickness = 2;
  track.start_end_markers = true;
  ro.overlays.push_back(track);
  io::renderGridMapPng(grid, path, ro);
}

}  // namespace

void writeSlamOutputs(const Mapper& mapper, const SlamJobOptions& o, SlamJobResult& res,
                      const std::string& title) {
  res.stats = mapper.stats();
  res.final_pose = mapper.pose();
  res.final_cov = mapper.covariance();
  res.outputs.clear();
  fs::create_directories(o.out_dir);
  auto out = [&](const std::string& name) {
    const std::string p = (fs::path(o.out_dir) / name).string();
    res.outputs.push_back(p);
    return p;
  };
  const auto sm = mapper.simpleMap();
  writeSimpleMap(sm, out("map.simplemap"));
  const auto traj = mapper.trajectory();
  io::writeTum(out("trajectory.tum"), traj);
  const auto grid = gridFromSimpleMap(sm, o.mapper.slam.grid_resolution);
  io::saveGridMap(grid, out("map.gridmap.gz"));
  io::writeRosMap(grid, out("map.yaml"));
  res.outputs.push_back((fs::path(o.out_dir) / "map.pgm").string());
  writePicture(grid, traj, title, out("map.png"));
  const std::string summary = out("summary.json");
  {
    std::ofstream f(summary + ".tmp");
    f << res.summaryJson(o);
  }
  fs::rename(summary + ".tmp", summary);
}

SlamJobResult runSlam(const SlamJobOptions& o) {
  SlamJobResult res;
  io::ScanStream stream(o.rawlog, o.mapper.slam.sensor);  // InputError: missing/empty rawlog
  auto mapper = createMapper(o.method, o.mapper);
  Progress progress("slam " + o.method, stream.reader().fileSize());
  progress.setEnabled(o.progress && progress.enabled());
  const auto t0 = std::chrono::steady_clock::now();
  io::ScanStep step;
  try {
    while (stream.next(step)) {
      mapper->process(step);
      if (res.steps == 0) res.first_pose = mapper->pose();
      ++res.steps;
      progress.update(stream.reader().filePosition(), stream.reader().entriesRead());
    }
  } catch (const io::RawlogError& e) {
    res.rawlog_error = e.what();
  }
  progress.finish();
  res.entries = stream.reader().entriesRead();
  if (res.steps == 0) {
    std::string msg = o.rawlog + ": no usable 2D laser scan";
    if (!o.mapper.slam.sensor.empty()) msg += " with sensor label '" + o.mapper.slam.sensor + "'";
    if (!stream.otherLabels().empty()) {
      msg += " (2D scans seen with labels:";
      for (const auto& l : stream.otherLabels()) msg += " '" + l + "'";
      msg += "; choose one with --set slam.sensor=LABEL)";
    }
    if (res.rawlog_error) msg += "; " + *res.rawlog_error;
    throw InputError(msg);
  }
  mapper->finish();
  res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  writeSlamOutputs(*mapper, o, res,
                   "carenav slam " + o.method + ": " + fs::path(o.rawlog).filename().string());
  return res;
}

std::string SlamJobResult::summaryJson(const SlamJobOptions& o) const {
  JsonWriter j;
  j.beginObject();
  j.key("rawlog").value(o.rawlog);
  j.key("method").value(o.method);
  j.key("complete").value(!rawlog_error.has_value());
  if (rawlog_error) j.key("rawlog_error").value(*rawlog_error);
  j.key("entries").value(static_cast<uint64_t>(entries));
  j.key("steps").value(static_cast<uint64_t>(steps));
  j.key("seconds").value(seconds);
  j.key("ms_per_step").value(steps ? 1000 * seconds / steps : 0.0);
  j.key("scans_inserted").value(static_cast<uint64_t>(stats.inserted));
  j.key("icp_accepted").value(static_cast<uint64_t>(stats.icp_accepted));
  j.key("icp_rejected").value(static_cast<uint64_t>(stats.icp_rejected));
  j.key("keyframes").value(static_cast<uint64_t>(stats.keyframes));
  j.key("loop_candidates").value(static_cast<uint64_t>(stats.loop_candidates));
  j.key("loop_closures").value(static_cast<uint64_t>(stats.loop_closures));
  j.key("loop_rejected").value(static_cast<uint64_t>(stats.loop_rejected));
  j.key("graph_optimisations").value(static_cast<uint64_t>(stats.optimisations));
  j.key("prior_rejected").value(static_cast<uint64_t>(stats.prior_rejected));
  j.key("scans_restamped").value(static_cast<uint64_t>(stats.restamped));
  auto pose = [&](const char* k, const mrpt::poses::CPose2D& p) {
    j.key(k).beginObject();
    j.key("x").value(p.x());
    j.key("y").value(p.y());
    j.key("yaw_deg").value(p.phi() * 180 / M_PI);
    j.endObject();
  };
  pose("first_pose", first_pose);
  pose("final_pose", final_pose);
  j.key("final_std").beginObject();
  j.key("x").value(std::sqrt(std::max(0.0, final_cov(0, 0))));
  j.key("y").value(std::sqrt(std::max(0.0, final_cov(1, 1))));
  j.key("yaw_deg").value(std::sqrt(std::max(0.0, final_cov(2, 2))) * 180 / M_PI);
  j.endObject();
  j.key("outputs").beginArray();
  for (const auto& f : outputs) j.value(f);
  j.endArray();
  j.endObject();
  return j.str() + "\n";
}

}  // namespace carenav::slam
