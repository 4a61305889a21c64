// SLAM back ends and the slam job on MRPT's real SENA rawlog.
#include <carenav/io/map_io.h>
#include <carenav/io/rawlog_reader.h>
#include <carenav/io/trajectory.h>
#include <carenav/slam/slam_job.h>

#include <gtest/gtest.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/serialization/CArchive.h>

#include <cmath>
#include <filesystem>
#include <fstream>

using namespace carenav;
namespace fs = std::filesystem;

namespace {
const std::string kSena =
    std::string(CARENAV_MRPT_DATASETS) + "/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog";

fs::path scratch(const std::string& name) {
  auto d = fs::temp_directory_path() / ("carenav_slam_" + std::to_string(::getpid())) / name;
  fs::create_directories(d);
  return d;
}

/** Copies entries [from, to) of a rawlog into a new one. */
void copyEntries(const std::string& in, const std::string& out, size_t from, size_t to) {
  io::RawlogReader r(in);
  mrpt::io::CFileGZOutputStream f(out);
  auto arch = mrpt::serialization::archiveFrom(f);
  io::RawlogEntry e;
  while (r.next(e))
    if (e.index >= from && e.index < to) arch << *e.object;
}

slam::SlamJobOptions options(const std::string& method, const std::string& rawlog,
                             const fs::path& out) {
  slam::SlamJobOptions o;
  o.rawlog = rawlog;
  o.out_dir = out.string();
  o.method = method;
  o.progress = false;
  return o;
}

/** Smallest distance between a pose and any pose at least `dt` seconds later. */
double revisitDistance(const io::Trajectory2D& t, double dt) {
  double best = 1e9;
  for (size_t i = 0; i < t.size(); ++i)
    for (size_t j = i + 1; j < t.size(); ++j)
      if (t[j].t - t[i].t > dt) best = std::min(best, std::hypot(t[j].x - t[i].x, t[j].y - t[i].y));
  return best;
}
}  // namespace

class SlamMethods : public ::testing::TestWithParam<std::string> {};

TEST_P(SlamMethods, MapsTheSenaLoopAndWritesLoadableOutputs) {
  const std::string method = GetParam();
  const auto out = scratch(method);
  const auto r = slam::runSlam(options(method, kSena, out));
  EXPECT_FALSE(r.rawlog_error.has_value());
  EXPECT_EQ(r.steps, 225u);  // every scan of the log
  EXPECT_GT(r.stats.inserted, 50u);

  // The three back ends agree on where the loop ends (MRPT's icp-slam ends
  // at (4.31, -18.49, -87.7 deg) on this log, see the CLI test).
  EXPECT_NEAR(r.final_pose.x(), 4.3, 0.8);
  EXPECT_NEAR(r.final_pose.y(), -18.5, 0.8);
  EXPECT_NEAR(r.final_pose.phi() * 180 / M_PI, -88, 5);

  const auto traj = io::readTum((out / "trajectory.tum").string());
  ASSERT_EQ(traj.size(), 225u);
  // The robot drives around a block and passes its start again.
  EXPECT_LT(revisitDistance(traj, 30.0), 1.0);

  // Outputs load in MRPT.
  mrpt::maps::CSimpleMap sm;
  {
    mrpt::io::CFileGZInputStream f((out / "map.simplemap").string());
    auto arch = mrpt::serialization::archiveFrom(f);
    arch >> sm;
  }
  EXPECT_EQ(sm.size(), r.stats.inserted);
  mrpt::maps::COccupancyGridMap2D grid;
  {
    mrpt::io::CFileGZInputStream f((out / "map.gridmap.gz").string());
    auto arch = mrpt::serialization::archiveFrom(f);
    arch >> grid;
  }
  const auto st = io::gridStats(grid);
  EXPECT_GT(st.occupied, 2000u);
  EXPECT_GT(st.free, 100000u);
  // A faculty building of some 40 x 40 m.
  EXPECT_GT(st.widthMetres(), 30);
  EXPECT_LT(st.widthMetres(), 150);

  // The ROS map is the same grid, in map_server's conventions.
  const auto ros = io::readRosMap((out / "map.yaml").string());
  EXPECT_EQ(ros.getSizeX(), grid.getSizeX());
  EXPECT_EQ(ros.getSizeY(), grid.getSizeY());
  EXPECT_NEAR(ros.getXMin(), grid.getXMin(), 1e-6);
  EXPECT_NEAR(ros.getYMin(), grid.getYMin(), 1e-6);
  EXPECT_NEAR(ros.getResolution(), grid.getResolution(), 1e-9);
  const auto rst = io::gridStats(ros);
  EXPECT_EQ(rst.occupied, st.occupied);
  EXPECT_EQ(rst.free, st.free);
  EXPECT_TRUE(fs::exists(out / "map.png"));
  EXPECT_GT(fs::file_size(out / "map.png"), 10000u);

  std::ifstream sj(out / "summary.json");
  const std::string summary((std::istreambuf_iterator<char>(sj)), std::istreambuf_iterator<char>());
  EXPECT_NE(summary.find("\"steps\": 225"), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"complete\": true"), std::string::npos);
}

INSTANTIATE_TEST_SUITE_P(AllBackEnds, SlamMethods, ::testing::Values("icp", "icp-graph", "rbpf"),
                         [](const auto& info) {
                           std::string n = info.param;
                           for (auto& c : n)
                             if (c == '-') c = '_';
                           return n;
                         });

TEST(SlamGraph, ClosesTheLoopWithLoopClosureEdges) {
  const auto r = slam::runSlam(options("icp-graph", kSena, scratch("graph_loop")));
  EXPECT_GT(r.stats.keyframes, 50u);
  EXPECT_GT(r.stats.loop_closures, 5u);
  EXPECT_GE(r.stats.optimisations, 1u);
}

TEST(SlamGraph, LaserOnlyMatchesTheRunWithOdometry) {
  auto o = options("icp-graph", kSena, scratch("graph_laser_only"));
  o.mapper.slam.use_odometry = false;
  const auto r = slam::runSlam(o);
  EXPECT_NEAR(r.final_pose.x(), 4.3, 0.8);
  EXPECT_NEAR(r.final_pose.y(), -18.5, 0.8);
}

TEST(SlamJob, ResumeExtendsASavedMap) {
  // The first 250 entries, then the rest started from the end of the first map.
  const auto dir = scratch("resume");
  const std::string a = (dir / "a.rawlog").string(), b = (dir / "b.rawlog").string();
  copyEntries(kSena, a, 0, 250);
  copyEntries(kSena, b, 249, 10000);  // starts with the action into the next frame
  for (const std::string method : {"icp", "icp-graph"}) {
    SCOPED_TRACE(method);
    const auto first = slam::runSlam(options(method, a, dir / (method + "_a")));
    mrpt::maps::CSimpleMap sm;
    {
      mrpt::io::CFileGZInputStream f((dir / (method + "_a") / "map.simplemap").string());
      auto arch = mrpt::serialization::archiveFrom(f);
      arch >> sm;
    }
    auto o = options(method, b, dir / (method + "_b"));
    o.mapper.resume_map = sm;
    o.mapper.start_pose = first.final_pose;
    const auto second = slam::runSlam(o);
    EXPECT_GT(second.stats.inserted + 0, 0u);
    // Ends where a single run over the whole log ends.
    EXPECT_NEAR(second.final_pose.x(), 4.3, 0.8);
    EXPECT_NEAR(second.final_pose.y(), -18.5, 0.8);
    mrpt::maps::CSimpleMap sm2;
    {
      mrpt::io::CFileGZInputStream f((dir / (method + "_b") / "map.simplemap").string());
      auto arch = mrpt::serialization::archiveFrom(f);
      arch >> sm2;
    }
    EXPECT_GT(sm2.size(), sm.size());  // the old map plus the new scans
  }
}

TEST(SlamJob, TruncatedRawlogKeepsWhatWasMapped) {
  const auto dir = scratch("truncated");
  std::string raw;
  {
    mrpt::io::CFileGZInputStream in(kSena);
    char buf[65536];
    size_t n;
    while ((n = in.Read(buf, sizeof buf)) > 0) raw.append(buf, n);
  }
  const auto cut = (dir / "cut.rawlog").string();
  std::ofstream(cut, std::ios::binary) << raw.substr(0, raw.size() / 2 + 17);
  const auto r = slam::runSlam(options("icp-graph", cut, dir / "out"));
  ASSERT_TRUE(r.rawlog_error.has_value());
  EXPECT_NE(r.rawlog_error->find("broken at entry"), std::string::npos);
  EXPECT_GT(r.steps, 80u);
  EXPECT_LT(r.steps, 225u);
  EXPECT_TRUE(fs::exists(dir / "out" / "map.yaml"));
  EXPECT_EQ(io::readTum((dir / "out" / "trajectory.tum").string()).size(), r.steps);
}

TEST(SlamJob, NoUsableScanIsBadInput) {
  const std::string gps = std::string(CARENAV_MRPT_DATASETS) + "/test_rtk_path.rawlog";
  try {
    slam::runSlam(options("icp", gps, scratch("noscan")));
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no usable 2D laser scan"), std::string::npos);
  }
  auto o = options("icp", kSena, scratch("badlabel"));
  o.mapper.slam.sensor = "HOKUYO";
  EXPECT_THROW(slam::runSlam(o), InputError);
  EXPECT_THROW(slam::runSlam(options("nope", kSena, scratch("badmethod"))), InputError);
}
