// The recovery guard of Localizer (recovery_ratio, recovery_patience,
// consistent_beams) on scans simulated in the apartment world: a converged
// filter keeps its estimate through occlusion and at a low scan rate, and a
// kidnapped robot is still found again.
#include <carenav/localization/localizer.h>
#include <carenav/sim/simulator.h>

#include <mrpt/obs/CObservation2DRangeScan.h>

#include <gtest/gtest.h>

#include "interbot_laser.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <utility>
#include <vector>

namespace carenav::localization {
namespace {

using mrpt::poses::CPose2D;

const std::string kWorld = std::string(CARENAV_SOURCE_DIR) + "/maps/worlds/apartment.yaml";

std::shared_ptr<const sim::World> apartment() {
  static auto w = std::make_shared<const sim::World>(sim::loadWorld(kWorld));
  return w;
}

SensorParams hokuyo() { return fixtures::interbotLaser(10); }

/** ini/interbot.ini's [localization] with every 60th beam, an update per scan. */
LocalizationParams params() {
  LocalizationParams p;
  p.particles_min = 200;
  p.particles_max = 5000;
  p.global_particles = 5000;
  p.lf_decimation = 60;
  return p;
}

/** Poses every ds metres along a polyline, heading along each segment. */
std::vector<CPose2D> walk(const std::vector<std::pair<double, double>>& pts, double ds) {
  std::vector<CPose2D> out;
  for (size_t i = 0; i + 1 < pts.size(); ++i) {
    const double dx = pts[i + 1].first - pts[i].first, dy = pts[i + 1].second - pts[i].second;
    const double len = std::hypot(dx, dy), yaw = std::atan2(dy, dx);
    for (double s = 0; s < len; s += ds)
      out.emplace_back(pts[i].first + s / len * dx, pts[i].second + s / len * dy, yaw);
  }
  return out;
}

/** Scans from the simulator at given true poses; odometry is the true
 *  motion (or, across a kidnap, what the caller says) with a little noise. */
class Replay {
 public:
  explicit Replay(Localizer& loc)
      : loc_(loc), sim_(apartment(), RobotParams{}, {hokuyo()}, sim::SimParams{}) {}

  /** One scan at `truth` after odometry `odo`; occlude: the first half of the
   *  beams read 0.6 m (a person next to the sensor). Returns the position
   *  error of the estimate. */
  double step(const CPose2D& truth, const CPose2D& odo, bool occlude = false, bool blind = false) {
    sim_.reset({truth.x(), truth.y(), truth.phi()});
    auto scan = std::dynamic_pointer_cast<mrpt::obs::CObservation2DRangeScan>(sim_.observe(0));
    if (occlude)
      for (size_t i = 0; i < scan->getScanSize() / 2; ++i) scan->setScanRange(i, 0.6f);
    if (blind)  // nothing in range: an open hall, or a blinded sensor
      for (size_t i = 0; i < scan->getScanSize(); ++i) scan->setScanRange(i, scan->maxRange);
    std::normal_distribution<double> n(0, 1);
    const double d = std::hypot(odo.x(), odo.y());
    const double ex = 0.02 * d * n(rng_), ephi = 0.01 * (d + std::abs(odo.phi())) * n(rng_);
    const CPose2D noisy(odo.x() + ex, odo.y(), odo.phi() + ephi);
    last_ = loc_.step(noisy, scan, t_ += 0.1);
    return std::hypot(last_.pose.x() - truth.x(), last_.pose.y() - truth.y());
  }
  /** Walks `poses` (the first one is where the robot already is); returns the
   *  largest position error. */
  double follow(const std::vector<CPose2D>& poses, bool occlude = false) {
    double worst = 0;
    for (size_t i = 1; i < poses.size(); ++i)
      worst = std::max(worst, step(poses[i], poses[i] - poses[i - 1], occlude));
    return worst;
  }
  const StepResult& last() const { return last_; }

 private:
  Localizer& loc_;
  sim::Simulator sim_;
  std::mt19937 rng_{7};
  double t_ = 0;
  StepResult last_;
};

// Converged on the south of the living room, then 40 scans with half of the
// beams cut short by a person: the likelihood falls for many updates in a
// row, but the scan does not contradict the map, so nothing is injected.
TEST(RecoveryGuard, OcclusionOfHalfTheBeamsInjectsNothingAndKeepsTheEstimate) {
  Localizer loc(apartment()->grid(), params());
  const auto path = walk({{1, 1}, {6, 1}, {6, 2.5}}, 0.05);
  loc.initPose(path.front(), 0.05, 0.05, mrpt::DEG2RAD(2.0));
  Replay replay(loc);
  const std::vector<CPose2D> clear(path.begin(), path.begin() + 40);
  EXPECT_LT(replay.follow(clear), 0.3);
  ASSERT_TRUE(loc.converged());
  const size_t before = loc.injections();
  const std::vector<CPose2D> occluded(path.begin() + 39, path.begin() + 80);
  double worst = 0, lowest_agreement = 1;
  for (size_t i = 1; i < occluded.size(); ++i) {
    worst = std::max(worst, replay.step(occluded[i], occluded[i] - occluded[i - 1], true));
    lowest_agreement = std::min(lowest_agreement, replay.last().agreement);
  }
  RecordProperty("lowest_agreement_pct", static_cast<int>(std::lround(100 * lowest_agreement)));
  EXPECT_EQ(loc.injections(), before);
  EXPECT_LT(worst, 0.3);
  EXPECT_TRUE(loc.events().empty());
  EXPECT_TRUE(loc.converged());
}

// Converged on walk A, then carried 4.5 m away (walk B) while odometry goes
// on without a jump: the estimate sees through walls, random particles are
// injected, a loss and a recovery are reported and the estimate is right again.
TEST(RecoveryGuard, AKidnappedRobotIsStillRecovered) {
  Localizer loc(apartment()->grid(), params());
  const auto a = walk({{1, 1}, {6, 1}, {6, 2.5}}, 0.05);
  const auto b = walk({{4, 6.5}, {1, 6.5}, {1, 4.5}}, 0.05);
  loc.initPose(a.front(), 0.05, 0.05, mrpt::DEG2RAD(2.0));
  Replay replay(loc);
  EXPECT_LT(replay.follow(a), 0.3);
  ASSERT_TRUE(loc.converged());
  EXPECT_EQ(loc.injections(), 0u);
  // The kidnap: the truth jumps, odometry says the robot moved 5 cm on.
  replay.step(b.front(), CPose2D(0.05, 0, 0));
  replay.follow(b);
  EXPECT_GT(loc.injections(), 0u);
  ASSERT_GE(loc.events().size(), 2u);
  EXPECT_EQ(loc.events().front().kind, LocalizationEvent::Kind::Loss);
  EXPECT_EQ(loc.events().back().kind, LocalizationEvent::Kind::Recovery);
  EXPECT_TRUE(loc.converged());
  const CPose2D end = loc.pose();
  EXPECT_LT(std::hypot(end.x() - b.back().x(), end.y() - b.back().y()), 0.3);
}

// One scan every 0.5 m (and a corner turned between two scans): large
// odometry steps, a likelihood that jumps from scan to scan, but a right
// estimate, so nothing is injected.
TEST(RecoveryGuard, LowScanRateInjectsNothingWhileTheEstimateIsRight) {
  Localizer loc(apartment()->grid(), params());
  const auto path = walk({{1, 1}, {6, 1}, {6, 2.5}, {1, 2.5}, {1, 1}, {6, 1}}, 0.5);
  loc.initPose(path.front(), 0.05, 0.05, mrpt::DEG2RAD(2.0));
  Replay replay(loc);
  EXPECT_LT(replay.follow(path), 0.3);
  EXPECT_EQ(loc.injections(), 0u);
  EXPECT_TRUE(loc.events().empty());
}

// The agreement itself: 1 at the truth, also with half the beams cut short;
// low for the same scan seen from a pose metres away.
TEST(RecoveryGuard, ScanAgreementIsHighAtTheTruthAndLowElsewhere) {
  Localizer loc(apartment()->grid(), params());
  sim::Simulator sim(apartment(), RobotParams{}, {hokuyo()}, sim::SimParams{});
  sim.reset({2, 1.5, 0.3});
  auto scan = std::dynamic_pointer_cast<mrpt::obs::CObservation2DRangeScan>(sim.observe(0));
  EXPECT_GT(loc.scanAgreement(*scan, CPose2D(2, 1.5, 0.3)), 0.95);
  EXPECT_LT(loc.scanAgreement(*scan, CPose2D(3, 6.5, 0.3)), loc.params().consistent_beams);
  for (size_t i = 0; i < scan->getScanSize() / 2; ++i) scan->setScanRange(i, 0.6f);
  EXPECT_GT(loc.scanAgreement(*scan, CPose2D(2, 1.5, 0.3)), 0.95);
}

/** The apartment's grid with a wall that is not in the world: a band of
 *  occupied cells across the living room (furniture mapped and since moved,
 *  a person mapped as an obstacle, a doubled wall of a SLAM map). */
mrpt::maps::COccupancyGridMap2D gridWithASpuriousWall() {
  mrpt::maps::COccupancyGridMap2D g = apartment()->grid();
  for (double x = 2; x <= 5; x += 0.5 * g.getResolution())
    for (double y = 1.7; y <= 1.8; y += 0.5 * g.getResolution()) g.setPos(x, y, 0.0f);
  return g;
}

/** The south walk of the living room and back, past the spurious wall: many
 *  beams cross it at the right pose. Returns the largest position error. */
double walkPastTheSpuriousWall(Localizer& loc) {
  const auto path = walk({{1, 1}, {6, 1}, {6, 2.5}, {1, 2.5}, {1, 1}}, 0.05);
  loc.initPose(path.front(), 0.05, 0.05, mrpt::DEG2RAD(2.0));
  Replay replay(loc);
  double worst = 0, lowest = 1;
  for (size_t i = 1; i < path.size(); ++i) {
    worst = std::max(worst, replay.step(path[i], path[i] - path[i - 1]));
    lowest = std::min(lowest, replay.last().agreement);
  }
  EXPECT_LT(lowest, loc.params().consistent_beams);  // the map contradicts the right pose
  return worst;
}

// The map contradicts a right estimate: it is challenged (a global search
// runs beside it), but the search finds nothing that explains the scans
// better, so no loss is declared, no random particle joins the cloud, and
// the estimate stays right throughout.
TEST(Challenge, AContradictedButRightEstimateIsNotLost) {
  Localizer loc(gridWithASpuriousWall(), params());
  const double worst = walkPastTheSpuriousWall(loc);
  EXPECT_GE(loc.challenges(), 1u);
  EXPECT_EQ(loc.challengesWon(), 0u);
  EXPECT_TRUE(loc.events().empty());
  EXPECT_EQ(loc.injections(), loc.challenges());  // only the challengers' random particles
  EXPECT_LT(worst, 0.3);
  EXPECT_TRUE(loc.converged());
}

// The same walk with challenge = false: the earlier guard replaces the
// contradicted estimate by a global search and records a loss.
TEST(Challenge, WithoutChallengeTheContradictedEstimateIsLost) {
  LocalizationParams p = params();
  p.challenge = false;
  Localizer loc(gridWithASpuriousWall(), p);
  walkPastTheSpuriousWall(loc);
  EXPECT_EQ(loc.challenges(), 0u);
  ASSERT_FALSE(loc.events().empty());
  EXPECT_EQ(loc.events().front().kind, LocalizationEvent::Kind::Loss);
}

// A kidnap: the challenger's search explains the scans better than the
// estimate, so it takes over (a loss, then a recovery on the truth).
TEST(Challenge, AKidnappedRobotIsFoundByTheChallenger) {
  Localizer loc(apartment()->grid(), params());
  const auto a = walk({{1, 1}, {6, 1}, {6, 2.5}}, 0.05);
  const auto b = walk({{4, 6.5}, {1, 6.5}, {1, 4.5}}, 0.05);
  loc.initPose(a.front(), 0.05, 0.05, mrpt::DEG2RAD(2.0));
  Replay replay(loc);
  replay.follow(a);
  ASSERT_TRUE(loc.events().empty());
  replay.step(b.front(), CPose2D(0.05, 0, 0));
  bool challenged = false;
  for (size_t i = 1; i < b.size(); ++i) {
    replay.step(b[i], b[i] - b[i - 1]);
    challenged = challenged || replay.last().challenge;
  }
  EXPECT_TRUE(challenged);
  EXPECT_GE(loc.challengesWon(), 1u);
  ASSERT_GE(loc.events().size(), 2u);
  EXPECT_EQ(loc.events().front().kind, LocalizationEvent::Kind::Loss);
  const CPose2D end = loc.pose();
  EXPECT_LT(std::hypot(end.x() - b.back().x(), end.y() - b.back().y()), 0.3);
}

// Converged, then 30 scans (1.5 m) with no return in range: no update is
// weighed, the estimate follows odometry (no jump, nothing injected) and the
// filter goes on from there when returns come back.
TEST(DeadReckoning, ScansWithNoReturnsInRangeLeaveTheEstimateToOdometry) {
  Localizer loc(apartment()->grid(), params());
  const auto path = walk({{1, 1}, {6, 1}, {6, 2.5}}, 0.05);
  loc.initPose(path.front(), 0.05, 0.05, mrpt::DEG2RAD(2.0));
  Replay replay(loc);
  EXPECT_LT(replay.follow(std::vector<CPose2D>(path.begin(), path.begin() + 40)), 0.3);
  ASSERT_TRUE(loc.converged());
  const size_t updates = loc.updates();
  double worst = 0;
  for (size_t i = 40; i < 70; ++i) {
    worst = std::max(worst, replay.step(path[i], path[i] - path[i - 1], false, true));
    EXPECT_TRUE(replay.last().dead_reckoning) << i;
    EXPECT_FALSE(replay.last().updated) << i;
  }
  EXPECT_EQ(loc.updates(), updates);
  EXPECT_LT(worst, 0.3);
  EXPECT_EQ(loc.injections(), 0u);
  EXPECT_TRUE(loc.events().empty());
  EXPECT_LT(replay.follow(std::vector<CPose2D>(path.begin() + 69, path.begin() + 110)), 0.3);
  EXPECT_GT(loc.updates(), updates);
  EXPECT_TRUE(loc.converged());
}

// min_returns 0: every scan is weighed, an empty one too (the earlier rule).
TEST(DeadReckoning, MinReturnsZeroWeighsEveryScan) {
  LocalizationParams p = params();
  p.min_returns = 0;
  Localizer loc(apartment()->grid(), p);
  const auto path = walk({{1, 1}, {6, 1}}, 0.05);
  loc.initPose(path.front(), 0.05, 0.05, mrpt::DEG2RAD(2.0));
  Replay replay(loc);
  replay.step(path[1], path[1] - path[0], false, true);
  EXPECT_FALSE(replay.last().dead_reckoning);
  EXPECT_TRUE(replay.last().updated);
}

}  // namespace
}  // namespace carenav::localization
