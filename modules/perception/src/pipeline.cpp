#include <carenav/common/errors.h>
#include <carenav/common/json.h>
#include <carenav/common/progress.h>
#include <carenav/io/map_io.h>
#include <carenav/io/rawlog_reader.h>
#include <carenav/perception/pipeline.h>

#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/serialization/CArchive.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

namespace carenav::perception {

Method parseMethod(const std::string& n) {
  if (n == "rrt-gpd") return Method::RrtGpd;
  if (n == "ransac") return Method::Ransac;
  if (n == "height-band") return Method::HeightBand;
  if (n == "mrpt-2dscan") return Method::Mrpt2DScan;
  throw InputError("--method '" + n + "': expected rrt-gpd, ransac, height-band or mrpt-2dscan");
}

const char* methodName(Method m) {
  switch (m) {
    case Method::RrtGpd:
      return "rrt-gpd";
    case Method::Ransac:
      return "ransac";
    case Method::HeightBand:
      return "height-band";
    default:
      return "mrpt-2dscan";
  }
}

double FrameResult::timing(const std::string& stage) const {
  for (const auto& [k, v] : timing_ms)
    if (k == stage) return v;
  return 0;
}

Pipeline::Pipeline(const PerceptionParams& p, Method m)
    : p_(p),
      method_(m),
      elev_(p.grid_cells, p.resolution),
      grid_(p.grid_cells, p.resolution, p.logodds_max) {}

namespace {
using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}
}  // namespace

/** The robot's own floor, once RRT-GPD finds it where the mounting puts it
 *  (within prior_height_tolerance of z = 0 at the robot), confirms the
 *  mounting. From then on a plane lying below that floor at the robot by
 *  more than d_pth (the height that makes a voxel an obstacle) is a lower
 *  floor seen beyond a drop whose edge is out of view (in the blind zone
 *  under the camera, behind the robot's turn), not floor the robot can
 *  drive onto: the frame is classified against z = 0, its voxels lie below
 *  it and are obstacles. Before the mounting is confirmed such a plane is
 *  kept and reported (the sensor pose may be off: check it), unless the
 *  mounting is known right (mounting_calibrated: a robot navigating, which
 *  may start with a stair edge in the blind zone). */
void Pipeline::lowerFloor(FrameResult& r) {
  const double off = r.ground.prior_offset;
  if (std::abs(off) <= p_.prior_height_tolerance) floor_confirmed_ = true;
  if (!(floor_confirmed_ || p_.mounting_calibrated) || off >= -p_.d_pth) return;
  r.plane = Plane{};
  r.plane_source = "nominal";
  r.lower_floor = true;
  char buf[200];
  std::snprintf(buf, sizeof(buf),
                "ground plane %.3f m below the robot's floor at the robot (more than d_pth "
                "%.3f m), the mounting confirmed or calibrated: a lower floor beyond a drop; "
                "classified against z = 0",
                -off, p_.d_pth);
  r.plane_note = buf;
}

FrameResult Pipeline::process(const FrameInput& in, bool virtual_scans) {
  FrameResult r;
  const auto t_all = Clock::now();
  grid_.moveTo(in.odometry);
  static const Cloud kEmpty;
  const Cloud& c = in.cloud ? *in.cloud : kEmpty;
  r.points_total = c.points.size();
  r.plane_source = "none";
  grid_.beginFrame();
  if (method_ == Method::RrtGpd || method_ == Method::Ransac) {
    auto t = Clock::now();
    elev_.build(c, p_.z_min, p_.z_max, p_.outlier_sigma);
    r.points_valid = elev_.validPoints();  // counted by the grid's single pass
    r.timing_ms.emplace_back("elevation_grid", msSince(t));
    t = Clock::now();
    if (elev_.validCells() > 0) {
      r.ground = method_ == Method::RrtGpd ? detectGroundRrt(elev_, p_) : detectGroundRansac(c, p_);
      if (r.ground.plane) {
        r.plane = r.ground.plane;
        r.plane_source = methodName(method_);
        if (method_ == Method::RrtGpd &&
            std::abs(r.ground.prior_offset) > p_.prior_height_tolerance) {
          char buf[160];
          std::snprintf(buf, sizeof(buf),
                        "ground plane %.3f m from the robot's floor z = 0 at the robot (more "
                        "than prior_height_tolerance %.3f m): check the sensor pose",
                        r.ground.prior_offset, p_.prior_height_tolerance);
          r.plane_note = buf;
        }
        if (method_ == Method::RrtGpd) lowerFloor(r);
      } else {
        // Nothing plane-like seen, or only trees smaller than min_tree_nodes:
        // the floor the robot stands on (the mounting prior), never a small tree.
        r.plane = Plane{};
        r.plane_source = "nominal";
        r.plane_note = r.ground.trees_refused > 0
                           ? std::to_string(r.ground.trees_refused) +
                                 " RRT tree(s) smaller than min_tree_nodes refused: nominal "
                                 "floor z = 0"
                           : std::string("no ground seed: nominal floor z = 0");
      }
    }
    r.timing_ms.emplace_back("ground_plane", msSince(t));
    t = Clock::now();
    if (r.plane) {
      PerceptionParams q = p_;
      if (p_.noise_adapt_max > 1)
        r.noise_scale =
            std::clamp(measuredNoiseRatio(elev_, p_, &in.sensor_origin), 1.0, p_.noise_adapt_max);
      q.depth_noise_std *= r.noise_scale;
      r.ism = integrateIsm(elev_, *r.plane, q, grid_, &r.voxel_classes, &in.sensor_origin);
      r.drop_edges = markImageDropEdges(c, *r.plane, q, in.sensor_origin, grid_);
    }
    r.timing_ms.emplace_back("ism", msSince(t));
  } else if (method_ == Method::HeightBand) {
    r.points_valid = c.validCount();
    auto t = Clock::now();
    integrateHeightBand(c, p_, grid_);
    r.timing_ms.emplace_back("height_band", msSince(t));
  } else {
    r.points_valid = c.validCount();
    auto t = Clock::now();
    if (!in.depth_obs)
      throw InputError(
          "--method mrpt-2dscan needs depth images (CObservation3DRangeScan in a rawlog)");
    r.mrpt_scan = mrptConvertTo2DScan(*in.depth_obs, p_);
    r.timing_ms.emplace_back("convert_2d_scan", msSince(t));
    t = Clock::now();
    integrateScan(*r.mrpt_scan, grid_);
    r.timing_ms.emplace_back("scan_insertion", msSince(t));
  }
  grid_.endFrame();
  if (virtual_scans) {
    auto t = Clock::now();
    if (c.organised()) {
      r.fspf = fspfPlus(c, in.sensor_origin, p_);
      r.timing_ms.emplace_back("fspf", msSince(t));
      t = Clock::now();
      r.kos = kinectObstacleScan(r.fspf->filtered, p_);
    } else {
      r.kos = kinectObstacleScan(c, p_);
    }
    r.timing_ms.emplace_back("kos", msSince(t));
    t = Clock::now();
    r.maxrule = maxRuleScan(c, p_);
    r.timing_ms.emplace_back("maxrule", msSince(t));
  }
  r.counts = grid_.counts(p_.free_threshold, p_.occupied_threshold);
  r.timing_ms.emplace_back("total", msSince(t_all));
  return r;
}

mrpt::img::CImage Pipeline::render(const FrameResult& r) const {
  const int m = grid_.cells();
  mrpt::img::CImage img(m, m, mrpt::img::CH_RGB);
  auto put = [&](int i, int j, uint8_t R, uint8_t G, uint8_t B) {
    if (!grid_.inside(i, j)) return;
    const int row = m - 1 - i, col = m - 1 - j;  // x forward up, y left to the left
    uint8_t* px = img(col, row);
    px[0] = B;  // CImage stores BGR
    px[1] = G;
    px[2] = R;
  };
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      const double p = grid_.prob(i, j);
      uint8_t v;
      if (p > p_.occupied_threshold)
        v = static_cast<uint8_t>(std::lround(90 * (1 - p) / (1 - p_.occupied_threshold)));
      else if (p < p_.free_threshold)
        v = static_cast<uint8_t>(std::lround(200 + 55 * (1 - p / p_.free_threshold)));
      else
        v = 150;
      put(i, j, v, v, v);
    }
  const auto& rb = grid_.robot();
  const double ca = std::cos(rb.phi()), sa = std::sin(rb.phi());
  auto toGrid = [&](double x, double y, int& gi, int& gj) {
    gi = grid_.cellX(rb.x() + ca * x - sa * y);
    gj = grid_.cellY(rb.y() + sa * x + ca * y);
  };
  if (!r.voxel_classes.empty()) {
    const int me = elev_.cells();
    for (int i = 0; i < me; ++i)
      for (int j = 0; j < me; ++j) {
        const VoxelClass vc = r.voxel_classes[static_cast<size_t>(i) * me + j];
        if (vc == VoxelClass::None) continue;
        int gi, gj;
        toGrid(elev_.centre(i), elev_.centre(j), gi, gj);
        if (vc == VoxelClass::Ground)
          put(gi, gj, 90, 200, 90);
        else
          put(gi, gj, 200, 30, 30);
      }
  }
  for (const auto& n : r.ground.nodes) {
    int gi, gj;
    toGrid(n.p.x(), n.p.y(), gi, gj);
    put(gi, gj, 30, 60, 230);
  }
  const int rad = std::max(2, static_cast<int>(0.15 / grid_.resolution()));
  const int ri = grid_.cellX(rb.x()), rj = grid_.cellY(rb.y());
  for (int di = -rad; di <= rad; ++di)
    for (int dj = -rad; dj <= rad; ++dj)
      if (di * di + dj * dj <= rad * rad) put(ri + di, rj + dj, 255, 140, 0);
  for (int k = 0; k <= 2 * rad; ++k) {
    const double s = k * grid_.resolution();
    put(grid_.cellX(rb.x() + ca * s), grid_.cellY(rb.y() + sa * s), 120, 40, 0);
  }
  return img;
}

// ------------------------------------------------------------------ job

namespace {

void writePlane(JsonWriter& j, const std::optional<Plane>& pl) {
  if (!pl) {
    j.null();
    return;
  }
  j.beginObject().key("a").value(pl->a).key("b").value(pl->b).key("c").value(pl->c);
  j.key("d").value(pl->d).endObject();
}

size_t validRanges(const mrpt::obs::CObservation2DRangeScan& s) {
  size_t n = 0;
  for (size_t k = 0; k < s.getScanSize(); ++k) n += s.getScanRangeValidity(k) ? 1 : 0;
  return n;
}

void writeFrameGround(JsonWriter& j, const FrameResult& r, Method method) {
  j.key("ground_plane");
  writePlane(j, r.plane);
  j.key("plane_source").value(r.plane_source);
  if (r.plane) j.key("plane_tilt_deg").value(std::acos(std::min(1.0, r.plane->c)) * 180 / M_PI);
  j.key("plane_note").value(r.plane_note);
  j.key("floor_region_slope_deg");
  if (std::isnan(r.ism.floor_slope_x_deg))
    j.null();
  else
    j.beginArray().value(r.ism.floor_slope_x_deg).value(r.ism.floor_slope_y_deg).endArray();
  if (method == Method::RrtGpd) {
    j.key("plane_prior_offset_m").value(r.ground.plane ? r.ground.prior_offset : 0.0);
    j.key("rrt_trees").value(r.ground.trees_grown);
    j.key("rrt_trees_refused").value(r.ground.trees_refused);
  }
  j.key("depth_noise_scale").value(r.noise_scale);
  j.key("rrt_nodes").value(static_cast<uint64_t>(r.ground.nodes.size()));
  j.key("ransac_inliers").value(static_cast<uint64_t>(r.ground.ransac_inliers));
}

void writeFrameCells(JsonWriter& j, const FrameResult& r) {
  j.key("voxels").beginObject().key("total").value(static_cast<uint64_t>(r.ism.voxels));
  j.key("ground").value(static_cast<uint64_t>(r.ism.ground_voxels));
  j.key("obstacle").value(static_cast<uint64_t>(r.ism.obstacle_voxels));
  j.key("rescued").value(static_cast<uint64_t>(r.ism.rescued_voxels));
  j.key("step").value(static_cast<uint64_t>(r.ism.step_voxels)).endObject();
  j.key("cells").beginObject().key("occupied").value(static_cast<uint64_t>(r.counts.occupied));
  j.key("free").value(static_cast<uint64_t>(r.counts.free));
  j.key("unknown").value(static_cast<uint64_t>(r.counts.unknown)).endObject();
}

void writeFrameScans(JsonWriter& j, const FrameResult& r) {
  j.key("scans").beginObject();
  if (r.kos) j.key("kos_valid").value(static_cast<uint64_t>(validRanges(*r.kos)));
  if (r.maxrule) j.key("maxrule_valid").value(static_cast<uint64_t>(validRanges(*r.maxrule)));
  if (r.mrpt_scan)
    j.key("mrpt_2dscan_valid").value(static_cast<uint64_t>(validRanges(*r.mrpt_scan)));
  if (r.fspf) {
    j.key("fspf_planes")
        .value(r.fspf->planes)
        .key("fspf_planes_dropped")
        .value(r.fspf->planes_dropped);
    j.key("fspf_points").value(static_cast<uint64_t>(r.fspf->filtered.points.size()));
  }
  j.endObject();
}

/** The perceive job: frames through the pipeline into PNGs, gridmaps,
 *  virtual scans and summary.json. */
class PerceiveJob {
 public:
  explicit PerceiveJob(const PerceiveOptions& o)
      : o_(o),
        pipe_(o.params, o.method),
        scans_path_((std::filesystem::path(o.out_dir) / "virtual_scans.rawlog").string()) {
    j_.beginObject().key("method").value(methodName(o.method));
    j_.key("input").value(o.rawlog.empty() ? o.cloud : o.rawlog);
    j_.key("grid").beginObject().key("cells").value(o.params.grid_cells);
    j_.key("resolution").value(o.params.resolution).endObject();
    j_.key("frames").beginArray();
    if (!scans_out_.open(scans_path_)) throw std::runtime_error(scans_path_ + ": cannot write");
  }

  void perceiveCloudFile() {
    if (!o_.sensor_pose)
      throw InputError(o_.cloud +
                       ": a single cloud needs the sensor pose: --sensor-pose "
                       "x,y,z,yaw,pitch,roll or a depth-camera sensor in the profile");
    Cloud cam = readCloudFile(o_.cloud);
    res_.warnings = checkCloudContent(o_.cloud, cam);
    Cloud robot = toRobotFrame(cam, *o_.sensor_pose, true);
    const Point3f origin{static_cast<float>(o_.sensor_pose->x()),
                         static_cast<float>(o_.sensor_pose->y()),
                         static_cast<float>(o_.sensor_pose->z())};
    if (o_.method == Method::Mrpt2DScan)
      throw InputError(o_.cloud +
                       ": --method mrpt-2dscan needs depth images (CObservation3DRangeScan in "
                       "a rawlog), not a point cloud file");
    handleFrame(robot, origin, nullptr, mrpt::poses::CPose2D(), "cloud");
  }

  void perceiveRawlog() {
    io::RawlogReader reader(o_.rawlog);
    Progress prog("perceive", reader.fileSize(), false);
    prog.setEnabled(prog.enabled() && o_.progress);
    mrpt::poses::CPose2D odo;
    io::RawlogEntry e;
    while ((o_.max_frames == 0 || res_.frames < o_.max_frames) && reader.next(e)) {
      if (e.odometry_increment) odo = odo + *e.odometry_increment;
      for (const auto& obs : e.observations()) {
        if (!obs || (!o_.params.sensor.empty() && obs->sensorLabel != o_.params.sensor)) continue;
        perceiveObservation(obs, odo);
        if (o_.max_frames && res_.frames >= o_.max_frames) break;
      }
      prog.update(reader.filePosition(), reader.entriesRead());
    }
    prog.finish();
    if (res_.frames == 0)
      throw InputError(o_.rawlog +
                       ": no 3D observation (CObservation3DRangeScan, "
                       "CObservationPointCloud, CObservationVelodyneScan)" +
                       (o_.params.sensor.empty() ? std::string()
                                                 : " with sensorLabel '" + o_.params.sensor + "'") +
                       (o_.method == Method::Mrpt2DScan ? " with a depth image" : ""));
  }

  PerceiveResult finish() {
    j_.endArray();
    addWarnings();
    j_.key("frame_count").value(static_cast<uint64_t>(res_.frames));
    j_.key("frames_without_points").value(static_cast<uint64_t>(frames_without_points_));
    j_.key("warnings").beginArray();
    for (const auto& w : res_.warnings) j_.value(w);
    j_.endArray();
    j_.key("mean_total_ms").value(res_.frames ? total_ms_ / res_.frames : 0.0);
    j_.endObject();
    scans_out_.close();
    res_.outputs.push_back(scans_path_);
    const std::string sp = (std::filesystem::path(o_.out_dir) / "summary.json").string();
    std::ofstream sf(sp);
    sf << j_.str() << "\n";
    if (!sf) throw std::runtime_error(sp + ": cannot write");
    res_.outputs.push_back(sp);
    return res_;
  }

 private:
  /** One observation of the rawlog, in its sensor's pose (the given one, the
   *  profile's or its own). */
  void perceiveObservation(const mrpt::obs::CObservation::Ptr& obs,
                           const mrpt::poses::CPose2D& odo) {
    std::optional<mrpt::poses::CPose3D> pose = o_.sensor_pose;
    if (!pose)
      for (const auto& [label, pp] : o_.profile_poses)
        if (label == obs->sensorLabel) pose = pp;
    auto cloud = cloudFromObservation(*obs, pose);
    if (!cloud) return;
    mrpt::poses::CPose3D used = pose ? *pose : mrpt::poses::CPose3D();
    if (!pose) obs->getSensorPose(used);
    auto* depth = dynamic_cast<mrpt::obs::CObservation3DRangeScan*>(obs.get());
    if (depth && pose) depth->sensorPose = *pose;
    if (o_.method == Method::Mrpt2DScan && !depth) return;
    handleFrame(
        *cloud,
        {static_cast<float>(used.x()), static_cast<float>(used.y()), static_cast<float>(used.z())},
        depth, odo, obs->sensorLabel);
  }

  void handleFrame(Cloud& cloud, const Point3f& origin, mrpt::obs::CObservation3DRangeScan* obs,
                   const mrpt::poses::CPose2D& odo, const std::string& label) {
    FrameInput in;
    in.cloud = &cloud;
    in.sensor_origin = origin;
    in.depth_obs = obs;
    in.odometry = odo;
    const FrameResult r = pipe_.process(in, true);
    const size_t f = res_.frames++;
    if (r.points_valid == 0) ++frames_without_points_;
    if (r.plane_source == "nominal" && !r.lower_floor && r.ground.trees_refused > 0)
      ++frames_refused_;
    if (r.lower_floor) ++frames_lower_floor_;
    if (!r.plane_note.empty() && r.plane_source != "nominal") ++frames_far_plane_;
    char name[64];
    std::snprintf(name, sizeof(name), "frame_%04zu", f);
    const std::filesystem::path base = std::filesystem::path(o_.out_dir) / name;
    const std::string png = base.string() + ".png", gm = base.string() + ".gridmap.gz";
    if (!pipe_.render(r).saveToFile(png)) throw std::runtime_error(png + ": cannot write");
    io::saveGridMap(pipe_.grid().toMrpt(), gm);
    res_.outputs.push_back(png);
    res_.outputs.push_back(gm);
    for (auto* s : {&r.kos, &r.maxrule, &r.mrpt_scan})
      if (*s) scans_arch_ << **s;
    total_ms_ += r.timing("total");
    writeFrameJson(r, f, label, png, gm);
  }

  void writeFrameJson(const FrameResult& r, size_t f, const std::string& label,
                      const std::string& png, const std::string& gm) {
    namespace fs = std::filesystem;
    j_.beginObject().key("index").value(static_cast<uint64_t>(f)).key("sensor").value(label);
    j_.key("points").value(static_cast<uint64_t>(r.points_total));
    j_.key("valid_points").value(static_cast<uint64_t>(r.points_valid));
    writeFrameGround(j_, r, o_.method);
    writeFrameCells(j_, r);
    writeFrameScans(j_, r);
    j_.key("timing_ms").beginObject();
    for (const auto& [k, v] : r.timing_ms) j_.key(k).value(v);
    j_.endObject().key("png").value(fs::path(png).filename().string());
    j_.key("gridmap").value(fs::path(gm).filename().string()).endObject();
  }

  void addWarnings() {
    if (frames_without_points_ > 0)
      res_.warnings.push_back(
          (o_.rawlog.empty() ? o_.cloud : o_.rawlog) + ": " +
          std::to_string(frames_without_points_) + " of " + std::to_string(res_.frames) +
          " frame(s) had no usable point (none valid, or none in the local grid, z " +
          std::to_string(o_.params.z_min) + " to " + std::to_string(o_.params.z_max) +
          " m): no information, the cells stay unknown");
    const std::string input = o_.rawlog.empty() ? o_.cloud : o_.rawlog;
    if (frames_refused_ > 0)
      res_.warnings.push_back(input + ": " + std::to_string(frames_refused_) + " of " +
                              std::to_string(res_.frames) +
                              " frame(s): every RRT tree was smaller than min_tree_nodes; the "
                              "nominal floor z = 0 was used (see plane_note)");
    if (frames_lower_floor_ > 0)
      res_.warnings.push_back(input + ": " + std::to_string(frames_lower_floor_) + " of " +
                              std::to_string(res_.frames) +
                              " frame(s): the only ground plane in view lay more than d_pth below "
                              "the robot's floor, the mounting confirmed or calibrated (a drop): "
                              "classified against z = 0");
    if (frames_far_plane_ > 0)
      res_.warnings.push_back(input + ": " + std::to_string(frames_far_plane_) + " of " +
                              std::to_string(res_.frames) +
                              " frame(s): ground plane farther than prior_height_tolerance from "
                              "the robot's floor z = 0 (see plane_note; check the sensor pose)");
  }

  const PerceiveOptions& o_;
  PerceiveResult res_;
  Pipeline pipe_;
  JsonWriter j_;
  mrpt::io::CFileGZOutputStream scans_out_;
  const std::string scans_path_;
  mrpt::serialization::CArchiveStreamBase<mrpt::io::CFileGZOutputStream> scans_arch_{scans_out_};
  double total_ms_ = 0;
  size_t frames_without_points_ = 0;  // no valid point inside the grid's z band
  size_t frames_far_plane_ = 0, frames_refused_ = 0, frames_lower_floor_ = 0;
};

}  // namespace

PerceiveResult runPerceive(const PerceiveOptions& o) {
  namespace fs = std::filesystem;
  if (o.rawlog.empty() == o.cloud.empty())
    throw InputError("perceive: give exactly one of --rawlog and --cloud");
  std::error_code ec;
  fs::create_directories(o.out_dir, ec);
  if (ec || !fs::is_directory(o.out_dir))
    throw InputError(o.out_dir + ": cannot create the output folder");
  PerceiveJob job(o);
  if (!o.cloud.empty())
    job.perceiveCloudFile();
  else
    job.perceiveRawlog();
  return job.finish();
}

}  // namespace carenav::perception
