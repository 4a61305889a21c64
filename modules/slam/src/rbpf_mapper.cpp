// "rbpf": MRPT's CMetricMapBuilderRBPF with occupancy-grid particles (the
// engine of MRPT's rbpf-slam app), without its GUI.
#include <carenav/slam/mapper.h>

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose3DPDF.h>
#include <mrpt/poses/CPosePDFGaussian.h>
#include <mrpt/slam/CMetricMapBuilderRBPF.h>

#include <cmath>
#include <sstream>

namespace carenav::slam {

namespace {

using mrpt::poses::CPose2D;

/** The profile's values as the MRPT sections the builder reads. */
std::string rbpfIni(const MapperConfig& cfg) {
  const auto& r = cfg.rbpf;
  const auto& s = cfg.slam;
  const int algo = r.proposal == "standard" ? 0 : r.proposal == "optimal" ? 2 : 3;
  std::ostringstream o;
  o << "[MappingApplication]\n"
    << "insertionLinDistance = " << s.insertion_lin_distance << "\n"
    << "insertionAngDistance_deg = " << s.insertion_ang_distance << "\n"
    << "localizeLinDistance = " << r.localize_lin_distance << "\n"
    << "localizeAngDistance_deg = " << r.localize_ang_distance << "\n"
    << "verbosity_level = ERROR\n"
    << "PF_algorithm = " << algo << "\n"
    << "adaptiveSampleSize = 0\nresamplingMethod = 0\n"
    << "sampleSize = " << r.particles << "\n"
    << "BETA = " << r.resample_ess << "\n"
    << "occupancyGrid_count = 1\npointsMap_count = 0\nlikelihoodMapSelection = -1\n"
    << "powFactor = 0.01\npfAuxFilterOptimal_MaximumSearchSamples = 400\n"
    << "pfOptimalProposal_mapSelection = 0\n"
    << "[MappingApplication_occupancyGrid_00_creationOpts]\n"
    << "resolution = " << s.grid_resolution << "\n"
    << "[MappingApplication_occupancyGrid_00_insertOpts]\n"
    << "maxDistanceInsertion = " << r.lf_max_range << "\n"
    << "maxOccupancyUpdateCertainty = 0.60\nconsiderInvalidRangesAsFreeSpace = 1\n"
    << "[MappingApplication_occupancyGrid_00_likelihoodOpts]\n"
    << "likelihoodMethod = 4\nLF_decimation = 5\n"
    << "LF_stdHit = " << r.lf_std_hit << "\n"
    << "LF_maxCorrsDistance = 0.30\nLF_zHit = 0.999\nLF_zRandom = 0.001\n"
    << "LF_maxRange = " << r.lf_max_range << "\n"
    << "enableLikelihoodCache = 1\n";
  return o.str();
}

mrpt::slam::CMetricMapBuilderRBPF::TConstructionOptions options(const MapperConfig& cfg) {
  mrpt::slam::CMetricMapBuilderRBPF::TConstructionOptions opts;
  if (cfg.mrpt_ini) {
    opts.loadFromConfigFile(*cfg.mrpt_ini, "MappingApplication");
  } else {
    mrpt::config::CConfigFileMemory ini(rbpfIni(cfg));
    opts.loadFromConfigFile(ini, "MappingApplication");
  }
  opts.verbosity_level = mrpt::system::LVL_ERROR;
  return opts;
}

class RbpfMapper : public Mapper {
 public:
  explicit RbpfMapper(const MapperConfig& cfg) : cfg_(cfg), builder_(options(cfg)) {
    builder_.setVerbosityLevel(mrpt::system::LVL_ERROR);
    // The particle filter warns on every particle whose scan match falls
    // back to odometry: routine for the optimal proposal, noise for users.
    builder_.mapPDF.setVerbosityLevel(mrpt::system::LVL_ERROR);
    mrpt::poses::CPosePDFGaussian x0(cfg.start_pose.value_or(CPose2D()));
    builder_.initialize(cfg.resume_map.value_or(mrpt::maps::CSimpleMap()), &x0);
  }

  void process(const io::ScanStep& step) override {
    const CPose2D guess =
        (cfg_.slam.use_odometry && step.odometry) ? *step.odometry : last_increment_;
    mrpt::obs::CActionCollection acts;
    mrpt::obs::CActionRobotMovement2D move;
    mrpt::obs::CActionRobotMovement2D::TMotionModelOptions mm;
    move.computeFromOdometry(guess, mm);
    move.timestamp = step.scan->timestamp;
    acts.insert(move);
    mrpt::obs::CSensoryFrame sf;
    sf.insert(clipScan(step.scan, cfg_.slam.scan_range_max));
    const unsigned before = builder_.getCurrentlyBuiltMapSize();
    builder_.processActionObservation(acts, sf);
    if (builder_.getCurrentlyBuiltMapSize() > before) ++stats_.inserted;
    ++stats_.scans;
    const CPose2D p = pose();
    if (!traj_.empty()) last_increment_ = p - last_pose_;
    last_pose_ = p;
    traj_.push_back({step.time, p.x(), p.y(), p.phi()});
  }

  CPose2D pose() const override {
    return CPose2D(builder_.getCurrentPoseEstimation()->getMeanVal());
  }

  mrpt::math::CMatrixDouble33 covariance() const override {
    const auto [cov6, mean] = builder_.getCurrentPoseEstimation()->getCovarianceAndMean();
    mrpt::math::CMatrixDouble33 c;
    const int idx[3] = {0, 1, 3};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) c(i, j) = cov6(idx[i], idx[j]);
    return c;
  }

  mrpt::maps::CSimpleMap simpleMap() const override {
    mrpt::maps::CSimpleMap m;
    builder_.getCurrentlyBuiltMap(m);
    return m;
  }

  /** The poses of the most likely particle's path would be smoother, but
   *  the filter's mean at each step is what a user sees live. */
  io::Trajectory2D trajectory() const override { return traj_; }
  MapperStats stats() const override { return stats_; }

 private:
  MapperConfig cfg_;
  mutable mrpt::slam::CMetricMapBuilderRBPF builder_;
  io::Trajectory2D traj_;
  CPose2D last_pose_, last_increment_;
  MapperStats stats_;
};

}  // namespace

std::unique_ptr<Mapper> makeRbpfMapper(const MapperConfig& cfg) {
  return std::make_unique<RbpfMapper>(cfg);
}

}  // namespace carenav::slam
