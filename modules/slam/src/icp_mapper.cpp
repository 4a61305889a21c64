// "icp": MRPT's CMetricMapBuilderICP (scan-to-map ICP on a points map), the
// same engine as MRPT's icp-slam app, without its GUI.
#include <carenav/slam/mapper.h>

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/poses/CPose3DPDF.h>
#include <mrpt/poses/CPosePDFGaussian.h>
#include <mrpt/slam/CMetricMapBuilderICP.h>

#include <chrono>
#include <cmath>
#include <optional>

namespace carenav::slam {

namespace {

using mrpt::poses::CPose2D;

/** The map MRPT's builder aligns against: one planar points map. */
const char* kPointsMapIni = R"([map]
pointsMap_count = 1
occupancyGrid_count = 0
likelihoodMapSelection = -1
[map_pointsMap_00_insertOpts]
minDistBetweenLaserPoints = 0.05
fuseWithExisting = false
isPlanarMap = 1
)";

/** Re-expresses every pose of the (deep-copied) simple map in another frame. */
void changeFrame(mrpt::maps::CSimpleMap& m, const mrpt::poses::CPose3D& frame) {
  for (size_t i = 0; i < m.size(); ++i) {
    auto [pdf, sf] = m.get(i);
    if (pdf) pdf->changeCoordinatesReference(frame);
  }
}

class IcpMapper : public Mapper {
 public:
  explicit IcpMapper(const MapperConfig& cfg) : cfg_(cfg) {
    using mrpt::config::CConfigFileMemory;
    if (cfg.mrpt_ini) {
      builder_.ICP_options.loadFromConfigFile(*cfg.mrpt_ini, "MappingApplication");
      builder_.ICP_params.loadFromConfigFile(*cfg.mrpt_ini, "ICP");
    } else {
      const auto& s = cfg.slam;
      auto& o = builder_.ICP_options;
      o.matchAgainstTheGrid = false;
      o.insertionLinDistance = s.insertion_lin_distance;
      o.insertionAngDistance = s.insertion_ang_distance * M_PI / 180;
      o.localizationLinDistance = s.localization_lin_distance;
      o.localizationAngDistance = s.localization_ang_distance * M_PI / 180;
      o.minICPgoodnessToAccept = s.min_icp_goodness;
      CConfigFileMemory maps(kPointsMapIni);
      o.mapInitializers.loadFromConfigFile(maps, "map");
      CConfigFileMemory icp(cfg.icp.asMrptIni("ICP"));
      builder_.ICP_params.loadFromConfigFile(icp, "ICP");
    }
    builder_.setVerbosityLevel(mrpt::system::LVL_ERROR);
    // MRPT stamps an initial pose given to initialize() with the wall clock,
    // after which its pose estimator ignores the (older) rawlog odometry. So
    // the builder always starts at its origin, and a start pose is a change
    // of frame: the builder's frame is the start pose's.
    offset_ = cfg.start_pose.value_or(CPose2D());
    mrpt::maps::CSimpleMap initial;
    if (cfg.resume_map) {
      initial = *cfg.resume_map;
      const mrpt::poses::CPose3D inv(-offset_);
      changeFrame(initial, inv);
    }
    builder_.initialize(initial);
  }

  void process(const io::ScanStep& step) override {
    // MRPT's pose extrapolator divides odometry increments by the time
    // between readings: a scan whose timestamp does not advance (logs stamped
    // in whole seconds, or not at all) gives it infinite velocities and the
    // builder stops growing the map. Such scans reach the builder stamped
    // kRestampStep after the one before; the trajectory keeps the log's
    // times. Scans that do advance keep theirs.
    auto scan = clipScan(step.scan, cfg_.slam.scan_range_max);
    mrpt::Clock::time_point stamp = scan->timestamp;
    if (last_stamp_ && !(stamp > *last_stamp_)) {
      stamp = *last_stamp_ + kRestampStep;
      if (scan == step.scan) scan = std::make_shared<mrpt::obs::CObservation2DRangeScan>(*scan);
      scan->timestamp = stamp;
      ++stats_.restamped;
    }
    last_stamp_ = stamp;
    // Odometry as an absolute reading (the builder differentiates it), then
    // the scan: MRPT's observation-only path. Without odometry the builder
    // runs ICP on every scan from the last pose (MRPT's laser-only mode).
    if (cfg_.slam.use_odometry && step.odometry) {
      odometry_ = odometry_ + *step.odometry;
      auto odo = mrpt::obs::CObservationOdometry::Create();
      odo->timestamp = stamp;
      odo->odometry = odometry_;
      builder_.processObservation(odo);
    }
    const unsigned before = builder_.getCurrentlyBuiltMapSize();
    builder_.processObservation(scan);
    if (builder_.getCurrentlyBuiltMapSize() > before) ++stats_.inserted;
    ++stats_.scans;
    const CPose2D p = pose();
    traj_.push_back({step.time, p.x(), p.y(), p.phi()});
  }

  CPose2D pose() const override {
    return offset_ + CPose2D(builder_.getCurrentPoseEstimation()->getMeanVal());
  }

  mrpt::math::CMatrixDouble33 covariance() const override {
    const auto [cov6, mean] = builder_.getCurrentPoseEstimation()->getCovarianceAndMean();
    mrpt::math::CMatrixDouble33 c;
    const int idx[3] = {0, 1, 3};  // x, y, yaw of (x y z yaw pitch roll)
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) c(i, j) = cov6(idx[i], idx[j]);
    // Rotate the x-y block into the map frame.
    const double cs = std::cos(offset_.phi()), sn = std::sin(offset_.phi());
    mrpt::math::CMatrixDouble33 r;
    r.setIdentity();
    r(0, 0) = cs, r(0, 1) = -sn, r(1, 0) = sn, r(1, 1) = cs;
    mrpt::math::CMatrixDouble33 rt = r;
    rt(0, 1) = sn, rt(1, 0) = -sn;  // transpose of a rotation
    return r * c * rt;
  }

  mrpt::maps::CSimpleMap simpleMap() const override {
    mrpt::maps::CSimpleMap m;
    builder_.getCurrentlyBuiltMap(m);
    const mrpt::poses::CPose3D off(offset_);
    changeFrame(m, off);
    return m;
  }

  io::Trajectory2D trajectory() const override { return traj_; }
  MapperStats stats() const override { return stats_; }

 private:
  /** A time step no laser scans at (1 kHz): only its sign matters to the
   *  builder, whose extrapolation spans the 0 s from odometry to scan. */
  static constexpr std::chrono::milliseconds kRestampStep{1};
  MapperConfig cfg_;
  mutable mrpt::slam::CMetricMapBuilderICP builder_;
  std::optional<mrpt::Clock::time_point> last_stamp_;
  io::Trajectory2D traj_;
  CPose2D offset_;    // start pose: the builder's frame in the map frame
  CPose2D odometry_;  // accumulated motion prior, fed as odometry readings
  MapperStats stats_;
};

}  // namespace

std::unique_ptr<Mapper> makeIcpMapper(const MapperConfig& cfg) {
  return std::make_unique<IcpMapper>(cfg);
}

}  // namespace carenav::slam
