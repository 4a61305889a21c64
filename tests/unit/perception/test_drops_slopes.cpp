// Rules of issue 17 (docs/perceive.md): drop edges from missing or lower
// returns where the floor should be, the depth noise measured per frame, and
// steep ground (rule 4) against the plane whatever the mounting error.
#include "scene.h"

#include <carenav/perception/ism.h>
#include <carenav/perception/pipeline.h>

#include <gtest/gtest.h>

using namespace carenav;
using namespace carenav::perception;
using namespace carenav_test;

namespace {

constexpr double kDeg = M_PI / 180;
constexpr double kProfileNoise = 0.005;  // ini/isr-aiwalker.ini [sensor.kinect] noise_std

PerceptionParams walker() {
  PerceptionParams p;
  p.depth_noise_std = kProfileNoise;
  return p;
}

struct Shot {
  FrameResult r;
  std::unique_ptr<Pipeline> pipe;
};

/** One frame of `s` seen from `truth` with noise `noise` (std at 1 m, times
 *  depth^2), given to the pipeline as if the camera were at `given`; W x H
 *  pixels (the Kinect's 512 x 424, or a quarter of it per side: 128 x 106,
 *  the simulator's depth_decimation 4). */
Shot perceive(const Scene& s, const mrpt::poses::CPose3D& truth, const mrpt::poses::CPose3D& given,
              double noise, const PerceptionParams& p = walker(), unsigned seed = 3, int W = 512,
              int H = 424) {
  Cloud optical;
  renderDepth(s, truth, seed, 1.0, &optical, W, H, noise);
  const Cloud c = toRobotFrame(optical, given, true);
  Shot sh;
  sh.pipe = std::make_unique<Pipeline>(p, Method::RrtGpd);
  FrameInput in;
  in.cloud = &c;
  in.sensor_origin = {static_cast<float>(given.x()), static_cast<float>(given.y()),
                      static_cast<float>(given.z())};
  sh.r = sh.pipe->process(in, false);
  return sh;
}

mrpt::poses::CPose3D camera(double h, double pitch_deg) {
  return mrpt::poses::CPose3D(0.2, 0, h, 0, pitch_deg * kDeg, 0);
}

/** Occupied share of the cells with centres in the box that hold evidence. */
double occupiedSeen(const LocalOccupancy& g, double x0, double x1, double y0, double y1) {
  size_t n = 0, occ = 0;
  for (int i = 0; i < g.cells(); ++i)
    for (int j = 0; j < g.cells(); ++j) {
      const double x = g.centreX(i), y = g.centreY(j), pr = g.prob(i, j);
      if (x < x0 || x > x1 || y < y0 || y > y1 || std::abs(pr - 0.5) < 1e-6) continue;
      ++n;
      occ += pr > 0.55 ? 1 : 0;
    }
  return n ? static_cast<double>(occ) / n : 0.0;
}

/** Nearest occupied cell ahead in the walker's corridor (|y| <= 0.325 m), or 99. */
double firstOccupiedAhead(const LocalOccupancy& g) {
  double best = 99;
  for (int i = 0; i < g.cells(); ++i)
    for (int j = 0; j < g.cells(); ++j)
      if (g.centreX(i) > 0.25 && std::abs(g.centreY(j)) <= 0.325 && g.prob(i, j) > 0.55)
        best = std::min(best, g.centreX(i));
  return best;
}

}  // namespace

TEST(DropEdges, AFloorEndingWhereItWouldStillReturnIsAnObstacleLine) {
  // The camera low and pitched up (0.6 m, 20 deg): beyond the edge at 1.5 m
  // the rays reach the lower floor (3 m down) beyond depth_max, nothing
  // returns; without the rule nothing is occupied before the robot falls.
  Scene s;
  s.floor(-10, 1.5).floor(1.5, 10, -3.0);
  const auto sh = perceive(s, camera(0.6, 20), camera(0.6, 20), kProfileNoise);
  EXPECT_GT(sh.r.drop_edges, 50u);
  EXPECT_LE(firstOccupiedAhead(sh.pipe->grid()), 1.6);
  EXPECT_GT(occupiedSeen(sh.pipe->grid(), 1.45, 1.6, -0.3, 0.3), 0.5);
  EXPECT_LT(occupiedSeen(sh.pipe->grid(), 0.9, 1.35, -1, 1), 0.01);
}

TEST(DropEdges, LowerReturnsBeyondTheFloorMarkTheEdgeOfACurb) {
  // A 10 cm curb down at 2 m, seen from 0.6 m / 20 deg: the lower floor
  // returns only far beyond the edge (its shadow), the edge itself becomes
  // an obstacle line.
  Scene s;
  s.floor(-10, 2.0).floor(2.0, 10, -0.10);
  const auto sh = perceive(s, camera(0.6, 20), camera(0.6, 20), kProfileNoise);
  EXPECT_LE(firstOccupiedAhead(sh.pipe->grid()), 2.1);
  EXPECT_LT(occupiedSeen(sh.pipe->grid(), 0.9, 1.8, -1, 1), 0.01);
}

TEST(DropEdges, AFloorRunningToTheRangeLimitIsNoDrop) {
  // Camera 1.2 m high, 15 deg: the floor is in view up to depth_max; the
  // returns end there because of the range, not at an edge.
  Scene s;
  s.floor(-10, 20);
  const auto sh = perceive(s, camera(1.2, 15), camera(1.2, 15), kProfileNoise);
  EXPECT_LT(occupiedSeen(sh.pipe->grid(), 0.5, 5, -3, 3), 0.005);
  EXPECT_EQ(firstOccupiedAhead(sh.pipe->grid()), 99);
}

TEST(NoiseMeasured, ThreeTimesTheModelsNoiseIsMeasuredAndTheFloorStaysFree) {
  Scene s;
  s.floor(-10, 20);
  const auto sh = perceive(s, camera(0.9, 30), camera(0.9, 30), 3 * kProfileNoise);
  EXPECT_GT(sh.r.noise_scale, 2.4);
  EXPECT_LT(sh.r.noise_scale, 3.6);
  EXPECT_LT(occupiedSeen(sh.pipe->grid(), 0.5, 4.5, -3, 3), 0.01);
  // The model as given (noise_adapt_max 1) calls the noise obstacles.
  PerceptionParams fixed = walker();
  fixed.noise_adapt_max = 1;
  const auto off = perceive(s, camera(0.9, 30), camera(0.9, 30), 3 * kProfileNoise, fixed);
  EXPECT_EQ(off.r.noise_scale, 1.0);
  EXPECT_GT(occupiedSeen(off.pipe->grid(), 0.5, 4.5, -3, 3), 0.05);
}

TEST(SteepGround, ATwelveDegreeRampIsNeverClearWhateverThePlane) {
  // The case: 0.6 m / 20 deg, the mounting pitch off by 0, +3 and -3
  // deg; a 12 deg ramp (max_slope_deg 8) from 1.5 m for 1 m, then its
  // landing. Blocked within 0.3 m of its foot.
  for (const double err : {0.0, 3.0, -3.0}) {
    Scene s;
    s.floor(-10, 1.5).ramp(1.5, 2.5, std::tan(12 * kDeg));
    const auto sh = perceive(s, camera(0.6, 20 + err), camera(0.6, 20), kProfileNoise);
    EXPECT_LE(firstOccupiedAhead(sh.pipe->grid()), 1.8) << "pitch error " << err;
  }
}

TEST(SteepGround, AFourDegreeRampStaysFree) {
  for (const double err : {0.0, 3.0, -3.0}) {
    Scene s;
    s.floor(-10, 1.5).ramp(1.5, 3.5, std::tan(4 * kDeg));
    const auto sh = perceive(s, camera(0.6, 20 + err), camera(0.6, 20), kProfileNoise);
    EXPECT_LT(occupiedSeen(sh.pipe->grid(), 0.5, 3.5, -1, 1), 0.01) << "pitch error " << err;
  }
}

namespace {

/** Elevation grid of a floor (z = 0) up to x = 1.5 m and a ramp of `deg`
 *  beyond it to x = 3 m, sampled every 1 cm with 1 mm of deterministic
 *  jitter; the rule-4 verdicts against `plane`. */
std::vector<VoxelClass> classifyRamp(double deg, const Plane& plane, IsmStats& st) {
  Cloud c;
  const double t = std::tan(deg * kDeg);
  for (int a = 50; a < 300; ++a)
    for (int b = -100; b <= 100; ++b) {
      const double x = a * 0.01, y = b * 0.01, jitter = 0.001 * (((a * 7 + b * 13) % 5) - 2);
      c.points.push_back({static_cast<float>(x), static_cast<float>(y),
                          static_cast<float>((x < 1.5 ? 0.0 : (x - 1.5) * t) + jitter)});
    }
  static ElevationGrid g(200, 0.05);
  g.build(c, -1, 2, 3);
  PerceptionParams p = walker();
  const Point3f o{0.2f, 0.f, 0.9f};
  std::vector<VoxelClass> classes;
  st = classifyVoxels(g, plane, p, &o, classes);
  return classes;
}

/** Obstacle share of the voxels with centres in x0..x1, |y| < 0.5. */
double obstacleShare(const std::vector<VoxelClass>& classes, double x0, double x1) {
  ElevationGrid g(200, 0.05);
  size_t n = 0, obs = 0;
  for (int i = 0; i < 200; ++i)
    for (int j = 0; j < 200; ++j) {
      const auto vc = classes[static_cast<size_t>(i) * 200 + j];
      if (vc == VoxelClass::None || g.centre(i) < x0 || g.centre(i) > x1 ||
          std::abs(g.centre(j)) > 0.5)
        continue;
      ++n;
      obs += vc == VoxelClass::Obstacle;
    }
  return n ? static_cast<double>(obs) / n : 0.0;
}

}  // namespace

TEST(SteepGround, ARampSteeperThanMaxSlopeIsAnObstacleEvenWhenThePlaneLiesOnIt) {
  // The plane fitted to the 12 deg ramp itself (the ramp fills the view):
  // rules 1-3 see the ramp on the plane; rule 4 measures it against the
  // robot frame's level (the plane is tilted more than prior_tilt_deg).
  const double a = 12 * kDeg;
  const Plane on_ramp = Plane::fromPointNormal({2.0, 0, 0.5 * std::tan(a)},
                                               Eigen::Vector3d(-std::sin(a), 0, std::cos(a)));
  IsmStats st;
  const auto classes = classifyRamp(12, on_ramp, st);
  EXPECT_GT(st.steep_voxels, 100u);
  EXPECT_GT(obstacleShare(classes, 1.8, 2.7), 0.9);
}

TEST(SteepGround, SlopesAreMeasuredAgainstALevelPlaneAndGentleRampsStayGround) {
  IsmStats st;
  // 12 deg against the floor plane: an obstacle (rules 1-2 above the plane or rule 4).
  EXPECT_GT(obstacleShare(classifyRamp(12, Plane{}, st), 1.8, 2.7), 0.9);
  // 5 deg: ground all along, no steep voxel, the floor too.
  const auto gentle = classifyRamp(5, Plane{}, st);
  EXPECT_EQ(st.steep_voxels, 0u);
  EXPECT_LT(obstacleShare(gentle, 0.6, 2.7), 0.01);
  // The floor under a plane tilted 2 deg (within prior_tilt_deg, a mounting
  // error): the slope is measured against the plane, the floor stays ground.
  const double b = 2 * kDeg;
  const Plane tilted =
      Plane::fromPointNormal({0, 0, 0}, Eigen::Vector3d(-std::sin(b), 0, std::cos(b)));
  classifyRamp(0, tilted, st);
  EXPECT_EQ(st.steep_voxels, 0u);
}

TEST(GentleGround, ASixDegreeRampWithThePitchOffByThreeDegreesStaysMostlyFree) {
  // Camera 0.7 m / 25 deg, truly 28 deg: rules 1-3 leave 68 % of the ramp
  // (seen 1.5-3.5 m) occupied; rule 5 (the 7 x 7 fit over every judged voxel,
  // no steeper than max_slope_deg) keeps most of it ground.
  Scene s;
  s.floor(-10, 1.5).ramp(1.5, 3.5, 2 * std::tan(6 * kDeg));
  const auto sh = perceive(s, camera(0.7, 28), camera(0.7, 25), kProfileNoise);
  EXPECT_LT(occupiedSeen(sh.pipe->grid(), 0.5, 3.5, -1, 1), 0.25);
  EXPECT_GT(sh.r.ism.rescued_voxels, 1000u);
}

TEST(GentleGround, SlopesAreMeasuredAgainstTheFloorNearTheRobotWhenThePlaneLeansOnTheRamp) {
  // Twice the noise, the pitch off by +3 deg: the plane leans 4.9 deg (floor
  // and ramp), beyond the mounting's tilt uncertainty; the floor near the
  // robot is the reference, the 5 deg ramp is not steep (56 % of it was
  // occupied against the robot frame's level).
  Scene s;
  s.floor(-10, 1.5).ramp(1.5, 3.5, 2 * std::tan(5 * kDeg));
  const auto sh = perceive(s, camera(0.7, 28), camera(0.7, 25), 2 * kProfileNoise);
  EXPECT_LT(occupiedSeen(sh.pipe->grid(), 0.5, 3.5, -1, 1), 0.05);
  EXPECT_LT(sh.r.ism.steep_voxels, 50u);
}

namespace {

/** A ramp of `deg` from 1.5 m to 3 m (then its landing) seen from 0.8 m /
 *  30 deg with the pitch off by `pitch_err` deg and twice the profile's
 *  noise, under `p`. */
Shot rampShot(double deg, double pitch_err, const PerceptionParams& p = walker()) {
  Scene s;
  s.floor(-10, 1.5).ramp(1.5, 3.0, 1.5 * std::tan(deg * kDeg));
  return perceive(s, camera(0.8, 30 + pitch_err), camera(0.8, 30), 2 * kProfileNoise, p);
}

}  // namespace

TEST(RampsByRegion, ASevenAndAHalfDegreeNoisyRampIsTraversable) {
  // Rule 6: the ramp is one region whose slope (~500 cells, a standard error
  // of ~0.1 deg) is judged as a whole; without it (the 7 x 7 windows alone,
  // 0.5-1 deg each) 12 / 60 / 7 % of the ramp are occupied and the walker
  // is stopped at 2.4 / 1.6 / 2.3 m (pitch off by 0 / +3 / -3 deg).
  for (const double err : {0.0, 3.0, -3.0}) {
    const auto sh = rampShot(7.5, err);
    EXPECT_LT(occupiedSeen(sh.pipe->grid(), 1.6, 2.9, -0.5, 0.5), 0.06) << "pitch error " << err;
    EXPECT_GT(firstOccupiedAhead(sh.pipe->grid()), 2.3) << "pitch error " << err;
  }
}

TEST(RampsByRegion, AnEightAndAHalfDegreeNoisyRampIsBlockedAtItsFoot) {
  for (const double err : {0.0, 3.0, -3.0}) {
    const auto sh = rampShot(8.5, err);
    EXPECT_GT(occupiedSeen(sh.pipe->grid(), 1.6, 2.9, -0.5, 0.5), 0.9) << "pitch error " << err;
    EXPECT_LE(firstOccupiedAhead(sh.pipe->grid()), 1.8) << "pitch error " << err;
  }
}

TEST(RampsByRegion, AStepIsNoRampWhateverItsTopsSlope) {
  // A level plateau 8 cm up from 1.5 m: a gentle region, but its border
  // with the floor is a step (the planes differ by 8 cm all along it), so
  // rule 6 gives none of it back as ground: as occupied as without rule 6
  // (regions never judged), and blocked at the step.
  Scene s;
  s.floor(-10, 1.5).floor(1.5, 10, 0.08);
  PerceptionParams off = walker();
  off.region_min_cells = 1000000;
  const auto with6 = perceive(s, camera(0.8, 30), camera(0.8, 30), kProfileNoise);
  const auto without6 = perceive(s, camera(0.8, 30), camera(0.8, 30), kProfileNoise, off);
  EXPECT_LE(firstOccupiedAhead(with6.pipe->grid()), 1.6);
  EXPECT_GE(occupiedSeen(with6.pipe->grid(), 1.6, 2.5, -0.5, 0.5),
            occupiedSeen(without6.pipe->grid(), 1.6, 2.5, -0.5, 0.5));
  EXPECT_GT(occupiedSeen(with6.pipe->grid(), 1.6, 2.5, -0.5, 0.5), 0.15);
}

namespace {

/** Voxel classes of a level surface at height `top` (robot frame), seen from
 *  0.9 m (x 0.5-3 m, |y| <= 1 m, every 1 cm with 1 mm of deterministic
 *  jitter), against the level plane at height `plane_z`. */
std::vector<VoxelClass> classifyLevel(double top, double plane_z) {
  Cloud c;
  for (int a = 50; a < 300; ++a)
    for (int b = -100; b <= 100; ++b) {
      const double jitter = 0.001 * (((a * 7 + b * 13) % 5) - 2);
      c.points.push_back({static_cast<float>(a * 0.01), static_cast<float>(b * 0.01),
                          static_cast<float>(top + jitter)});
    }
  static ElevationGrid g(200, 0.05);
  g.build(c, -1, 2, 3);
  const Point3f o{0.2f, 0.f, 0.9f};
  std::vector<VoxelClass> classes;
  classifyVoxels(g, Plane::fromPointNormal({0, 0, plane_z}, Eigen::Vector3d(0, 0, 1)), walker(), &o,
                 classes);
  return classes;
}

/** A ramp of `deg` from 1.2 m to 2.7 m (then its landing) seen from `h` m,
 *  pitched 25 deg with the pitch off by `err` deg, `noise` times the
 *  profile's noise: occupied share of the seen cells 0.3-4.5 m ahead, |y|
 *  <= 1.5 m. */
double rampOccupied(double deg, double h, double err, double noise) {
  Scene s;
  s.floor(-10, 1.2).ramp(1.2, 2.7, 1.5 * std::tan(deg * kDeg));
  const auto sh = perceive(s, camera(h, 25 + err), camera(h, 25), noise * kProfileNoise);
  return occupiedSeen(sh.pipe->grid(), 0.3, 4.5, -1.5, 1.5);
}

}  // namespace

TEST(FloorRegion, TheFloorUnderTheRobotIsGroundWhenThePlaneLiesAboveIt) {
  // The plane 5 cm above the floor (the plateau case): rules 1-2
  // call the whole floor an obstacle and rules 3 and 5 have no ground to
  // start from. Rule 6's floor region (level, and at z = 0 under the sensor
  // within prior_height_tolerance) gives back what passes rules 1-2
  // against its own plane: without that, all of it stays an obstacle.
  const auto classes = classifyLevel(0.0, 0.05);
  EXPECT_LT(obstacleShare(classes, 0.6, 2.9), 0.02);
}

TEST(FloorRegion, ALowerSurfaceSeenFirstIsNoFloorUnderTheRobot) {
  // The robot on a floor the camera does not see (the blind zone), the
  // street 8 cm below it in view (a curb down just ahead): the nearest
  // region is level but 8 cm off z = 0 under the sensor, so it is not the
  // floor under the robot and keeps its obstacles (with the floor region
  // rescued whatever its height, 0 % would be).
  const auto classes = classifyLevel(-0.08, 0.0);
  EXPECT_GT(obstacleShare(classes, 0.6, 2.9), 0.95);
}

TEST(SurfaceNoise, ARampRisingAwayIsJudgedWithTheNoiseAboutItsOwnPlane) {
  // About a surface rising away from the sensor the samples scatter more
  // than about a level floor (depth_noise_std r H, H the sensor's height
  // over the ramp's plane). Judged with the level floor's noise: 4.9 % and
  // 4.4 % occupied (its far end and cells that look uneven).
  EXPECT_LT(rampOccupied(7.0, 0.9, 3, 2), 0.035);
  EXPECT_LT(rampOccupied(6.0, 1.1, 3, 2), 0.035);
}

TEST(SlopeVerdicts, RuleFourMeasuresAgainstTheFloorsRegion) {
  // Pitch off by +3 deg: the floor the robot stands on looks tilted by 3
  // deg, beyond what slopeReference() accepts from the nearest ground
  // voxels, so rule 4 alone measured the ramp against the level (6.5 deg +
  // 3): 31 % and 22 % occupied. Against the floor's region of rule 6: < 3 %.
  EXPECT_LT(rampOccupied(6.5, 0.9, 3, 2), 0.03);
  EXPECT_LT(rampOccupied(6.0, 1.1, 3, 2), 0.03);
}

TEST(SlopeVerdicts, ASteepWindowDoesNotSpreadOverGroundJudgedGentle) {
  // Rule 4's windows call a few cells of a 7 deg ramp steep (a slope
  // standard error of ~1 deg at 3 m); the inverse sensor model spread each
  // of them ~0.16 m along its ray over the cells whose own window or region
  // read gentle: 11.7 % occupied. Without that spread: < 7 %.
  EXPECT_LT(rampOccupied(7.0, 1.1, -3, 2), 0.07);
}

namespace {

/** A ramp of `deg` from x = 2.55 m, seen from 0.64 m pitched 44 deg and
 *  rolled 2 deg (the top rows of the image end about 0.2 m up a steep
 *  ramp): render seed `seed`, the profile's noise. */
Shot shortView(double deg, unsigned seed) {
  Scene s;
  s.floor(-10, 2.55).ramp(2.55, 4.05, 1.5 * std::tan(deg * kDeg));
  const mrpt::poses::CPose3D cam(0.2, 0, 0.64, 0, 44 * kDeg, 2 * kDeg);
  return perceive(s, cam, cam, kProfileNoise, walker(), seed);
}

}  // namespace

TEST(ShortView, ASteepRampSeenOverAFewRowsIsNotTraversable) {
  // The view ends a few cells up a 15 deg ramp: every cell of it lies within
  // the noise's smear of its foot or of the view's end, so rule 6's trimmed
  // fit has nothing to judge and rules 1-5 call the ramp ground. The plain
  // fit over the short region (flattened by the smear) plus 4 standard
  // errors exceeds max_slope_deg: steep. Without that, no voxel was steep and
  // the corridor was clear (nothing occupied) on 3 of these 5 frames.
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const auto sh = shortView(15, seed);
    EXPECT_GT(sh.r.ism.steep_voxels, 50u) << "seed " << seed;
    EXPECT_LE(firstOccupiedAhead(sh.pipe->grid()), 2.55 + 0.3) << "seed " << seed;
  }
}

TEST(ShortView, AFiveDegreeRampSeenOverAFewRowsStaysTraversable) {
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const auto sh = shortView(5, seed);
    EXPECT_EQ(sh.r.ism.steep_voxels, 0u) << "seed " << seed;
    EXPECT_GT(firstOccupiedAhead(sh.pipe->grid()), 4.0) << "seed " << seed;
    EXPECT_LT(occupiedSeen(sh.pipe->grid(), 0.5, 3.5, -1.5, 1.5), 0.01) << "seed " << seed;
  }
}

TEST(RegionBorders, TheRangeLimitIsNoBorder) {
  // Ramps of 5 and 6 deg running out of range (to depth_max) under 2-3 times
  // the profile's noise: counted as a border, the voxels near depth_max cut
  // the fit's margin off the far part of the ramp's region, it had no
  // interior to judge, and 49 % / 57 % of the view was occupied, the walker
  // stopped at 2.3 m / 1.9 m. The end of the view is no kink.
  struct Case {
    double deg, x0, h, noise;
  };
  for (const Case c : {Case{5, 2.5, 1.1, 2}, Case{6, 2.0, 0.85, 3}}) {
    Scene s;
    s.floor(-10, c.x0).ramp(c.x0, 10, (10 - c.x0) * std::tan(c.deg * kDeg));
    const auto sh = perceive(s, camera(c.h, 19), camera(c.h, 19), c.noise * kProfileNoise);
    EXPECT_LT(occupiedSeen(sh.pipe->grid(), 0.3, 4.5, -1.5, 1.5), 0.02) << c.deg << " deg";
    EXPECT_GT(firstOccupiedAhead(sh.pipe->grid()), 3.0) << c.deg << " deg";
  }
}

TEST(BeyondRegions, TheLandingPastARampsTopIsGround) {
  // The 6 deg ramp of rampShot() levels off at 3 m; its landing lies in the
  // band near depth_max, too thin for a region of its own, and was tested
  // against the ramp's plane alone (9 cm below it 0.75 m past the top):
  // 2.6 % / 14 % of the landing occupied (pitch off by 0 / +3 deg). Against
  // the heights between the ramp's plane and the level through the ramp's
  // last cells: < 1.5 %.
  for (const double err : {0.0, 3.0}) {
    const auto sh = rampShot(6.0, err);
    EXPECT_LT(occupiedSeen(sh.pipe->grid(), 3.0, 4.5, -1.5, 1.5), 0.015) << "pitch error " << err;
  }
}

TEST(FloorRegion, ARampWhoseFootHidesTheFloorIsNoFloor) {
  // A 7 deg ramp from 1.2 m seen from 1.1 m with the pitch off by -3 deg:
  // the floor in view ends at its foot and the ramp, 4 deg tilted in the
  // robot frame, is the first region level within the tilt uncertainty.
  // Taken as the floor, its level landing measured 7.1 deg against it and
  // was judged steep: 70 % of the landing occupied. The ramp's plane lies
  // several cm below the floor under the sensor: no floor; the landing is judged
  // against rule 4's reference.
  Scene s;
  s.floor(-10, 1.2).ramp(1.2, 2.7, 1.5 * std::tan(7 * kDeg));
  const auto sh = perceive(s, camera(1.1, 22), camera(1.1, 25), 2 * kProfileNoise);
  EXPECT_LT(occupiedSeen(sh.pipe->grid(), 2.8, 4.5, -1.5, 1.5), 0.02);
  EXPECT_LT(occupiedSeen(sh.pipe->grid(), 1.2, 2.7, -1.5, 1.5), 0.01);
}

TEST(RegionBorders, AOneCellHoleInARegionIsNoBorder) {
  // Gentle ramps (4-7 deg) from 2.2-2.9 m to beyond the view, seen by a low
  // camera (0.55-0.75 m, pitched 17-30 deg) under 2-3 times the profile's
  // noise. Single voxels inside the ramp are not judged there (too few
  // samples, or not flat within the level-floor noise); as borders each cut
  // a disc of the fit's margin (about 1.2 m across at 3.5 m) out of the
  // ramp's region, which then held too few cells to be judged and kept the
  // false obstacles of rules 1-5: 13-30 % of the ramp occupied in 5 of these
  // 12 cases, 4 of 12 below 10 %. A one-cell hole is no border now: those 5
  // at most 0.6 %, 9 of 12 below 10 %. The other 3 (17-33 %) are unchanged
  // (docs/BENCHMARKS.md, "one-cell holes in a ramp's region").
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(0, 1);
  int below_10pct = 0;
  for (int k = 0; k < 12; ++k) {
    const double deg = 4 + 3 * u(rng), x0 = 2.2 + 0.7 * u(rng), h = 0.55 + 0.2 * u(rng),
                 pitch = 17 + 13 * u(rng), noise = (2 + u(rng)) * kProfileNoise;
    Scene s;
    s.floor(-10, x0).ramp(x0, 10, (10 - x0) * std::tan(deg * kDeg));
    const auto sh = perceive(s, camera(h, pitch), camera(h, pitch), noise, walker(), 100 + k);
    const double occ = occupiedSeen(sh.pipe->grid(), x0 + 0.1, 4.5, -1.5, 1.5);
    below_10pct += occ < 0.10;
    RecordProperty("case" + std::to_string(k), std::to_string(occ));
  }
  EXPECT_GE(below_10pct, 9);
}

TEST(StepBorders, ALowStepUpIsBlockedWhenTheGroundPlaneSplitsItsLevels) {
  // Steps up of 2.1-2.5 cm seen from a low camera (0.55-0.7 m, pitched
  // 30-40 deg), the step 1.0-1.5 m ahead: the ground plane can settle
  // between the two levels (hazard_random seed 74 scene 49: 1.1 cm up for a
  // 2.3 cm step), both within mean_step of it, and nothing was occupied.
  // The upper level is a region past a step from the floor's region: its
  // border with it is an obstacle line.
  int blocked = 0, frames = 0;
  for (const double step : {0.021, 0.023, 0.025})
    for (const double h : {0.55, 0.7})
      for (const double edge : {1.0, 1.5}) {
        Scene s;
        s.floor(-10, edge).floor(edge, 10, step);
        const auto cam = camera(h, h < 0.6 ? 30 : 40);
        const auto sh = perceive(s, cam, cam, kProfileNoise, walker(), 5 + frames);
        blocked += firstOccupiedAhead(sh.pipe->grid()) <= edge + 0.1;
        ++frames;
      }
  EXPECT_GE(blocked, frames - 1) << blocked << " of " << frames << " blocked";
}

TEST(StepBorders, ARampsFootIsNoStep) {
  // Gentle ramps (4-5.5 deg) whose foot lies 2.1-2.5 m ahead, seen from
  // 1.0-1.15 m with 2-3x the profile's noise and the pitch off by 2 deg (as
  // in hazard_random seeds 2-4): the floor's region and the ramp's can meet
  // at a border that lies off the kink, where their planes differ by more
  // than a step's mean_step. A step needs parallel planes and an offset
  // beyond the cells' noise and the planes' own uncertainty at the border
  // (a far ramp's plane extrapolated to it): no step line on 23 of the 24
  // frames. Known exception: the 4.2 deg ramp at 2.3 m from 1.0 m, pitch
  // +2 deg, 2.5x noise (planes 4.9 cm apart along an interleaved border of
  // 504 cell pairs, allowed about 4.6 cm): a line there, 28 % of the ramp
  // occupied. With neither the parallel test nor the planes' uncertainty, 2 frames.
  int with_steps = 0, frames = 0;
  for (const double deg : {4.2, 5.4})
    for (const double edge : {2.1, 2.3, 2.5})
      for (const double h : {1.0, 1.15})
        for (const double err : {-2.0, 2.0}) {
          Scene s;
          s.floor(-10, edge).ramp(edge, edge + 1.5, 1.5 * std::tan(deg * kDeg));
          const double noise = (2.0 + 0.5 * (frames % 3)) * kProfileNoise;
          const auto sh =
              perceive(s, camera(h, 26 + err), camera(h, 26), noise, walker(), 11 + frames);
          with_steps += sh.r.ism.step_voxels > 0;
          ++frames;
        }
  EXPECT_LE(with_steps, 1) << with_steps << " of " << frames << " frames with a step line";
}

TEST(SlopeFits, TheNearEdgeOfTheDataDoesNotTiltAShortFloor) {
  // A 6.7 deg ramp from 1.6 m seen from 1.0-1.16 m pitched 19.5-21 deg (no
  // mounting error: the floor is level in the robot frame) with 2.5 times
  // the profile's noise: the floor in view is a strip of ~0.5 m between the
  // image's lower border and the ramp's foot. The cells at that border hold
  // mostly samples the depth noise moved up and nearer (the first row 2 cm
  // high); in the floor region's slope fit they tilted it away from the
  // ramp, on these 12 frames by -0.19 deg on average (11 of 12 negative, up
  // to -0.5 deg), and rule 6 measures every slope against that fit
  // (hazard_random seed 6 scene 17: a 6.7 deg ramp read 7.4 deg and was
  // 56 % occupied). Cells within a cell plus region_trim_k depth sigmas of
  // the data's near edge are out of a region's slope fit when it differs
  // from the fit with them beyond the noise.
  double sum = 0;
  int frames = 0;
  for (const double h : {1.0, 1.16})
    for (const double pitch : {19.5, 21.0})
      for (unsigned seed = 1; seed <= 3; ++seed) {
        Scene s;
        s.floor(-10, 1.6).ramp(1.6, 3.1, 1.5 * std::tan(6.7 * kDeg));
        const auto cam = camera(h, pitch);
        const auto sh = perceive(s, cam, cam, 2.5 * kProfileNoise, walker(), seed);
        ASSERT_FALSE(std::isnan(sh.r.ism.floor_slope_x_deg)) << "h " << h << " pitch " << pitch;
        sum += sh.r.ism.floor_slope_x_deg;
        ++frames;
      }
  EXPECT_LT(std::abs(sum / frames), 0.1) << "mean floor slope ahead " << sum / frames << " deg";
}

TEST(BeyondRegions, AFarLandingSeenAtAGrazingAngleIsGround) {
  // A 5.7 deg ramp from 0.9 m to 2.4 m and its landing (15 cm up), seen
  // from a camera 0.5 m high pitched 24 deg (1.3 deg more than it is given)
  // with 1.5x the profile's noise (hazard_random seed 73 scene 72): the
  // landing 3.4-4.5 m ahead is seen at 5-8 deg, where many voxels hold one
  // or two samples. Those stayed obstacles and stopped the search from the
  // ramp's region over the landing, which kept its false obstacles behind
  // them: 76-84 % of the landing occupied on these 4 frames. Judged by the
  // same rules against the ramp's surface: 22-27 % (what keeps those
  // occupied was not looked into).
  double sum = 0;
  int frames = 0;
  for (unsigned seed = 1; seed <= 4; ++seed) {
    Scene s;
    s.floor(-10, 0.9).ramp(0.9, 2.4, 1.5 * std::tan(5.7 * kDeg));
    const auto sh =
        perceive(s, camera(0.5, 25.3), camera(0.5, 24), 1.5 * kProfileNoise, walker(), seed);
    sum += occupiedSeen(sh.pipe->grid(), 3.4, 4.5, -1.0, 1.0);
    ++frames;
  }
  EXPECT_LT(sum / frames, 0.4) << "landing occupied " << sum / frames;
}

TEST(DropEdges, ASmallGutterSeenOverOneRowOfAQuarterResolutionImageIsBlocked) {
  // Gutters 10-16 cm wide and 10-20 cm deep across the view, 1.6-2.2 m
  // ahead (separable by the noise model), seen at a quarter of the Kinect's
  // resolution from 0.7-1.1 m pitched 20-35 deg: the gutter's far wall
  // spans one image row, one lower return per column, and two lower returns
  // in one column seldom occur; side by side in one row they are as
  // unlikely from noise and mark the edge. Before: 0-5 edge columns in 6 of
  // the 16 frames, the first occupied cell past the edge in 3.
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> U(0, 1);
  for (int k = 0; k < 16; ++k) {
    const double xe = 1.6 + 0.6 * U(rng), w = 0.10 + 0.06 * U(rng), dz = 0.10 + 0.10 * U(rng);
    const double h = 0.7 + 0.4 * U(rng), pitch = 20 + 15 * U(rng);
    Scene s;
    s.floor(-10, xe).floor(xe + w, 10).box({xe, xe + w, -10, 10, -2, -dz});
    const Shot sh =
        perceive(s, camera(h, pitch), camera(h, pitch), kProfileNoise, walker(), 40 + k, 128, 106);
    EXPECT_GE(sh.r.drop_edges, 16u) << "gutter " << k;  // of 128 columns
    EXPECT_LE(firstOccupiedAhead(sh.pipe->grid()), xe + 0.025) << "gutter " << k;
  }
}

TEST(DropEdges, AFlatFloorAtAQuarterResolutionHasNoDropEdge) {
  // The same mountings over a flat floor with 1-3 times the profile's noise.
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> U(0, 1);
  size_t edges = 0;
  for (int k = 0; k < 16; ++k) {
    const double h = 0.7 + 0.4 * U(rng), pitch = 20 + 15 * U(rng), noise = 1 + 2 * U(rng);
    Scene s;
    s.floor(-10, 20);
    const Shot sh = perceive(s, camera(h, pitch), camera(h, pitch), noise * kProfileNoise, walker(),
                             60 + k, 128, 106);
    edges += sh.r.drop_edges;
    EXPECT_EQ(firstOccupiedAhead(sh.pipe->grid()), 99) << "floor " << k;
  }
  std::printf("[ floor ] %zu edge columns in 16 frames\n", edges);
  EXPECT_LE(edges, 16u);
}
