// Ray casting: lidar ranges match the room geometry to the cell size; depth
// frames see steps, drops, table tops and people where they are.
#include <carenav/io/map_io.h>
#include <carenav/sim/raycast.h>
#include <carenav/sim/simulator.h>

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/poses/CPose3D.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace carenav;
using namespace carenav::sim;

namespace {
const std::string kWorlds = std::string(CARENAV_SOURCE_DIR) + "/maps/worlds";

/** Distance from (x, y) inside the box [lo, hi]^2 to its border along angle a. */
double boxRange(double x, double y, double a, double lo, double hi) {
  const double dx = std::cos(a), dy = std::sin(a);
  double t = 1e300;
  if (dx > 1e-12) t = std::min(t, (hi - x) / dx);
  if (dx < -1e-12) t = std::min(t, (lo - x) / dx);
  if (dy > 1e-12) t = std::min(t, (hi - y) / dy);
  if (dy < -1e-12) t = std::min(t, (lo - y) / dy);
  return t;
}

/** A free square grid with features (no walls). */
World openWorld(std::vector<Feature> features, std::vector<Person> people = {}) {
  auto g = io::makeGrid(0, 0, 0.05, 200, 200, 1.0f);
  return World(std::move(g), std::move(features), std::move(people), 2.5);
}
}  // namespace

TEST(SimRaycast, LidarRangesMatchTheRoomToTheCellSize) {
  const World w = loadWorld(kWorlds + "/empty_room.yaml");
  // walls are the 2 outer pixel rows: inner faces at 0.1 m and 19.9 m
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pos(1.0, 19.0), ang(-M_PI, M_PI);
  double worst = 0;
  for (int i = 0; i < 2000; ++i) {
    const double x = pos(rng), y = pos(rng), a = ang(rng);
    const double r = castRay2D(w, {}, x, y, 0.3, a, 40);
    ASSERT_NE(r, kNoHit);
    worst = std::max(worst, std::abs(r - boxRange(x, y, a, 0.1, 19.9)));
  }
  EXPECT_LT(worst, 0.05);
  // beyond the range: no hit
  EXPECT_EQ(castRay2D(w, {}, 10, 10, 0.3, 0, 5.0), kNoHit);
}

TEST(SimRaycast, LidarSeesPeopleAndTallFeaturesOnly) {
  Feature low;  // a 0.1 m step: under a lidar at 0.3 m
  low.kind = Feature::Kind::Step;
  low.height = 0.1;
  low.polygon = {{3, 0}, {4, 0}, {4, 10}, {3, 10}};
  Feature tall = low;  // a 0.5 m block
  tall.height = 0.5;
  tall.polygon = {{6, 0}, {7, 0}, {7, 10}, {6, 10}};
  Person p;
  p.path = {{2.0, 7.0}};
  p.radius = 0.3;
  const World w = openWorld({low, tall}, {p});
  EXPECT_NEAR(castRay2D(w, peopleAt(w, 0), 1, 5, 0.3, 0, 20), 5.0, 1e-6);   // the tall block
  EXPECT_NEAR(castRay2D(w, peopleAt(w, 0), 1, 5, 0.05, 0, 20), 2.0, 1e-6);  // the low step
  EXPECT_NEAR(castRay2D(w, peopleAt(w, 0), 1, 7, 0.3, 0, 20), 0.7, 1e-6);   // the person
  EXPECT_EQ(castRay2D(w, peopleAt(w, 0), 1, 7, 1.9, 0, 20), kNoHit);        // over everything
}

TEST(SimRaycast, DepthRaysHitFloorStepsWallsAndTables) {
  const World w = loadWorld(kWorlds + "/apartment.yaml");
  const auto none = std::vector<PersonNow>{};
  // straight down on plain floor, on the table top, into the gutter
  {
    const double o[3] = {1.0, 1.0, 1.5}, d[3] = {0, 0, -1};
    EXPECT_NEAR(castRay3D(w, none, o, d, 10), 1.5, 1e-6);
  }
  {
    const double o[3] = {2.8, 5.45, 1.5}, d[3] = {0, 0, -1};
    EXPECT_NEAR(castRay3D(w, none, o, d, 10), 0.75, 1e-6);
  }
  {
    const double o[3] = {4.9, 1.0, 1.0}, d[3] = {0, 0, -1};
    EXPECT_NEAR(castRay3D(w, none, o, d, 10), 1.10, 1e-6);
  }
  // horizontal at the table top's height: its edge at x = 2.0
  {
    const double o[3] = {1.0, 5.45, 0.73}, d[3] = {1, 0, 0};
    EXPECT_NEAR(castRay3D(w, none, o, d, 10), 1.0, 0.05 + 1e-6);
  }
  // under the table (between the legs) to the wall at x = 7 - 0.05
  {
    const double o[3] = {1.0, 5.45, 0.3}, d[3] = {1, 0, 0};
    EXPECT_NEAR(castRay3D(w, none, o, d, 10), 5.95, 0.05 + 1e-6);
  }
  // over the wall: nothing inside the range (no ceiling)
  {
    const double o[3] = {1.0, 5.45, 2.6}, d[3] = {1, 0, 0};
    EXPECT_EQ(castRay3D(w, none, o, d, 30), kNoHit);
  }
}

TEST(SimRaycast, DepthFrameOfADownwardStairShowsTheDrop) {
  Feature stairs;
  stairs.kind = Feature::Kind::Stairs;
  stairs.polygon = {{5, 0}, {7, 0}, {7, 10}, {5, 10}};
  stairs.axis = {1, 0};
  stairs.steps = 4;
  stairs.rise = -0.2;  // treads at -0.2, -0.4, -0.6, -0.8
  auto world = std::make_shared<World>(openWorld({stairs}));
  auto flat = std::make_shared<World>(openWorld({}));
  SensorParams cam;
  cam.label = "cam";
  cam.type = "depth-camera";
  cam.z = 1.0;
  cam.pitch = 30;
  cam.width = 80;
  cam.height = 60;
  cam.fov = 60;
  cam.vfov = 45;
  cam.range_min = 0.3;
  cam.range_max = 8;
  cam.noise_std = 0;
  SimParams sp;
  sp.depth_invalid_rate = 0;
  Simulator sim(world, RobotParams{}, {cam}, sp), ref(flat, RobotParams{}, {cam}, sp);
  sim.reset({3.5, 5, 0});
  ref.reset({3.5, 5, 0});
  auto obs = std::dynamic_pointer_cast<mrpt::obs::CObservation3DRangeScan>(sim.observe(0));
  auto obs0 = std::dynamic_pointer_cast<mrpt::obs::CObservation3DRangeScan>(ref.observe(0));
  ASSERT_TRUE(obs && obs0);
  ASSERT_EQ(obs->rangeImage.cols(), 80);
  ASSERT_EQ(obs->rangeImage.rows(), 60);
  const auto& K = obs->cameraParams;
  const mrpt::poses::CPose3D cam_pose = mrpt::poses::CPose3D(3.5, 5, 0, 0, 0, 0) + obs->sensorPose;
  int on_treads = 0, deeper = 0, matched = 0, checked = 0;
  double lowest = 0;
  for (int r = 0; r < 60; ++r)
    for (int c = 0; c < 80; ++c) {
      const double z = obs->rangeImage(r, c) * obs->rangeUnits;
      const double z0 = obs0->rangeImage(r, c) * obs0->rangeUnits;
      if (z <= 0) continue;
      // unproject as MRPT does (range_is_depth): x forward, y left, z up
      const double lx = z, ly = (K.cx() - c) * z / K.fx(), lz = (K.cy() - r) * z / K.fy();
      const auto p = cam_pose.composePoint(mrpt::math::TPoint3D(lx, ly, lz));
      lowest = std::min(lowest, p.z);
      if (p.x > 5.05 && p.x < 6.95) {
        ++on_treads;
        if (z0 > 0 && z > z0 + 0.05) ++deeper;
      }
      // the point lies on the floor of its cell (away from tread edges, where
      // a ray may hit the riser)
      const double u = std::fmod(p.x - 5.0, 0.5);
      if (p.x < 4.9 || (p.x > 5.05 && p.x < 6.95 && u > 0.05 && u < 0.45)) {
        ++checked;
        if (std::abs(p.z - world->floorAt(p.x, p.y)) < 0.01) ++matched;
      }
    }
  EXPECT_GT(on_treads, 200);
  EXPECT_EQ(deeper, on_treads);  // everything on the stairs is farther than a flat floor
  EXPECT_LT(lowest, -0.55);      // the lower treads are in view
  EXPECT_GT(checked, 1000);
  EXPECT_GE(matched, checked * 99 / 100);
}

TEST(SimRaycast, DepthSeesAPersonAsACylinder) {
  Person p;
  p.path = {{5.0, 5.0}};
  p.radius = 0.3;
  p.height = 1.7;
  const World w = openWorld({}, {p});
  const auto people = peopleAt(w, 0);
  const double o[3] = {2.0, 5.0, 1.0}, d[3] = {1, 0, 0};
  EXPECT_NEAR(castRay3D(w, people, o, d, 10), 2.7, 1e-9);
  const double o2[3] = {5.0, 5.0, 3.0}, d2[3] = {0.01, 0, -1};
  EXPECT_NEAR(castRay3D(w, people, o2, d2, 10), 1.3, 1e-9);  // the top of the head
}
