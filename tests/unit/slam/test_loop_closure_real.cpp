// icp-graph's loop closures on a real log seen through a short-range scanner:
// the CSAIL CARMEN log of the test data with seeded noisy odometry and its
// ranges cut at 10 m (what a walker's lidar sees), so that corridors give
// closures that slide along them.
#include <carenav/io/carmen.h>
#include <carenav/io/evaluation.h>
#include <carenav/io/trajectory.h>
#include <carenav/slam/slam_job.h>

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

using namespace carenav;

namespace {

/** ATE (m, by index) of `carenav slam` (icp-graph, profile defaults but
 *  slam.scan_range_max = `range`) on the CARMEN log `name` of the test data
 *  imported with the noisy odometry of `seed` (`carenav import carmen
 *  --odometry-noise SEED`). */
double shortRangeAte(const std::string& name, uint64_t seed, double range) {
  namespace fs = std::filesystem;
  const auto dir = fs::temp_directory_path() /
                   ("carenav_lc_" + name + std::to_string(seed) + "_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  io::CarmenImportOptions import;
  import.input = std::string(CARENAV_TEST_DATA) + "/carmen/" + name + "-corrected.log.gz";
  import.output = (dir / "log.rawlog").string();
  io::OdometryNoiseParams noise;
  noise.seed = seed;
  import.odometry_noise = noise;
  io::importCarmen(import);
  slam::SlamJobOptions o;
  o.rawlog = import.output;
  o.out_dir = (dir / "map").string();
  o.method = "icp-graph";
  o.progress = false;
  o.mapper.slam.scan_range_max = range;
  slam::runSlam(o);
  io::AssociationParams by_index;
  by_index.by_index = true;
  const auto est = io::readTum((dir / "map" / "trajectory.tum").string());
  const auto ref = io::readTum((dir / "log.tum").string());
  const double ate = io::computeAte(io::associate(est, ref, by_index)).translation.rmse;
  fs::remove_all(dir);
  return ate;
}

}  // namespace

TEST(LoopClosureRealLog, CorridorClosuresThatSlideDoNotBendTheMap) {
  // Through a 10 m scanner CSAIL's corridors show two walls and little else:
  // a loop match there pairs nearly every point (ICP goodness over
  // loop_min_goodness) and ICP's covariance claims a few cm along the
  // corridor, yet the match slides along it. Accepted on goodness alone
  // (before), such closures locked in where the drifted estimate put the
  // robot and the maps ended 1.31 and 0.63 m ATE from the reference; checked
  // for distinctness like every other closure, 0.12 and 0.13 m.
  for (const uint64_t seed : {1u, 2u})
    EXPECT_LT(shortRangeAte("csail", seed, 10.0), 0.3) << "odometry noise seed " << seed;
}
