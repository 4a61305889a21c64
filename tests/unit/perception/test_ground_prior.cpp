// Choosing the ground plane with the mounting prior: trees smaller than
// min_tree_nodes are refused, the floor under the robot wins over a larger
// plateau, a floor far from the prior is found and reported; on many seeded
// random scenes and on the real office1.pcd frame.
#include "scene.h"

#include <carenav/perception/cloud.h>
#include <carenav/perception/pipeline.h>

#include <gtest/gtest.h>

#include <random>

using namespace carenav;
using namespace carenav::perception;
using namespace carenav_test;

namespace {

constexpr double kDeg = M_PI / 180;

struct Shot {
  FrameResult r;
  std::unique_ptr<Pipeline> pipe;
};

Shot perceiveScene(const Scene& s, const mrpt::poses::CPose3D& cam, unsigned seed,
                   const PerceptionParams& p = {}) {
  const Cloud c = renderDepth(s, cam, seed, 1.0, nullptr, 256, 212);
  Shot sh;
  sh.pipe = std::make_unique<Pipeline>(p, Method::RrtGpd);
  FrameInput in;
  in.cloud = &c;
  in.sensor_origin = {static_cast<float>(cam.x()), static_cast<float>(cam.y()),
                      static_cast<float>(cam.z())};
  sh.r = sh.pipe->process(in, false);
  return sh;
}

/** Occupied share (p > 0.55) of the cells with centres in [x0,x1] x [y0,y1]
 *  that the frame saw (p != 0.5). */
double occupiedSeen(const LocalOccupancy& g, double x0, double x1, double y0, double y1,
                    size_t* seen = nullptr) {
  size_t n = 0, occ = 0;
  for (int i = 0; i < g.cells(); ++i)
    for (int j = 0; j < g.cells(); ++j) {
      const double x = g.centreX(i), y = g.centreY(j);
      if (x < x0 || x > x1 || y < y0 || y > y1) continue;
      const double pr = g.prob(i, j);
      if (std::abs(pr - 0.5) < 1e-6) continue;
      ++n;
      occ += pr > 0.55 ? 1 : 0;
    }
  if (seen) *seen = n;
  return n ? static_cast<double>(occ) / n : 0.0;
}

/** Where the lowest image row of a camera at height h pitched `pitch` down
 *  meets the floor, x ahead of the robot (camera 0.2 m ahead of the axle). */
double nearEdge(double h, double pitch) { return 0.2 + h / std::tan(pitch + 30 * kDeg); }

}  // namespace

TEST(GroundPrior, TreesSmallerThanMinTreeNodesNeverGiveThePlane) {
  // Seeded random scenes with only small flat tops near the robot's floor
  // height (pedestals 8-25 cm wide over a void: a seed on them cannot grow a
  // tree) and, in half of them, a real floor. A plane must always come from a
  // tree of >= min_tree_nodes nodes supported by as many; without a floor the
  // pipeline falls back to the nominal z = 0 plane and says why.
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> U(0, 1);
  const PerceptionParams p;
  int refused_scenes = 0, nominal = 0, with_plane = 0;
  for (int k = 0; k < 40; ++k) {
    Scene s;
    const bool floor = k % 2 == 1;
    if (floor) s.floor(-10, 10);
    const int n_ped = 3 + static_cast<int>(U(rng) * 6);
    for (int q = 0; q < n_ped; ++q) {
      const double w = 0.08 + 0.17 * U(rng), x = 1.0 + 2.5 * U(rng), y = -1.2 + 2.4 * U(rng);
      const double top = -0.1 + 0.2 * U(rng) + (floor ? 0.25 : 0.0);
      s.box({x, x + w, y, y + w, -2, top});
    }
    const double h = 0.5 + 0.7 * U(rng), pitch = (15 + 30 * U(rng)) * kDeg,
                 roll = (-5 + 10 * U(rng)) * kDeg;
    const auto sh = perceiveScene(s, mrpt::poses::CPose3D(0.2, 0, h, 0, pitch, roll), 100 + k);
    const auto& g = sh.r.ground;
    refused_scenes += g.trees_refused > 0 ? 1 : 0;
    if (g.plane) {
      ++with_plane;
      EXPECT_GE(static_cast<int>(g.nodes.size()), p.min_tree_nodes) << "scene " << k;
      EXPECT_GE(static_cast<int>(g.ransac_inliers), p.min_tree_nodes) << "scene " << k;
      EXPECT_EQ(sh.r.plane_source, "rrt-gpd");
    } else {
      ++nominal;
      ASSERT_TRUE(sh.r.plane) << "scene " << k;
      EXPECT_EQ(sh.r.plane_source, "nominal");
      EXPECT_NEAR(sh.r.plane->c, 1.0, 1e-12);
      EXPECT_NEAR(sh.r.plane->d, 0.0, 1e-12);
      EXPECT_FALSE(sh.r.plane_note.empty());
    }
    if (floor) {  // the real floor is found, the pedestals (>= 15 cm) are obstacles
      ASSERT_TRUE(g.plane) << "scene " << k;
      EXPECT_LT(std::abs(*g.plane->zAt(0, 0)), 0.03) << "scene " << k;
      EXPECT_GT(g.plane->c, std::cos(3 * kDeg)) << "scene " << k;
    }
  }
  EXPECT_GE(refused_scenes, 10);  // the refusal was exercised
  EXPECT_GE(nominal, 10);
  EXPECT_GE(with_plane, 20);
}

TEST(GroundPrior, APlateauLargerThanTheFloorPatchNeverBecomesTheGround) {
  // The robot stands on the floor; 0.5-1.0 m of it are in view, then a 4-6 cm
  // high flat plateau 2-4 m deep fills the rest. The plane must be the floor
  // (within 2 cm at the robot) and the visible floor patch must stay free.
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> U(0, 1);
  int plateau_planes = 0, blocked_patches = 0;
  const int n = 30;
  for (int k = 0; k < n; ++k) {
    const double h = 0.5 + 0.7 * U(rng), pitch = (15 + 30 * U(rng)) * kDeg,
                 roll = (-5 + 10 * U(rng)) * kDeg;
    const double x_near = nearEdge(h, pitch);
    const double x0 = x_near + 0.5 + 0.5 * U(rng), depth = 2 + 2 * U(rng);
    const double rise = 0.04 + 0.02 * U(rng), w = 1.5 + 2.5 * U(rng), yc = -0.3 + 0.6 * U(rng);
    Scene s;
    s.floor(-10, 10).box({x0, x0 + depth, yc - w / 2, yc + w / 2, -1, rise});
    const auto sh = perceiveScene(s, mrpt::poses::CPose3D(0.2, 0, h, 0, pitch, roll), 300 + k);
    ASSERT_TRUE(sh.r.plane);
    const double z0 = *sh.r.plane->zAt(0, 0);
    // 0.2 m before the step: an obstacle voxel's Gaussian (sigma2) reaches ~0.14 m toward the
    // robot.
    const double occ = occupiedSeen(sh.pipe->grid(), x_near + 0.1, x0 - 0.2, -0.25, 0.25);
    plateau_planes += std::abs(z0) > 0.02 ? 1 : 0;
    blocked_patches += occ >= 0.1 ? 1 : 0;
    EXPECT_LT(std::abs(z0), 0.02) << "scene " << k << ": h " << h << " pitch " << pitch / kDeg
                                  << " plateau at " << x0 << " rise " << rise;
    EXPECT_LT(occ, 0.1) << "scene " << k << ": floor patch " << x_near << ".." << x0;
    // The plateau's front edge is an obstacle (a 4-6 cm step).
    EXPECT_GT(occupiedSeen(sh.pipe->grid(), x0 - 0.05, x0 + 0.3, yc - w / 4, yc + w / 4), 0.2)
        << "scene " << k;
  }
  std::printf(
      "[ plateau ] %d of %d scenes with the plane on the plateau, %d with the floor patch "
      "blocked\n",
      plateau_planes, n, blocked_patches);
}

TEST(GroundPrior, AFloorFarFromThePriorIsFoundAndReported) {
  // The sensor pose is off by 0.35-0.6 m (or the robot's own floor is out of
  // view): the only large level surface lies beyond seed_max_elevation, with
  // small flat tops at the prior height. The floor is found (second seed
  // pass), stays mostly free, and the offset is reported.
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> U(0, 1);
  for (int k = 0; k < 20; ++k) {
    const double off = -(0.35 + 0.25 * U(rng));
    const double h = 0.6 + 0.6 * U(rng), pitch = (15 + 25 * U(rng)) * kDeg;
    Scene s;
    s.floor(-10, 10, off);
    for (int q = 0; q < 3; ++q) {
      const double w = 0.15 + 0.15 * U(rng), x = 1.0 + 2.5 * U(rng),
                   y = (q % 2 ? 0.6 : -0.6 - w) +
                       (q % 2 ? 1 : -1) * 0.6 * U(rng);  // beside the lane
      s.box({x, x + w, y, y + w, off, -0.02 + 0.04 * U(rng)});
    }
    const auto sh = perceiveScene(s, mrpt::poses::CPose3D(0.2, 0, h, 0, pitch, 0), 500 + k);
    const auto& g = sh.r.ground;
    ASSERT_TRUE(g.plane) << "scene " << k;
    EXPECT_NEAR(*g.plane->zAt(0, 0), off, 0.03) << "scene " << k;
    EXPECT_NEAR(g.prior_offset, off, 0.03);
    EXPECT_TRUE(g.wide_search);
    EXPECT_NE(sh.r.plane_note.find("check the sensor pose"), std::string::npos) << sh.r.plane_note;
    // Open floor away from the boxes, in view: mostly free.
    size_t seen = 0;
    const double x_near = nearEdge(h - off, pitch);
    const double occ = occupiedSeen(sh.pipe->grid(), x_near + 0.2, x_near + 1.5, -0.4, 0.4, &seen);
    EXPECT_GT(seen, 20u) << "scene " << k << " h " << h << " off " << off << " pitch "
                         << pitch / kDeg << " near " << x_near << " counts " << sh.r.counts.free
                         << " " << sh.r.counts.occupied << " valid " << sh.r.points_valid;
    EXPECT_LT(occ, 0.05) << "scene " << k;
  }
}

TEST(GroundPrior, Office1WithTheSensorPoseOffByFortyCentimetresKeepsTheFloorFree) {
  // office1.pcd: Kinect level 1.4 m above the floor. With the pose given as
  // 1.0 m the floor lies 0.4 m below the robot's z = 0; the objects' tops near
  // z = 0 gave a 2-node tree tilted 27.9 deg and 98.9% of the floor occupied.
  // Floor cells: those whose voxels are ground with the right pose (1.4 m).
  const Cloud cam = readPcd(std::string(CARENAV_TEST_DATA) + "/pcd/office1.pcd");
  auto run = [&](double h) {
    const mrpt::poses::CPose3D pose(0, 0, h, 0, 0, 0);
    auto robot = std::make_shared<Cloud>(toRobotFrame(cam, pose, true));
    Shot sh;
    sh.pipe = std::make_unique<Pipeline>(PerceptionParams{}, Method::RrtGpd);
    FrameInput in;
    in.cloud = robot.get();
    in.sensor_origin = {0, 0, static_cast<float>(h)};
    sh.r = sh.pipe->process(in, false);
    return sh;
  };
  const Shot ref = run(1.4), off = run(1.0);
  // Floor cells: ground voxels with the right pose whose cell the right pose
  // also leaves free (the Gaussian of nearby obstacles is not the floor's fault).
  ASSERT_TRUE(ref.r.ground.plane);
  ASSERT_TRUE(off.r.ground.plane);
  EXPECT_GE(static_cast<int>(off.r.ground.nodes.size()), PerceptionParams{}.min_tree_nodes);
  EXPECT_LT(std::acos(off.r.ground.plane->c) / kDeg, 6.0);
  // The floor is seen 3-5 m ahead: the plane is 0.4 m down there; its height
  // at the robot (the reported offset) carries the extrapolated tilt.
  EXPECT_NEAR(*off.r.ground.plane->zAt(4, 0), -0.4, 0.05);
  EXPECT_LT(off.r.ground.prior_offset, -0.2);
  EXPECT_TRUE(off.r.ground.wide_search);
  EXPECT_FALSE(off.r.plane_note.empty());
  const auto& e = ref.pipe->elevation();
  const auto& g = off.pipe->grid();
  size_t floor_cells = 0, occupied = 0;
  for (int i = 0; i < g.cells(); ++i)
    for (int j = 0; j < g.cells(); ++j) {
      const int ei = e.cellOf(g.centreX(i)), ej = e.cellOf(g.centreY(j));
      if (!e.inside(ei, ej)) continue;
      if (ref.r.voxel_classes[static_cast<size_t>(ei) * e.cells() + ej] != VoxelClass::Ground ||
          ref.pipe->grid().prob(i, j) >= 0.45)
        continue;
      ++floor_cells;
      occupied += g.prob(i, j) > 0.55 ? 1 : 0;
    }
  ASSERT_GT(floor_cells, 300u);
  const double share = static_cast<double>(occupied) / floor_cells;
  std::printf("[ office1 ] pose 1.0 m: %zu of %zu floor cells occupied (%.1f%%), tilt %.2f deg\n",
              occupied, floor_cells, 100 * share, std::acos(off.r.ground.plane->c) / kDeg);
  EXPECT_LT(share, 0.3);  // 19.6% measured (the RRT plane of this far floor varies by ~0.5 deg)
}
