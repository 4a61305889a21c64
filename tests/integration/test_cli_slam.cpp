// `carenav slam` as a user runs it, against MRPT's own icp-slam.
#include "cli_helpers.h"

using namespace carenav_test;
namespace fs = std::filesystem;

namespace {
/** MRPT's icp-slam demo INI made headless, reading `rawlog`, logging to `out`. */
std::string mrptIcpIni(const fs::path& dir, const std::string& rawlog, const fs::path& out) {
  const std::string ini = (dir / "icp-slam.ini").string();
  const RunResult r = shell(
      "sed -e 's|^rawlog_file=.*|rawlog_file=" + rawlog +
      "|' -e 's|^SHOW_PROGRESS_3D_REAL_TIME=.*|SHOW_PROGRESS_3D_REAL_TIME=0|' "
      "-e 's|^SAVE_3D_SCENE=.*|SAVE_3D_SCENE=0|' -e 's|^SAVE_POSE_LOG=.*|SAVE_POSE_LOG=1|' "
      "-e 's|^LOG_FREQUENCY=.*|LOG_FREQUENCY=100000|' -e 's|^logOutput_dir=.*|logOutput_dir=" +
      out.string() + "|' /usr/share/mrpt/config_files/icp-slam/icp-slam_demo_classic.ini > " +
      quote(ini));
  EXPECT_EQ(r.code, 0);
  return ini;
}

std::vector<double> lastLineNumbers(const fs::path& p) {
  std::ifstream f(p);
  std::string line, last;
  while (std::getline(f, line))
    if (!line.empty() && line[0] != '#') last = line;
  std::istringstream is(last);
  std::vector<double> v;
  double x;
  while (is >> x) v.push_back(x);
  return v;
}
}  // namespace

TEST(CliSlam, EachMethodEndsWhereMrptIcpSlamEnds) {
  ASSERT_TRUE(fs::exists("/usr/bin/icp-slam")) << "install mrpt-apps (scripts/setup.sh)";
  const auto dir = scratch() / "slam_vs_mrpt";
  fs::create_directories(dir);
  const auto ini = mrptIcpIni(dir, kSena, dir / "mrpt_out");
  ASSERT_EQ(shell("/usr/bin/icp-slam " + quote(ini) + " > /dev/null 2>&1").code, 0);
  const auto ref = lastLineNumbers(dir / "mrpt_out" / "log_estimated_path.txt");
  ASSERT_EQ(ref.size(), 4u);  // index x y phi
  for (const char* method : {"icp", "icp-graph"}) {
    SCOPED_TRACE(method);
    const auto out = dir / method;
    const RunResult r = carenav({"slam", "--profile", kSrc + "/ini/interbot.ini", "--rawlog", kSena,
                                 "--method", method, "--out", out.string()});
    ASSERT_EQ(r.code, 0) << r.err;
    const auto est = lastLineNumbers(out / "trajectory.tum");
    ASSERT_EQ(est.size(), 8u);
    EXPECT_NEAR(est[1], ref[1], 0.5);
    EXPECT_NEAR(est[2], ref[2], 0.5);
    for (const char* f : {"map.simplemap", "map.gridmap.gz", "map.yaml", "map.pgm", "map.png",
                          "trajectory.tum", "summary.json"})
      EXPECT_TRUE(fs::exists(out / f)) << f;
    // Other tools read the map: carenav's own loader of ROS maps.
    const RunResult info = carenav({"map", "info", (out / "map.yaml").string()});
    EXPECT_EQ(info.code, 0) << info.err;
  }
}

TEST(CliSlam, AcceptsMrptIcpSlamIniFiles) {
  const auto dir = scratch() / "slam_mrpt_ini";
  fs::create_directories(dir);
  const auto ini = mrptIcpIni(dir, kSena, dir / "unused");
  const RunResult r =
      carenav({"slam", "--profile", ini, "--rawlog", kSena, "--out", (dir / "out").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string summary = slurp(dir / "out" / "summary.json");
  EXPECT_NE(summary.find("\"method\": \"icp\""), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"steps\": 225"), std::string::npos) << summary;
}

TEST(CliSlam, BadInputsExitTwoAndKeepWhatWasMapped) {
  const auto dir = scratch() / "slam_bad";
  fs::create_directories(dir);
  // A misspelt key of the [slam] section.
  RunResult r = carenav({"slam", "--profile", kSrc + "/ini/interbot.ini", "--rawlog", kSena,
                         "--out", (dir / "a").string(), "--set", "slam.grid_resolutoin=0.1"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("[slam] grid_resolutoin: unknown key (did you mean 'grid_resolution'?)"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir / "a" / "map.yaml"));
  // Out of range.
  r = carenav({"slam", "--profile", kSrc + "/ini/interbot.ini", "--rawlog", kSena, "--out",
               (dir / "b").string(), "--set", "slam.grid_resolution=5"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("slam] grid_resolution: '5': out of range"), std::string::npos) << r.err;
  // A rawlog without any 2D scan.
  r = carenav({"slam", "--profile", kSrc + "/ini/interbot.ini", "--rawlog",
               kDatasets + "/test_rtk_path.rawlog", "--out", (dir / "c").string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("no usable 2D laser scan"), std::string::npos) << r.err;
  // A truncated rawlog: exit 2, and the map of what was read is there.
  const auto raw = dir / "sena.rawlog";
  ASSERT_EQ(shell("gzip -dc " + quote(kSena) + " > " + quote(raw.string())).code, 0);
  const auto cut = dir / "cut.rawlog";
  ASSERT_EQ(shell("head -c 300000 " + quote(raw.string()) + " > " + quote(cut.string())).code, 0);
  r = carenav({"slam", "--profile", kSrc + "/ini/interbot.ini", "--rawlog", cut.string(),
               "--method", "icp-graph", "--out", (dir / "d").string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("broken at entry"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("was saved in"), std::string::npos) << r.err;
  const std::string summary = slurp(dir / "d" / "summary.json");
  EXPECT_NE(summary.find("\"complete\": false"), std::string::npos) << summary;
  EXPECT_TRUE(fs::exists(dir / "d" / "map.pgm"));
  // A missing rawlog, and --resume with something that is not a map.
  r = carenav({"slam", "--profile", kSrc + "/ini/interbot.ini", "--rawlog",
               (dir / "none.rawlog").string(), "--out", (dir / "e").string()});
  EXPECT_EQ(r.code, 2);
  r = carenav({"slam", "--profile", kSrc + "/ini/interbot.ini", "--rawlog", kSena, "--out",
               (dir / "f").string(), "--resume", kSena});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("not an MRPT .simplemap"), std::string::npos) << r.err;
}

// A log whose timestamps all repeat (a log stamped in whole seconds or not at
// all): `icp` advances by scan order and maps as it does with the log's real
// times, says so, and the trajectory can be evaluated by index.
TEST(CliSlam, IcpAdvancesByScanOrderWhenTimestampsRepeat) {
  const fs::path dir = scratch() / "slam_equal_stamps";
  fs::create_directories(dir);
  const std::string intel = kTestData + "/carmen/intel-corrected.log.gz";
  const std::string real = (dir / "real.log").string(), same = (dir / "same.log").string();
  ASSERT_EQ(shell("zcat " + quote(intel) + " | head -n 3000 > " + quote(real)).code, 0);
  ASSERT_EQ(shell("awk '$1==\"FLASER\"||$1==\"ODOM\"{$(NF-2)=7} {print}' " + quote(real) + " > " +
                  quote(same))
                .code,
            0);
  struct Run {
    uint64_t steps = 0, inserted = 0, restamped = 0;
    std::string err;
  };
  auto run = [&](const std::string& log, const std::string& name) {
    Run r;
    const std::string rawlog = (dir / (name + ".rawlog")).string();
    const RunResult imp =
        carenav({"-q", "import", "carmen", log, "--odometry", "laser", "--out", rawlog});
    EXPECT_EQ(imp.code, 0) << imp.err;
    const RunResult s = carenav({"slam", "--profile", kSrc + "/ini/defaults.ini", "--method", "icp",
                                 "--rawlog", rawlog, "--out", (dir / name).string()});
    EXPECT_EQ(s.code, 0) << s.err;
    const std::string sum = slurp(dir / name / "summary.json");
    r.steps = jsonNumber(sum, "steps");
    r.inserted = jsonNumber(sum, "scans_inserted");
    r.restamped = jsonNumber(sum, "scans_restamped");
    EXPECT_NE(sum.find("\"complete\": true"), std::string::npos);
    r.err = s.err;
    return r;
  };
  const Run a = run(real, "real"), b = run(same, "same");
  ASSERT_GT(a.steps, 100u);
  EXPECT_EQ(b.steps, a.steps);
  EXPECT_EQ(a.restamped, 0u);
  EXPECT_EQ(b.restamped, b.steps - 1);
  EXPECT_NE(b.err.find("did not advance in time"), std::string::npos) << b.err;
  EXPECT_GT(a.inserted, a.steps / 2);
  EXPECT_EQ(b.inserted, a.inserted);  // the same map, not a 2-scan one

  // The trajectories: by time they cannot be paired (one repeated stamp),
  // the message says why and names --by-index, which pairs them.
  const std::string est = (dir / "same" / "trajectory.tum").string();
  const std::string ref = (dir / "real" / "trajectory.tum").string();
  RunResult e = carenav({"eval", "--est", est, "--ref", ref});
  EXPECT_EQ(e.code, 2);
  EXPECT_NE(e.err.find("--by-index"), std::string::npos) << e.err;
  e = carenav({"eval", "--est", est, "--ref", ref, "--by-index", "--json"});
  ASSERT_EQ(e.code, 0) << e.err;
  EXPECT_EQ(jsonNumber(e.out, "matched"), a.steps);
  EXPECT_NE(e.out.find("\"method\": \"index\""), std::string::npos);
}
