// The kidnapped robot on simulated data: two walks simulated in the same
// world are joined into one rawlog in which the GROUND TRUTH jumps from the
// end of the first walk to the start of the second while the odometry goes on
// without a jump (the second walk's odometry is re-based onto the first one's
// end), so nothing but the laser tells the filter it was carried away. The
// localiser must report a loss after the jump, a recovery, and end on the
// truth.
#include <carenav/localization/localize_job.h>
#include <carenav/sim/simulate_job.h>
#include <carenav/sim/simulator.h>

#include <mrpt/io/CFileInputStream.h>
#include <mrpt/io/CFileOutputStream.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/serialization/CArchive.h>

#include <gtest/gtest.h>

#include <unistd.h>
#include "interbot_laser.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace carenav::localization {
namespace {

namespace fs = std::filesystem;
const std::string kSrc = CARENAV_SOURCE_DIR;

fs::path scratch() {
  auto d = fs::temp_directory_path() / ("carenav_loc_kidnap_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

SensorParams hokuyo() { return fixtures::interbotLaser(10); }

sim::SimulateResult simulateWalk(const std::string& out, std::vector<sim::Vec2> path, int seed) {
  sim::SimulateOptions o;
  o.sensors = {hokuyo()};
  o.params.seed = seed;
  o.world = kSrc + "/maps/worlds/apartment.yaml";
  o.path = std::move(path);
  o.out = out;
  o.progress = false;
  return sim::runSimulate(o);
}

std::vector<mrpt::obs::CObservation::Ptr> readObservations(const std::string& path) {
  mrpt::io::CFileInputStream f(path);
  auto arch = mrpt::serialization::archiveFrom(f);
  std::vector<mrpt::obs::CObservation::Ptr> out;
  while (true) {
    mrpt::serialization::CSerializable::Ptr o;
    try {
      o = arch.ReadObject();
    } catch (const mrpt::ExceptionWithCallBackBase&) {
      break;  // end of file
    } catch (const std::exception&) {
      break;
    }
    auto obs = std::dynamic_pointer_cast<mrpt::obs::CObservation>(o);
    if (obs) out.push_back(obs);
  }
  return out;
}

struct TumRow {
  double t, x, y;
  std::string rest;  // z qx qy qz qw
};

std::vector<TumRow> readTum(const std::string& path) {
  std::vector<TumRow> out;
  std::ifstream f(path);
  std::string line;
  while (std::getline(f, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    TumRow r;
    ls >> r.t >> r.x >> r.y;
    std::getline(ls, r.rest);
    out.push_back(r);
  }
  return out;
}

TEST(KidnappedSim, TruthJumpsOdometryDoesNotLossAndRecoveryReported) {
  const auto dir = scratch();
  // Walk A in the south of the living room; walk B in its north, past the
  // table, 4.5 m away.
  const auto a = simulateWalk((dir / "a.rawlog").string(), {{1, 1}, {6, 1}, {6, 2.5}}, 2);
  const auto b = simulateWalk((dir / "b.rawlog").string(), {{4, 6.5}, {1, 6.5}, {1, 4.5}}, 5);
  ASSERT_TRUE(a.path_completed && b.path_completed);
  ASSERT_EQ(a.collisions + b.collisions, 0u);

  const auto obs_a = readObservations(a.rawlog), obs_b = readObservations(b.rawlog);
  ASSERT_GT(obs_a.size(), 100u);
  ASSERT_GT(obs_b.size(), 100u);
  // The last odometry reading of A and the first of B.
  mrpt::poses::CPose2D odo_a_end, odo_b_start;
  bool have_b = false;
  for (const auto& o : obs_a)
    if (auto od = std::dynamic_pointer_cast<mrpt::obs::CObservationOdometry>(o))
      odo_a_end = od->odometry;
  for (const auto& o : obs_b)
    if (auto od = std::dynamic_pointer_cast<mrpt::obs::CObservationOdometry>(o); od && !have_b) {
      odo_b_start = od->odometry;
      have_b = true;
    }
  ASSERT_TRUE(have_b);
  // B starts one laser period after A's last frame.
  const double shift = a.sim_seconds + 0.1;
  const auto shifted = [&](mrpt::Clock::time_point t) {
    return t +
           std::chrono::duration_cast<mrpt::Clock::duration>(std::chrono::duration<double>(shift));
  };

  const std::string joined = (dir / "kidnap.rawlog").string();
  {
    mrpt::io::CFileOutputStream f(joined);
    auto arch = mrpt::serialization::archiveFrom(f);
    for (const auto& o : obs_a) arch << *o;
    for (const auto& o : obs_b) {
      o->timestamp = shifted(o->timestamp);
      if (auto od = std::dynamic_pointer_cast<mrpt::obs::CObservationOdometry>(o))
        // odometry continues from A's end: A_end (+) (B_start^-1 (+) B)
        od->odometry = odo_a_end + (od->odometry - odo_b_start);
      arch << *o;
    }
  }
  const auto gt_a = readTum(a.ground_truth), gt_b = readTum(b.ground_truth);
  ASSERT_FALSE(gt_a.empty() || gt_b.empty());
  const std::string gt = (dir / "kidnap.gt.tum").string();
  {
    std::ofstream f(gt);
    char buf[128];
    for (const auto& r : gt_a) {
      std::snprintf(buf, sizeof buf, "%.6f %.6f %.6f", r.t, r.x, r.y);
      f << buf << r.rest << "\n";
    }
    for (const auto& r : gt_b) {
      std::snprintf(buf, sizeof buf, "%.6f %.6f %.6f", r.t + shift, r.x, r.y);
      f << buf << r.rest << "\n";
    }
  }
  // The jump is real: the truth moves metres between two frames.
  const double jump = std::hypot(gt_b.front().x - gt_a.back().x, gt_b.front().y - gt_a.back().y);
  ASSERT_GT(jump, 3.0);

  // The apartment's bare PNG as a map_server YAML.
  const std::string map = (dir / "apartment.yaml").string();
  std::ofstream(map) << "image: " << kSrc << "/maps/worlds/apartment.png\nresolution: 0.05\n"
                     << "origin: [0.0, 0.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\n"
                     << "free_thresh: 0.196\n";

  LocalizeJobOptions o;
  o.map = map;
  o.rawlog = joined;
  o.ref = gt;
  o.progress = false;
  // ini/interbot.ini's [localization] with every 60th beam (see
  // tests/integration/test_cli_localize_sim.cpp for why)
  o.params.particles_min = 200;
  o.params.particles_max = 5000;
  o.params.global_particles = 5000;
  o.params.update_min_d = 0.1;
  o.params.update_min_a = 5;
  o.params.lf_decimation = 60;
  InitialPose init;
  init.x = 1;
  init.y = 1;
  init.yaw = 0;
  init.std_x = init.std_y = 0.1;
  init.std_yaw = mrpt::DEG2RAD(3.0);
  o.init = init;
  const auto r = runLocalize(o);

  // Relative time of the kidnapping (events are stamped from the first scan).
  const double t_jump = shift;
  bool loss_after = false, recovery_after_loss = false;
  for (const auto& e : r.events) {
    EXPECT_GE(e.t, t_jump - 1e-6) << "an event before the kidnapping: " << e.name();
    if (e.kind == LocalizationEvent::Kind::Loss && e.t >= t_jump - 1e-6) loss_after = true;
    if (loss_after && e.kind == LocalizationEvent::Kind::Recovery) recovery_after_loss = true;
  }
  std::string events;
  for (const auto& e : r.events) events += std::string(" ") + e.name() + "@" + std::to_string(e.t);
  EXPECT_TRUE(loss_after) << "no loss after the kidnapping at " << t_jump
                          << " s; events:" << events;
  EXPECT_TRUE(recovery_after_loss) << events;
  RecordProperty("events", events);
  EXPECT_GE(r.injections, 1u);
  EXPECT_TRUE(r.converged_at_end);
  // Before the jump the track was right (tracking), at the end it is right
  // again. 0.3 m: the converged cloud's std here is a few centimetres; a
  // look-alike pose in this apartment is metres away.
  const auto& fin = r.track.back();
  const auto& truth = gt_b.back();
  RecordProperty(
      "final_error_mm",
      static_cast<int>(std::lround(1000 * std::hypot(fin.x - truth.x, fin.y - truth.y))));
  EXPECT_LT(std::hypot(fin.x - truth.x, fin.y - truth.y), 0.3)
      << "ended at " << fin.x << ", " << fin.y << ", truth " << truth.x << ", " << truth.y;
  // and just before the jump too
  for (const auto& p : r.track)
    if (p.t > gt_a.back().t - 0.05 && p.t <= gt_a.back().t + 1e-6)
      EXPECT_LT(std::hypot(p.x - gt_a.back().x, p.y - gt_a.back().y), 0.3);
  if (!::testing::Test::HasFailure()) fs::remove_all(dir);
}

}  // namespace
}  // namespace carenav::localization
