#include "slam_outputs.h"

#include <carenav/io/map_io.h>
#include <carenav/io/map_render.h>

#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/serialization/CArchive.h>

#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;

namespace carenav::ros {

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
                  const slam::SlamJobOptions& o, const std::string& path) {
  io::RenderOptions ro;
  ro.crop_to_known = true;
  ro.title = "carenav ros slam " + o.method + ": " + o.rawlog;
  io::Overlay track;
  for (const auto& p : traj) track.points.push_back({p.x, p.y});
  track.colour = {220, 30, 30};
  track.thickness = 2;
  track.start_end_markers = true;
  ro.overlays.push_back(track);
  io::renderGridMapPng(grid, path, ro);
}

}  // namespace

void writeSlamOutputs(const slam::Mapper& mapper, const slam::SlamJobOptions& o,
                      slam::SlamJobResult& res) {
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
  const auto grid = slam::gridFromSimpleMap(sm, o.mapper.slam.grid_resolution);
  io::saveGridMap(grid, out("map.gridmap.gz"));
  io::writeRosMap(grid, out("map.yaml"));
  res.outputs.push_back((fs::path(o.out_dir) / "map.pgm").string());
  writePicture(grid, traj, o, out("map.png"));
  const std::string summary = out("summary.json");
  {
    std::ofstream f(summary + ".tmp");
    f << res.summaryJson(o);
  }
  fs::rename(summary + ".tmp", summary);
}

}  // namespace carenav::ros
