// One perception pipeline per method, frame by frame, and the job behind
// `carenav perceive`.
#pragma once

#include <carenav/perception/cloud.h>
#include <carenav/perception/elevation_grid.h>
#include <carenav/perception/ground_plane.h>
#include <carenav/perception/ism.h>
#include <carenav/perception/perception_params.h>
#include <carenav/perception/virtual_scans.h>

#include <mrpt/img/CImage.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/poses/CPose2D.h>

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace carenav::perception {

/** rrt-gpd: 2.5D grid + RRT-GPD + ISM (the method of [Garrote17]);
 *  ransac: 2.5D grid + RANSAC-only plane over the points + the same ISM;
 *  height-band: 0.2-1.5 m band projection ([Rosa17, Sec. 5.3]);
 *  mrpt-2dscan: MRPT's CObservation3DRangeScan::convertTo2DScan (depth images only). */
enum class Method { RrtGpd, Ransac, HeightBand, Mrpt2DScan };
Method parseMethod(const std::string& name);  ///< throws InputError
const char* methodName(Method m);

struct FrameResult {
  size_t points_total = 0, points_valid = 0;
  std::optional<Plane> plane;  ///< robot frame, normal up
  std::string plane_source;    ///< rrt-gpd | ransac | nominal (z = 0) | none
  /** Why the plane is nominal (no seed / every tree refused / a lower floor), or that it
   *  lies farther from the robot's floor than prior_height_tolerance; empty otherwise. */
  std::string plane_note;
  /** RRT-GPD's plane lay more than d_pth below the robot's floor, the mounting
   *  confirmed or calibrated (Pipeline::lowerFloor()): classified against z = 0. */
  bool lower_floor = false;
  GroundPlaneResult ground;
  /** depth_noise_std of this frame over the profile's: the measured noise
   *  (measuredNoiseRatio) clamped to [1, noise_adapt_max]. */
  double noise_scale = 1;
  size_t drop_edges = 0;  ///< image columns where the floor ends at a drop (markImageDropEdges)
  IsmStats ism;
  CellCounts counts;
  std::vector<std::pair<std::string, double>> timing_ms;  ///< per stage, then "total"
  std::vector<VoxelClass> voxel_classes;                  ///< per elevation cell (ISM methods)
  std::optional<mrpt::obs::CObservation2DRangeScan> kos, maxrule, mrpt_scan;
  std::optional<FspfResult> fspf;
  double timing(const std::string& stage) const;
};

struct FrameInput {
  const Cloud* cloud = nullptr;                             ///< robot frame
  Point3f sensor_origin;                                    ///< robot frame
  mrpt::obs::CObservation3DRangeScan* depth_obs = nullptr;  ///< for mrpt-2dscan
  mrpt::poses::CPose2D odometry;                            ///< robot pose, odometry frame
};

class Pipeline {
 public:
  Pipeline(const PerceptionParams& p, Method m);
  /** Processes one frame. An empty or all-invalid cloud leaves the local
   *  grid as it was (no information) and reports plane_source "none". */
  FrameResult process(const FrameInput& in, bool virtual_scans);
  const LocalOccupancy& grid() const { return grid_; }
  const ElevationGrid& elevation() const { return elev_; }
  Method method() const { return method_; }
  /** PNG view of the local grid: x forward is up; unknown grey, free white,
   *  occupied black; this frame's ground-plane voxels green, obstacle voxels
   *  red, RRT nodes blue, the robot an orange disc with its heading. */
  mrpt::img::CImage render(const FrameResult& r) const;

 private:
  void lowerFloor(FrameResult& r);

  PerceptionParams p_;
  Method method_;
  bool floor_confirmed_ = false;  ///< RRT-GPD found the robot's floor at z = 0 (lowerFloor())
  ElevationGrid elev_;
  LocalOccupancy grid_;
};

/** `carenav perceive` */
struct PerceiveOptions {
  PerceptionParams params;
  Method method = Method::RrtGpd;
  std::string rawlog, cloud, out_dir;
  /** Sensor pose on the robot: for --cloud required (from --sensor-pose or the
   *  profile's depth sensor); for rawlogs overrides the observations' own. */
  std::optional<mrpt::poses::CPose3D> sensor_pose;
  /** Per sensorLabel poses from the profile's [sensor.*] sections. */
  std::vector<std::pair<std::string, mrpt::poses::CPose3D>> profile_poses;
  size_t max_frames = 0;  ///< 0: all
  bool progress = true;
};
struct PerceiveResult {
  size_t frames = 0;
  /** Accepted but suspicious input (also in summary.json "warnings"); the CLI prints them. */
  std::vector<std::string> warnings;
  std::vector<std::string> outputs;
};
PerceiveResult runPerceive(const PerceiveOptions& o);

}  // namespace carenav::perception
