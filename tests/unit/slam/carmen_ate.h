// Shared helper of the SLAM tests on the CARMEN logs of the test data: map a
// log with `carenav slam` (icp-graph) and score it against the log's
// reference poses.
#pragma once

#include <carenav/io/carmen.h>
#include <carenav/io/evaluation.h>
#include <carenav/io/trajectory.h>
#include <carenav/slam/slam_job.h>

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

namespace carenav::slam::test {

/** ATE (m, by index, after SE(2) alignment) of icp-graph with `params` as the
 *  [slam] parameters on the CARMEN log `name` of the test data, imported
 *  laser only (`noise_seed` empty: `carenav import carmen --odometry none`)
 *  or with the seeded noisy odometry of `--odometry-noise SEED`. */
inline double carmenAte(const std::string& name, std::optional<uint64_t> noise_seed,
                        const SlamParams& params) {
  namespace fs = std::filesystem;
  const auto dir = fs::temp_directory_path() /
                   ("carenav_ate_" + name + "_" + std::to_string(noise_seed.value_or(0)) + "_" +
                    std::to_string(::getpid()));
  fs::create_directories(dir);
  io::CarmenImportOptions import;
  import.input = std::string(CARENAV_TEST_DATA) + "/carmen/" + name + "-corrected.log.gz";
  import.output = (dir / "log.rawlog").string();
  if (noise_seed) {
    io::OdometryNoiseParams noise;
    noise.seed = *noise_seed;
    import.odometry_noise = noise;
  } else {
    import.odometry = io::CarmenOdometry::None;
  }
  io::importCarmen(import);
  SlamJobOptions o;
  o.rawlog = import.output;
  o.out_dir = (dir / "map").string();
  o.method = "icp-graph";
  o.progress = false;
  o.mapper.slam = params;
  runSlam(o);
  io::AssociationParams by_index;
  by_index.by_index = true;
  const auto est = io::readTum((dir / "map" / "trajectory.tum").string());
  const auto ref = io::readTum((dir / "log.tum").string());
  const double ate = io::computeAte(io::associate(est, ref, by_index)).translation.rmse;
  fs::remove_all(dir);
  return ate;
}

}  // namespace carenav::slam::test
