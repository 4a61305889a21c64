// Perception: readers, RRT-GPD, ISM and the safety claims on analytic scenes.
#include "scene.h"

#include <carenav/common/errors.h>
#include <carenav/common/profile.h>
#include <carenav/perception/pipeline.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

using namespace carenav;
using namespace carenav::perception;
using namespace carenav_test;
namespace fs = std::filesystem;

namespace {

fs::path tmpDir() {
  auto d = fs::temp_directory_path() / ("carenav_perc_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

void writeText(const fs::path& p, const std::string& s) {
  std::ofstream f(p, std::ios::binary);
  f << s;
}

/** Expects an InputError whose message names the file and contains `what`. */
template <class F>
void expectInputError(F&& f, const std::string& file, const std::string& what) {
  try {
    f();
    ADD_FAILURE() << "no InputError for " << file;
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(file), std::string::npos) << m;
    EXPECT_NE(m.find(what), std::string::npos) << m;
  }
}

struct Run {
  FrameResult r;
  std::unique_ptr<Pipeline> pipe;
};

Run perceive(const Cloud& c, Method m, const PerceptionParams& p = {}) {
  Run run;
  run.pipe = std::make_unique<Pipeline>(p, m);
  FrameInput in;
  in.cloud = &c;
  in.sensor_origin = {0.2f, 0.f, 0.9f};
  run.r = run.pipe->process(in, false);
  return run;
}

/** Share of the cells whose centres lie in [x0,x1] x [y0,y1] that are occupied. */
double occupiedShare(const LocalOccupancy& g, double x0, double x1, double y0, double y1,
                     double thr = 0.55) {
  size_t n = 0, occ = 0;
  for (int i = 0; i < g.cells(); ++i)
    for (int j = 0; j < g.cells(); ++j) {
      const double x = g.centreX(i), y = g.centreY(j);
      if (x < x0 || x > x1 || y < y0 || y > y1) continue;
      ++n;
      occ += g.prob(i, j) > thr ? 1 : 0;
    }
  return n ? static_cast<double>(occ) / n : 0.0;
}

double freeShare(const LocalOccupancy& g, double x0, double x1, double y0, double y1) {
  size_t n = 0, fr = 0;
  for (int i = 0; i < g.cells(); ++i)
    for (int j = 0; j < g.cells(); ++j) {
      const double x = g.centreX(i), y = g.centreY(j);
      if (x < x0 || x > x1 || y < y0 || y > y1) continue;
      ++n;
      fr += g.prob(i, j) < 0.45 ? 1 : 0;
    }
  return n ? static_cast<double>(fr) / n : 0.0;
}

}  // namespace

// ------------------------------------------------------------------ readers

TEST(PerceptionIo, PcdAndPlyRoundTripAllEncodings) {
  const auto d = tmpDir();
  Cloud c;
  c.width = 3;
  c.height = 2;
  c.points = {{1, 2, 3}, {-1.5f, 0.25f, 4}, {0, 0, 0}, {7, 8, 9}, {0.125f, -2, 1}, {5, 5, 5}};
  for (auto enc : {PcdEncoding::Ascii, PcdEncoding::Binary}) {
    const auto f = (d / "rt.pcd").string();
    writePcd(f, c, enc);
    const Cloud r = readPcd(f);
    ASSERT_EQ(r.points.size(), 6u);
    EXPECT_EQ(r.width, 3u);
    EXPECT_EQ(r.height, 2u);
    EXPECT_FLOAT_EQ(r.points[1].x, -1.5f);
    EXPECT_FLOAT_EQ(r.points[4].y, -2.f);
    EXPECT_EQ(r.validCount(), 5u);  // (0,0,0) is a zero depth
  }
  for (auto enc : {PlyEncoding::Ascii, PlyEncoding::BinaryLittleEndian}) {
    const auto f = (d / "rt.ply").string();
    writePly(f, c, enc);
    const Cloud r = readCloudFile(f);
    ASSERT_EQ(r.points.size(), 6u);
    EXPECT_FLOAT_EQ(r.points[4].x, 0.125f);
    EXPECT_FLOAT_EQ(r.points[3].z, 9.f);
  }
}

TEST(PerceptionIo, ReadsTheBinaryCompressedKinectFrame) {
  const std::string f = std::string(CARENAV_TEST_DATA) + "/pcd/office1.pcd";
  const Cloud c = readPcd(f);
  EXPECT_EQ(c.width, 640u);
  EXPECT_EQ(c.height, 480u);
  ASSERT_EQ(c.points.size(), 307200u);
  EXPECT_TRUE(c.organised());
  const size_t valid = c.validCount();
  EXPECT_GT(valid, 200000u);
  EXPECT_LT(valid, 307200u);  // Kinect holes are NaN
  // Every valid point is in front of the camera, within the Kinect's range.
  for (const auto& p : c.points)
    if (validPoint(p)) {
      ASSERT_GT(p.z, 0.3f);
      ASSERT_LT(p.z, 12.f);
    }
}

TEST(PerceptionIo, MalformedFilesAreInputErrorsNamingFileAndProblem) {
  const auto d = tmpDir();
  const std::string hdr =
      "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 4\nHEIGHT 1\n";
  const auto empty = (d / "empty.pcd").string();
  writeText(empty, "");
  expectInputError([&] { readPcd(empty); }, empty, "empty");
  const auto trunc = (d / "trunc.pcd").string();
  writeText(trunc, hdr + "POINTS 4\nDATA binary\n" + std::string(20, '\0'));
  expectInputError([&] { readPcd(trunc); }, trunc, "truncated");
  const auto trunc_a = (d / "trunc_ascii.pcd").string();
  writeText(trunc_a, hdr + "POINTS 4\nDATA ascii\n1 2 3\n4 5 6\n");
  expectInputError([&] { readPcd(trunc_a); }, trunc_a, "truncated");
  const auto count = (d / "count.pcd").string();
  writeText(count, hdr + "POINTS 5\nDATA ascii\n1 2 3\n4 5 6\n1 1 1\n2 2 2\n3 3 3\n");
  expectInputError([&] { readPcd(count); }, count, "POINTS 5");
  const auto bad = (d / "bad.pcd").string();
  writeText(bad, "VERSION 0.7\nFIELDS x y z\nSIZE 4 4\nTYPE F F F\nWIDTH 1\nDATA ascii\n1 2 3\n");
  expectInputError([&] { readPcd(bad); }, bad, "different lengths");
  const auto nodata = (d / "nodata.pcd").string();
  writeText(nodata, hdr);
  expectInputError([&] { readPcd(nodata); }, nodata, "DATA");
  const auto word = (d / "word.pcd").string();
  writeText(word, hdr + "POINTS 4\nDATA ascii\n1 2 3\n4 x 6\n1 1 1\n2 2 2\n");
  expectInputError([&] { readPcd(word); }, word, "not a number");
  const auto ply = (d / "trunc.ply").string();
  writeText(ply,
            "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
            "property float y\nproperty float z\nend_header\n" +
                std::string(30, '\0'));
  expectInputError([&] { readPly(ply); }, ply, "truncated");
  const auto ply2 = (d / "nohdr.ply").string();
  writeText(ply2, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n");
  expectInputError([&] { readPly(ply2); }, ply2, "end_header");
  const auto ply3 = (d / "noxyz.ply").string();
  writeText(ply3, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n");
  expectInputError([&] { readPly(ply3); }, ply3, "x, y and z");
  const auto ext = (d / "cloud.xyz").string();
  writeText(ext, "1 2 3\n");
  expectInputError([&] { readCloudFile(ext); }, ext, "format");
}

// ------------------------------------------------------------------ planes

TEST(PerceptionPlane, FitAndRansacRecoverAPlaneWithOutliers) {
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j) pts.emplace_back(i * 0.1, j * 0.1, 0.1 * i * 0.1 + 0.5);
  for (int k = 0; k < 100; ++k) pts.emplace_back(k * 0.02, 1.0, 3.0 + k * 0.01);  // outliers
  std::mt19937 rng(3);
  const auto r = ransacPlane(pts, 200, 0.01, rng);
  ASSERT_TRUE(r.plane);
  EXPECT_EQ(r.inliers, 400u);
  const Eigen::Vector3d n_true = Eigen::Vector3d(-0.1, 0, 1).normalized();
  EXPECT_GT(r.plane->normal().dot(n_true), 0.9999);
  EXPECT_NEAR(*r.plane->zAt(1.0, 1.0), 0.6, 1e-6);
  std::vector<Eigen::Vector3d> line = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}};
  EXPECT_FALSE(fitPlane(line));  // collinear
}

// ------------------------------------------------------------------ safety claims

TEST(PerceptionScene, FlatFloorIsFoundAndStaysFree) {
  Scene s;
  s.floor(-10, 10);
  const Cloud c = renderDepth(s, walkerKinect());
  const auto run = perceive(c, Method::RrtGpd);
  ASSERT_TRUE(run.r.plane);
  EXPECT_EQ(run.r.plane_source, "rrt-gpd");
  // Normal within 1 deg of vertical, floor within 1 cm of z = 0.
  EXPECT_GT(run.r.plane->c, std::cos(1.0 * M_PI / 180));
  EXPECT_NEAR(run.r.plane->d, 0.0, 0.01);
  EXPECT_GT(run.r.ground.nodes.size(), 50u);
  EXPECT_EQ(run.r.counts.occupied, 0u);
  EXPECT_GT(run.r.counts.free, 1000u);
  EXPECT_GT(freeShare(run.pipe->grid(), 1.0, 3.0, -0.3, 0.3), 0.95);
}

TEST(PerceptionScene, TiltedSensorPoseErrorIsAbsorbedByThePlane) {
  // The camera is really pitched 33 deg; the robot believes 30 deg: the floor
  // appears tilted by 3 deg in the robot frame and RRT-GPD must follow it.
  Scene s;
  s.floor(-10, 10);
  const auto truth = mrpt::poses::CPose3D(0.2, 0, 0.9, 0, 33 * M_PI / 180, 0);
  Cloud cam;
  renderDepth(s, truth, 7, 1.0, &cam);
  const Cloud c = toRobotFrame(cam, walkerKinect(), true);
  const auto run = perceive(c, Method::RrtGpd);
  ASSERT_TRUE(run.r.plane);
  const double tilt = std::acos(run.r.plane->c) * 180 / M_PI;
  EXPECT_NEAR(tilt, 3.0, 1.0);
  EXPECT_EQ(run.r.counts.occupied, 0u);
}

TEST(PerceptionScene, DownwardStairIsAnObstacleAndHeightBandMissesIt) {
  Scene s;
  s.floor(-10, 1.0).floor(1.0, 10, -0.17);  // a step down 1 m ahead of the axle
  const Cloud c = renderDepth(s, walkerKinect());
  const auto rrt = perceive(c, Method::RrtGpd);
  ASSERT_TRUE(rrt.r.plane);
  EXPECT_NEAR(rrt.r.plane->d, 0.0, 0.02);  // the upper floor, not the lower one
  // The lower floor is seen from about 1.2 m (occlusion behind the edge).
  EXPECT_GT(occupiedShare(rrt.pipe->grid(), 1.35, 2.5, -0.3, 0.3), 0.95);
  EXPECT_GT(freeShare(rrt.pipe->grid(), 0.75, 0.95, -0.3, 0.3), 0.9);
  const auto band = perceive(c, Method::HeightBand);
  EXPECT_EQ(occupiedShare(band.pipe->grid(), 1.35, 2.5, -0.3, 0.3), 0.0);
  EXPECT_GT(freeShare(band.pipe->grid(), 1.35, 2.5, -0.3, 0.3), 0.9);  // drives off the stair
}

TEST(PerceptionScene, GutterIsAnObstacleAndHeightBandMissesIt) {
  Scene s;
  s.floor(-10, 1.5).floor(1.6, 10).floor(1.5, 1.6, -0.1);  // 0.1 m wide, 0.1 m deep
  const Cloud c = renderDepth(s, walkerKinect());
  const auto rrt = perceive(c, Method::RrtGpd);
  ASSERT_TRUE(rrt.r.plane);
  const auto& g = rrt.pipe->grid();
  // Every lateral cell column across the path has an occupied cell at the gutter.
  int cols = 0, blocked = 0;
  for (int j = g.cellY(-0.3); j <= g.cellY(0.3); ++j) {
    ++cols;
    bool occ = false;
    for (int i = g.cellX(1.45); i <= g.cellX(1.7); ++i) occ = occ || g.prob(i, j) > 0.55;
    blocked += occ ? 1 : 0;
  }
  EXPECT_EQ(blocked, cols);
  EXPECT_GT(freeShare(g, 0.7, 1.3, -0.3, 0.3), 0.9);  // the floor before it stays free
  const auto band = perceive(c, Method::HeightBand);
  EXPECT_EQ(occupiedShare(band.pipe->grid(), 1.4, 1.75, -0.3, 0.3), 0.0);
}

TEST(PerceptionScene, TableTopLegsAndWallAreObstacles) {
  Scene s;
  s.floor(-10, 10)
      .box({1.5, 2.1, -0.4, 0.4, 0.72, 0.75})  // table top at 0.75 m
      .box({1.5, 1.54, -0.4, -0.36, 0, 0.72})  // thin legs
      .box({1.5, 1.54, 0.36, 0.4, 0, 0.72})
      .box({3.0, 3.2, -10, 10, 0, 2.5});  // wall
  const Cloud c = renderDepth(s, walkerKinect());
  const auto rrt = perceive(c, Method::RrtGpd);
  ASSERT_TRUE(rrt.r.plane);
  EXPECT_NEAR(rrt.r.plane->d, 0.0, 0.02);
  EXPECT_GT(occupiedShare(rrt.pipe->grid(), 1.55, 1.65, -0.3, 0.3), 0.9);   // table edge
  EXPECT_GT(occupiedShare(rrt.pipe->grid(), 1.5, 1.55, -0.4, -0.35), 0.9);  // a leg
  EXPECT_GT(occupiedShare(rrt.pipe->grid(), 3.0, 3.05, -0.5, 0.5), 0.9);    // wall face
  EXPECT_GT(freeShare(rrt.pipe->grid(), 0.7, 1.3, -0.3, 0.3), 0.9);
}

TEST(PerceptionScene, RansacOnlyBaselineLocksOntoAWallThatDominatesTheView) {
  Scene s;
  s.floor(-10, 10).box({1.6, 1.8, -10, 10, 0, 3});  // a wall close ahead fills the view
  const Cloud c = renderDepth(s, walkerKinect());
  const auto rrt = perceive(c, Method::RrtGpd);
  ASSERT_TRUE(rrt.r.plane);
  EXPECT_GT(rrt.r.plane->c, 0.999);
  const auto ran = perceive(c, Method::Ransac);
  ASSERT_TRUE(ran.r.plane);
  EXPECT_LT(ran.r.plane->c, 0.1);  // the wall: the whole floor becomes "obstacle"
}

TEST(PerceptionScene, SameSeedSameOutputDifferentSeedStillFindsFloor) {
  Scene s;
  s.floor(-10, 1.0).floor(1.0, 10, -0.17);
  const Cloud c = renderDepth(s, walkerKinect());
  const auto a = perceive(c, Method::RrtGpd), b = perceive(c, Method::RrtGpd);
  ASSERT_TRUE(a.r.plane && b.r.plane);
  EXPECT_EQ(a.r.plane->a, b.r.plane->a);
  EXPECT_EQ(a.r.plane->d, b.r.plane->d);
  ASSERT_EQ(a.r.ground.nodes.size(), b.r.ground.nodes.size());
  for (size_t k = 0; k < a.r.ground.nodes.size(); ++k)
    EXPECT_EQ(a.r.ground.nodes[k].p, b.r.ground.nodes[k].p);
  const auto& ga = a.pipe->grid();
  const auto& gb = b.pipe->grid();
  for (int i = 0; i < ga.cells(); ++i)
    for (int j = 0; j < ga.cells(); ++j) ASSERT_EQ(ga.prob(i, j), gb.prob(i, j));
  PerceptionParams p;
  p.seed = 12345;
  const auto c2 = perceive(c, Method::RrtGpd, p);
  ASSERT_TRUE(c2.r.plane);
  EXPECT_NE(c2.r.ground.nodes.size() == a.r.ground.nodes.size() &&
                c2.r.ground.nodes.back().p == a.r.ground.nodes.back().p,
            true);
  EXPECT_NEAR(c2.r.plane->d, 0.0, 0.02);
}

// ------------------------------------------------- noise-aware voxel rules
// Depth noise of ini/isr-aiwalker.ini's Kinect: 5 mm at 1 m, growing with the
// square of the depth (4.5 cm at 3 m), as the simulator renders it.
constexpr double kProfileNoise = 0.005;

Cloud noisyFrame(const Scene& s, unsigned seed = 7) {
  return renderDepth(s, walkerKinect(), seed, 1.0, nullptr, 512, 424, kProfileNoise);
}

PerceptionParams noiseAware() {
  PerceptionParams p;
  p.depth_noise_std = kProfileNoise;  // what the profile sets
  return p;
}

TEST(PerceptionNoise, NoisyFlatFloorStaysFreeToFourMetres) {
  Scene s;
  s.floor(-10, 10);
  for (unsigned seed : {7u, 8u}) {
    const Cloud c = noisyFrame(s, seed);
    const auto run = perceive(c, Method::RrtGpd, noiseAware());
    ASSERT_TRUE(run.r.plane);
    const auto& g = run.pipe->grid();
    // The floor in view (0.7 m to the 4.5 m depth limit, ~4 m ahead) stays
    // free: no occupied cell, and almost every cell free out to 3.5 m.
    EXPECT_EQ(occupiedShare(g, 0.7, 4.2, -1.5, 1.5), 0.0) << "seed " << seed;
    EXPECT_GT(freeShare(g, 0.8, 3.5, -0.5, 0.5), 0.95) << "seed " << seed;
  }
  // Without the noise model ([Garrote17]'s fixed d_pth = 3 cm) the same frame puts
  // obstacles on the far floor: this is what the noise model fixes.
  const auto fixed = perceive(noisyFrame(s), Method::RrtGpd);
  EXPECT_GT(occupiedShare(fixed.pipe->grid(), 2.0, 3.5, -0.5, 0.5), 0.2);
}

TEST(PerceptionNoise, StairOutletAndGutterStayObstaclesUnderNoise) {
  Scene s;
  // An outlet 10 x 10 cm, 4 cm deep, 1.3 m ahead; a gutter 15 cm wide, 10 cm
  // deep, 1.9 m ahead; a stair down 2.6 m ahead (robot frame).
  s.floor(-10, 1.3).floor(1.4, 1.9).floor(2.05, 2.6).floor(2.6, 10, -0.17);
  s.box({1.3, 1.4, -10, -0.05, -2, 0}).box({1.3, 1.4, 0.05, 10, -2, 0});
  s.box({1.3, 1.4, -0.05, 0.05, -2, -0.04});  // outlet bottom
  s.floor(1.9, 2.05, -0.1);                   // gutter bottom
  const auto run = perceive(noisyFrame(s), Method::RrtGpd, noiseAware());
  ASSERT_TRUE(run.r.plane);
  EXPECT_NEAR(run.r.plane->d, 0.0, 0.02);
  const auto& g = run.pipe->grid();
  EXPECT_GT(occupiedShare(g, 1.3, 1.4, -0.05, 0.05), 0.5) << "outlet";
  int cols = 0, blocked = 0;  // every lateral column meets the gutter
  for (int j = g.cellY(-0.5); j <= g.cellY(0.5); ++j) {
    ++cols;
    bool occ = false;
    for (int i = g.cellX(1.85); i <= g.cellX(2.1); ++i) occ = occ || g.prob(i, j) > 0.55;
    blocked += occ ? 1 : 0;
  }
  EXPECT_EQ(blocked, cols) << "gutter";
  // The lower floor is seen from 3.05 m (occlusion behind the edge).
  EXPECT_GT(occupiedShare(g, 3.1, 3.8, -0.5, 0.5), 0.9) << "lower floor past the stair edge";
  EXPECT_EQ(occupiedShare(g, 0.7, 1.2, -0.5, 0.5), 0.0) << "floor before the outlet";
}

TEST(PerceptionNoise, SixDegreeRampAndLandingStayFree) {
  Scene s;
  s.floor(-10, 10).ramp(1.3, 2.8, 0.1577);  // 6 deg over 1.5 m, then a landing
  const auto run = perceive(noisyFrame(s), Method::RrtGpd, noiseAware());
  ASSERT_TRUE(run.r.plane);
  EXPECT_GT(run.r.ism.rescued_voxels, 100u);
  const auto& g = run.pipe->grid();
  // A few isolated voxels (one frame, 2 mm ramp steps) stay obstacles: < 5 %.
  EXPECT_LT(occupiedShare(g, 0.7, 3.8, -0.8, 0.8), 0.05);
  EXPECT_GT(freeShare(g, 1.3, 3.3, -0.5, 0.5), 0.9);
  // With the traversable-surface rule off, one plane per frame marks the
  // ramp (or the floor before it) as obstacle.
  PerceptionParams off = noiseAware();
  off.max_slope_deg = 0;
  const auto one_plane = perceive(noisyFrame(s), Method::RrtGpd, off);
  EXPECT_GT(occupiedShare(one_plane.pipe->grid(), 0.7, 3.8, -0.8, 0.8), 0.2);
}

TEST(PerceptionNoise, StepOfAStairUpIsNoRamp) {
  // A 17 cm step up: flat on both sides, but not reachable by any slope.
  Scene s;
  s.floor(-10, 10).box({1.8, 10, -10, 10, -2, 0.17});
  const auto run = perceive(noisyFrame(s), Method::RrtGpd, noiseAware());
  ASSERT_TRUE(run.r.plane);
  EXPECT_NEAR(run.r.plane->d, 0.0, 0.02);
  EXPECT_GT(occupiedShare(run.pipe->grid(), 1.8, 2.5, -0.5, 0.5), 0.9);
}

TEST(PerceptionNoise, TwoCentimetreBoxIsAnObstacleAtOneAndAHalfMetres) {
  // HOBBIT's 20 mm limit ([Puente14, App. Sec. VI]), 1 cm under [Garrote17]'s d_pth = 3 cm;
  // the step is too abrupt for the traversable-surface rule.
  Scene s;
  s.floor(-10, 10).box({1.5, 1.7, -0.15, 0.15, -2, 0.02});
  const auto run = perceive(noisyFrame(s), Method::RrtGpd, noiseAware());
  const auto& g = run.pipe->grid();
  EXPECT_GT(occupiedShare(g, 1.5, 1.7, -0.15, 0.15), 0.5);
  EXPECT_EQ(occupiedShare(g, 0.7, 1.3, -0.5, 0.5), 0.0);
}

namespace {
/** Elevation grid of a noise-free floor at z = 0 (plus a +-2 mm spread per
 *  cell) from x 0.5 to 2.5 m, with `patch(x, y)` added to the height. */
template <class F>
ElevationGrid patchGrid(F&& patch) {
  Cloud c;
  for (double x = 0.5; x < 2.5; x += 0.0125)
    for (double y = -0.5; y < 0.5; y += 0.0125)
      for (int k = 0; k < 2; ++k)
        c.points.push_back({static_cast<float>(x), static_cast<float>(y),
                            static_cast<float>(patch(x, y) + (k ? 0.002 : -0.002))});
  c.width = c.points.size();
  ElevationGrid g(200, 0.05);
  g.build(c, -1, 2, 3);
  return g;
}
VoxelClass classAt(const ElevationGrid& g, const std::vector<VoxelClass>& cl, double x, double y) {
  return cl[static_cast<size_t>(g.cellOf(x)) * g.cells() + g.cellOf(y)];
}
}  // namespace

TEST(PerceptionNoise, MeanRuleFindsAFlatTwoCentimetreTopThatTheDistanceRuleMisses) {
  const auto g = patchGrid(
      [](double x, double y) { return x > 1.5 && x < 1.7 && std::abs(y) < 0.15 ? 0.02 : 0.0; });
  PerceptionParams p;
  std::vector<VoxelClass> cl;
  classifyVoxels(g, Plane{}, p, nullptr, cl);
  EXPECT_EQ(classAt(g, cl, 1.6, 0.0), VoxelClass::Obstacle);
  EXPECT_EQ(classAt(g, cl, 1.2, 0.0), VoxelClass::Ground);
  p.mean_step = 0;  // [Garrote17]'s rule alone: z+ = 2.2 cm < d_pth
  classifyVoxels(g, Plane{}, p, nullptr, cl);
  EXPECT_EQ(classAt(g, cl, 1.6, 0.0), VoxelClass::Ground);
}

TEST(PerceptionNoise, RampRuleKeepsSlopesUpToMaxSlopeAndStopsAtSteeperOnes) {
  auto ramp = [](double deg) {
    return [deg](double x, double) {
      return x < 1.0 ? 0.0 : std::tan(deg * M_PI / 180) * (std::min(x, 2.0) - 1.0);
    };
  };
  PerceptionParams p;  // max_slope_deg 8
  std::vector<VoxelClass> cl;
  const auto six = patchGrid(ramp(6));
  const IsmStats st = classifyVoxels(six, Plane{}, p, nullptr, cl);
  EXPECT_GT(st.rescued_voxels, 300u);
  EXPECT_EQ(classAt(six, cl, 1.8, 0.0), VoxelClass::Ground);  // 8 cm up the ramp
  EXPECT_EQ(classAt(six, cl, 2.3, 0.0), VoxelClass::Ground);  // the landing, 10.5 cm up
  const auto twelve = patchGrid(ramp(12));
  classifyVoxels(twelve, Plane{}, p, nullptr, cl);
  EXPECT_EQ(classAt(twelve, cl, 1.8, 0.0), VoxelClass::Obstacle);
  EXPECT_EQ(classAt(twelve, cl, 2.3, 0.0), VoxelClass::Obstacle);
}

TEST(PerceptionNoise, VerticalNoiseFollowsTheQuadraticDepthModel) {
  PerceptionParams p;
  const Point3f o{0.2f, 0.f, 0.9f};
  EXPECT_EQ(verticalNoise(p, &o, 3, 0, 0), 0.0);  // no model: [Garrote17]'s fixed d_pth
  p.depth_noise_std = 0.005;
  EXPECT_EQ(verticalNoise(p, nullptr, 3, 0, 0), 0.0);
  // Floor 2.8 m ahead of the camera: r = sqrt(2.8^2 + 0.9^2), sigma = a r^2
  // along the ray, vertical share 0.9 / r.
  const double r = std::hypot(2.8, 0.9);
  EXPECT_NEAR(verticalNoise(p, &o, 3, 0, 0), 0.005 * r * r * 0.9 / r, 1e-9);
}

TEST(PerceptionScene, EmptyAndAllNaNFramesAreNoInformation) {
  Cloud empty;
  Cloud nan;
  nan.width = 64;
  nan.height = 48;
  const float q = std::numeric_limits<float>::quiet_NaN();
  nan.points.assign(64 * 48, {q, q, q});
  nan.points[5] = {0, 0, 0};  // a zero depth
  for (const Cloud* c : {&empty, &nan})
    for (Method m : {Method::RrtGpd, Method::Ransac, Method::HeightBand}) {
      Pipeline pipe(PerceptionParams{}, m);
      FrameInput in;
      in.cloud = c;
      const auto r = pipe.process(in, true);
      EXPECT_FALSE(r.plane);
      EXPECT_EQ(r.counts.occupied, 0u);
      EXPECT_EQ(r.counts.free, 0u);
      EXPECT_EQ(r.counts.unknown, 200u * 200u);
      ASSERT_TRUE(r.kos);
      for (size_t k = 0; k < r.kos->getScanSize(); ++k)
        EXPECT_FALSE(r.kos->getScanRangeValidity(k));
    }
}

TEST(PerceptionScene, OdometryMovesTheLocalGridAndEvidenceAccumulates) {
  Scene s;
  s.floor(-10, 10).box({3.0, 3.2, -10, 10, 0, 2.5});  // wall at x = 3 (odometry frame)
  Pipeline pipe(PerceptionParams{}, Method::RrtGpd);
  double p_prev = 0.5;
  for (int k = 0; k < 3; ++k) {
    const double x = 0.25 * k;  // the robot drives 0.25 m per frame toward the wall
    const auto pose = mrpt::poses::CPose3D(x, 0, 0, 0, 0, 0) + walkerKinect();
    Cloud c = renderDepth(s, pose, 11 + k);
    // Robot-frame cloud: subtract the robot's pose.
    for (auto& p : c.points) p.x -= static_cast<float>(x);
    FrameInput in;
    in.cloud = &c;
    in.odometry = mrpt::poses::CPose2D(x, 0, 0);
    pipe.process(in, false);
    const double p_wall = pipe.grid().probAt(3.02, 0.0);
    EXPECT_GT(p_wall, 0.55) << "frame " << k;
    EXPECT_GE(p_wall, p_prev - 1e-9) << "occupancy accumulates at the same world cell";
    p_prev = p_wall;
    EXPECT_LT(pipe.grid().probAt(x + 1.5, 0.0), 0.45);
  }
  EXPECT_GT(p_prev, 0.9);
  // The grid stays centred on the robot: its window moved by 0.5 m.
  EXPECT_NEAR(pipe.grid().centreX(pipe.grid().cells() / 2), 0.5, 0.05);
}

// ------------------------------------------------------------------ virtual scans

TEST(PerceptionScans, KosAndMaxRuleSeeTheWallsAndFspfDropsTheFloor) {
  Scene s;
  s.floor(-10, 10)
      .box({2.5, 2.7, -10, 10, 0, 2.5})     // front wall
      .box({1.2, 1.4, -0.1, 0.1, 0, 0.4});  // a box in front of it
  const Cloud c = renderDepth(s, walkerKinect());
  PerceptionParams p;
  Pipeline pipe(p, Method::RrtGpd);
  FrameInput in;
  in.cloud = &c;
  in.sensor_origin = {0.2f, 0.f, 0.9f};
  const auto r = pipe.process(in, true);
  ASSERT_TRUE(r.fspf && r.kos && r.maxrule);
  EXPECT_GT(r.fspf->planes_dropped, 0);  // the floor
  EXPECT_GT(r.fspf->planes, 0);          // wall and box faces
  size_t low = 0;  // floor points kept (wall bases touch the floor: a few are expected)
  for (const auto& q : r.fspf->filtered.points) low += std::abs(q.z) < 0.02f ? 1 : 0;
  EXPECT_LT(low, r.fspf->filtered.points.size() / 50);
  EXPECT_GT(r.fspf->filtered.points.size(), 5000u);
  auto rangeAt = [](const mrpt::obs::CObservation2DRangeScan& sc, double bearing) {
    const size_t n = sc.getScanSize();
    const size_t k = static_cast<size_t>((bearing + M_PI) / (2 * M_PI / n));
    return sc.getScanRangeValidity(k) ? sc.getScanRange(k) : -1.f;
  };
  // KOS keeps the minimum: the box at 1.2 m straight ahead; max-rule (at
  // 0.35 m) keeps the wall behind it.
  EXPECT_NEAR(rangeAt(*r.kos, 0.001), 1.2, 0.05);
  EXPECT_NEAR(rangeAt(*r.maxrule, 0.001), 2.5, 0.05);
  EXPECT_NEAR(rangeAt(*r.kos, 0.3), 2.5 / std::cos(0.3), 0.06);
}

TEST(PerceptionParams, SectionIsRegisteredWithTableIDefaults) {
  registerProfileSections();
  const PerceptionParams d;
  EXPECT_EQ(d.rrt_iterations, 600);
  EXPECT_EQ(d.normal_threshold, 0.2);
  EXPECT_EQ(d.elevation_threshold, 0.05);
  EXPECT_EQ(d.window, 3);
  EXPECT_EQ(d.grid_cells, 200);
  EXPECT_EQ(d.resolution, 0.05);
  EXPECT_EQ(d.expansion_distance, 0.4);
  EXPECT_EQ(d.d_pth, 0.03);
  EXPECT_EQ(d.k_g, 0.3);
  EXPECT_EQ(d.sigma2, 0.02);
  EXPECT_EQ(d.k_n, 0.0005);
  EXPECT_EQ(d.d_min, 3);
  EXPECT_EQ(d.k_m, 0.8);
  auto prof = Profile::fromText("[perception]\nrrt_iterations = 100\nwindow = 4\n", "t.ini");
  EXPECT_THROW(prof.section<PerceptionParams>("perception"), InputError);  // even window
  auto typo = Profile::fromText("[perception]\nrrt_iteration = 100\n", "t.ini");
  bool unknown = false;
  for (const auto& i : typo.check()) unknown = unknown || i.key == "rrt_iteration";
  EXPECT_TRUE(unknown);
  auto ok = Profile::fromText("[perception]\nrrt_iterations = 100\n", "t.ini");
  for (const auto& i : ok.check()) EXPECT_NE(i.section, "perception") << i.text();
  EXPECT_EQ(ok.section<PerceptionParams>("perception").rrt_iterations, 100);
}

TEST(PerceptionScene, NoStateCarriesOverBetweenPipelines) {
  // The pipeline keeps per-thread scratch buffers and lookup tables; a run
  // must not depend on what ran before it in the same thread (navigation
  // runs scenario after scenario in one process).
  Scene s;
  s.floor(-10, 1.2).floor(1.2, 10, -0.17);
  const Cloud c = noisyFrame(s, 3);
  const auto first = perceive(c, Method::RrtGpd, noiseAware());
  {
    // Something else in between: another scene, other parameters and method.
    Scene o;
    o.floor(-10, 10);
    PerceptionParams q = noiseAware();
    q.depth_noise_std = 0.02;
    q.sigma2 = 0.05;
    q.resolution = 0.1;
    perceive(noisyFrame(o, 9), Method::RrtGpd, q);
    perceive(noisyFrame(o, 9), Method::Ransac, PerceptionParams{});
  }
  const auto again = perceive(c, Method::RrtGpd, noiseAware());
  const auto& ga = first.pipe->grid();
  const auto& gb = again.pipe->grid();
  ASSERT_EQ(ga.cells(), gb.cells());
  for (int i = 0; i < ga.cells(); ++i)
    for (int j = 0; j < ga.cells(); ++j) ASSERT_EQ(ga.prob(i, j), gb.prob(i, j)) << i << "," << j;
}
