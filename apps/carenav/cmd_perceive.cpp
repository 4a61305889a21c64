// carenav perceive --profile P (--rawlog R | --cloud F.ply|F.pcd) --out DIR
//                  [--method rrt-gpd|ransac|height-band|mrpt-2dscan] [--sensor-pose
//                  x,y,z,yaw,pitch,roll]
#include "commands.h"

#include <carenav/common/profile.h>
#include <carenav/common/robot.h>
#include <carenav/perception/pipeline.h>

#include <iostream>

namespace carenav::app {
namespace {

struct PerceiveArgs {
  std::string profile, rawlog, cloud, out, method = "rrt-gpd", sensor_pose;
  size_t max_frames = 0;
  std::vector<std::string> sets;
};

mrpt::poses::CPose3D poseOf(const SensorParams& s) {
  const double d2r = M_PI / 180.0;
  return mrpt::poses::CPose3D(s.x, s.y, s.z, s.yaw * d2r, s.pitch * d2r, s.roll * d2r);
}

void addPerceiveCommand(CLI::App& app, const GlobalOptions& g) {
  auto a = std::make_shared<PerceiveArgs>();
  auto* cmd = app.add_subcommand(
      "perceive",
      "3D point clouds to safe 2D obstacle maps: 2.5D elevation grid, RRT-GPD ground plane "
      "and inverse sensor model fused into a robot-centred local occupancy grid (stairs down, "
      "gutters and floor outlets become obstacles), plus virtual 2D scans (FSPF+/KOS, max-rule). "
      "Writes to --out per frame frame_NNNN.png and frame_NNNN.gridmap.gz, virtual_scans.rawlog "
      "and summary.json (ground plane a,b,c,d in the robot frame, cell counts, timing per stage).");
  cmd->add_option("--profile", a->profile, "Robot profile (ini/*.ini; [perception] section)")
      ->required();
  cmd->add_option("--rawlog", a->rawlog,
                  "MRPT rawlog with CObservation3DRangeScan, CObservationPointCloud or "
                  "CObservationVelodyneScan (odometry moves the local grid)");
  cmd->add_option("--cloud", a->cloud,
                  "One frame from a .pcd (ascii, binary, binary_compressed) or .ply (ascii, "
                  "binary_little_endian) file, in the camera frame (x right, y down, z forward)");
  cmd->add_option("--out", a->out, "Output folder (created)")->required();
  cmd->add_option("--method", a->method,
                  "rrt-gpd (default), ransac (RANSAC-only ground plane), height-band (0.2-1.5 m "
                  "projection) or mrpt-2dscan (MRPT convertTo2DScan; depth images only)");
  cmd->add_option("--sensor-pose", a->sensor_pose,
                  "Sensor pose on the robot x,y,z,yaw,pitch,roll (m, deg; positive pitch looks "
                  "down); default: the profile's [sensor.<label>] for rawlogs (else the "
                  "observation's own pose), the profile's depth camera for --cloud");
  cmd->add_option("--max-frames", a->max_frames, "Stop after this many frames (0: all)");
  cmd->add_option("--set", a->sets, "Override a profile value: section.key=value (repeatable)");
  cmd->callback([a, &g] {
    prepareOutputFolder(a->out);
    Profile p = Profile::load(a->profile);
    p.applyOverrides(a->sets);
    p.validate();
    perception::PerceiveOptions o;
    o.params = p.section<perception::PerceptionParams>("perception");
    o.method = perception::parseMethod(a->method);
    o.rawlog = a->rawlog;
    o.cloud = a->cloud;
    o.out_dir = a->out;
    o.max_frames = a->max_frames;
    o.progress = !g.quiet;
    if (!a->sensor_pose.empty()) o.sensor_pose = perception::parseSensorPose(a->sensor_pose);
    for (const auto& s : loadSensors(p)) {
      if (s.type != "depth-camera") continue;
      o.profile_poses.emplace_back(s.label, poseOf(s));
      if (!a->cloud.empty() && !o.sensor_pose &&
          (o.params.sensor.empty() || o.params.sensor == s.label))
        o.sensor_pose = poseOf(s);
    }
    const auto r = perception::runPerceive(o);
    for (const auto& w : r.warnings) std::cerr << "[perceive] warning: " << w << "\n";
    if (!g.quiet) {
      std::cerr << "[perceive] " << r.frames << " frame(s), method " << a->method << "\n";
      for (const auto& f : r.outputs)
        if (f.find("summary.json") != std::string::npos ||
            f.find("virtual_scans") != std::string::npos)
          std::cerr << "[perceive] wrote " << f << "\n";
    }
  });
}

}  // namespace

CARENAV_COMMAND(50, addPerceiveCommand);

}  // namespace carenav::app
