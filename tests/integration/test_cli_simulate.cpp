// `carenav simulate` end to end: a walk on the real SENA map whose rawlog
// `carenav localize` tracks against the ground truth, MRPT's rawlog-edit
// reads the rawlog, and bad inputs exit 2 with a message naming the fault.
#include "cli_helpers.h"

#include <array>
#include <cmath>
#include <optional>

using namespace carenav_test;

namespace {

const std::string kWorlds = kSrc + "/maps/worlds";

std::optional<double> jsonReal(const std::string& json, const std::string& key) {
  std::smatch m;
  if (!std::regex_search(json, m, std::regex("\"" + key + "\": (-?[0-9.]+(?:[eE][-+]?[0-9]+)?)")))
    return std::nullopt;
  return std::stod(m[1]);
}

/** A profile with only a 2D lidar (10 Hz, 541 beams) on the defaults' robot. */
std::string laserProfile(const fs::path& dir) {
  const auto p = dir / "sim_laser.ini";
  std::ofstream(p) << "[profile]\nname = sim-laser\nbase = " << kSrc
                   << "/ini/defaults.ini\n\n[sensor.laser]\ntype = lidar2d\nx = 0.2\nz = 0.3\n"
                      "rate_hz = 10\nfov = 270\nbeams = 541\nrange_min = 0.1\nrange_max = 30\n"
                      "noise_std = 0.02\n";
  return p.string();
}

}  // namespace

TEST(CliSimulate, SenaWalkIsLocalisedAgainstItsGroundTruth) {
  const auto dir = scratch() / "sim_sena";
  fs::create_directories(dir);
  const auto profile = laserProfile(dir);
  const auto rawlog = (dir / "walk.rawlog").string();
  auto r = carenav({"simulate", "--profile", profile, "--world", kWorlds + "/sena.yaml", "--path",
                    "-8,4.5 3,4.5 3,-10", "--seed", "3", "--out", rawlog});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto gt = dir / "walk.gt.tum";
  ASSERT_TRUE(fs::exists(gt));
  const std::string summary = slurp(dir / "walk.summary.json");
  EXPECT_NE(summary.find("\"path_completed\": true"), std::string::npos) << summary;
  EXPECT_EQ(jsonNumber(summary, "collisions"), 0u);
  const uint64_t scans = jsonNumber(summary, "laser");
  EXPECT_GT(scans, 700u);  // about 85 s at 10 Hz
  // the odometry drifts: the final odometry is off the truth by decimetres or more
  // (so the localiser has real work to do)
  auto triple = [&](const std::string& key) {
    std::smatch m;
    const std::string num = "\\s*(-?[0-9.eE+-]+),";
    EXPECT_TRUE(std::regex_search(
        summary, m, std::regex("\"" + key + "\": \\[" + num + num + "\\s*(-?[0-9.eE+-]+)")))
        << summary;
    return std::array<double, 3>{std::stod(m[1]), std::stod(m[2]), std::stod(m[3])};
  };
  const auto truth = triple("final_truth"), odo = triple("final_odometry");
  EXPECT_NEAR(truth[0], 3, 0.1);
  EXPECT_NEAR(truth[1], -10, 0.1);
  EXPECT_GT(std::hypot(odo[0] - truth[0], odo[1] - truth[1]), 0.3);

  // MRPT's own tool reads it
  if (fs::exists("/usr/bin/rawlog-edit")) {
    const auto info = shell("/usr/bin/rawlog-edit --info -i " + quote(rawlog));
    EXPECT_EQ(info.code, 0) << info.err;
    EXPECT_NE(info.out.find("Observations format               : Yes"), std::string::npos)
        << info.out;
    std::smatch m;
    ASSERT_TRUE(std::regex_search(info.out, m, std::regex("laser /\\s+([0-9]+) /"))) << info.out;
    EXPECT_EQ(std::stoull(m[1]), scans);
    ASSERT_TRUE(std::regex_search(info.out, m, std::regex("odometry /\\s+([0-9]+) /")));
    EXPECT_EQ(std::stoull(m[1]), scans);
  } else {
    ADD_FAILURE() << "/usr/bin/rawlog-edit (mrpt-apps) is not installed";
  }

  // carenav localize tracks it from a rough start
  const auto out = dir / "loc";
  r = carenav({"localize", "--profile", profile, "--map", kSrc + "/maps/sena.gridmap.gz",
               "--rawlog", rawlog, "--init", "-7.8,4.3,5", "--ref", gt.string(), "--out",
               out.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string loc = slurp(out / "summary.json");
  const auto at = loc.find("\"ate\"");
  ASSERT_NE(at, std::string::npos) << loc;
  const auto rmse = jsonReal(loc.substr(at), "rmse");
  ASSERT_TRUE(rmse);
  EXPECT_LT(*rmse, 0.3);
  EXPECT_GT(jsonNumber(loc.substr(at), "pairs"), scans - 5);
}

TEST(CliSimulate, ScriptDrivesTheWalkerWithItsDepthCamera) {
  const auto dir = scratch() / "sim_script";
  fs::create_directories(dir);
  std::ofstream(dir / "cmds.txt") << "# t v w\n0 0.3 0\n4 0.2 0.3\n8 0 0\n10 0 0\n";
  const auto rawlog = (dir / "w.rawlog.gz").string();
  const auto r = carenav({"simulate", "--profile", kSrc + "/ini/isr-aiwalker.ini", "--world",
                          kWorlds + "/apartment.yaml", "--script", (dir / "cmds.txt").string(),
                          "--start", "1,1,0", "--set", "sim.depth_decimation=8", "--out", rawlog});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string summary = slurp(dir / "w.summary.json");
  EXPECT_NEAR(*jsonReal(summary, "sim_seconds"), 10.0, 1e-6);
  EXPECT_EQ(jsonNumber(summary, "kinect"), 100u);  // 10 s at 10 Hz
  EXPECT_EQ(jsonNumber(summary, "leddar"), 100u);
  // carenav's rawlog reader counts the same
  const auto info = carenav({"rawlog", "info", rawlog});
  EXPECT_EQ(info.code, 0) << info.err;
  EXPECT_NE((info.out + info.err).find("kinect"), std::string::npos) << info.out;
}

TEST(CliSimulate, BadWorldFilesExit2NamingFileAndLine) {
  const auto dir = scratch() / "sim_bad";
  fs::create_directories(dir);
  const auto profile = laserProfile(dir);
  auto run = [&](const std::string& name, const std::string& text) {
    const auto w = dir / name;
    std::ofstream(w) << text;
    return carenav({"simulate", "--profile", profile, "--world", w.string(), "--path", "2,2 3,3",
                    "--out", (dir / "x.rawlog").string()});
  };
  const std::string map = "map: " + kWorlds + "/empty_room.png\nresolution: 0.05\n";
  auto r = run("empty.yaml", "");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("empty.yaml"), std::string::npos) << r.err;
  r = run("trunc.yaml", map + "people:\n  - path: [[1, 1], [2,");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("trunc.yaml:4"), std::string::npos) << r.err;
  r = run("unknown.yaml", map + "furniture: []\n");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("unknown.yaml:3: unknown key 'furniture'"), std::string::npos) << r.err;
  r = run("badnum.yaml", map + "wall_height: tall\n");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("'tall' is not a number"), std::string::npos) << r.err;
  r = run("nomap.yaml", "map: nowhere.gridmap.gz\n");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("does not exist"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "x.rawlog"));
}

TEST(CliSimulate, BadScriptsAndOptionsExit2) {
  const auto dir = scratch() / "sim_badscript";
  fs::create_directories(dir);
  const auto profile = laserProfile(dir);
  const auto world = kWorlds + "/empty_room.yaml";
  auto run = [&](std::vector<std::string> extra) {
    std::vector<std::string> a = {
        "simulate", "--profile", profile, "--world", world, "--out", (dir / "x.rawlog").string()};
    a.insert(a.end(), extra.begin(), extra.end());
    return carenav(a);
  };
  std::ofstream(dir / "empty.txt") << "";
  std::ofstream(dir / "trunc.txt") << "0 0.2 0\n1 0.2";
  std::ofstream(dir / "bad.txt") << "0 0.2 0\n1 zero 0\n";
  auto r = run({"--script", (dir / "empty.txt").string(), "--start", "5,5,0"});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("empty.txt"), std::string::npos) << r.err;
  r = run({"--script", (dir / "trunc.txt").string(), "--start", "5,5,0"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("trunc.txt:2"), std::string::npos) << r.err;
  r = run({"--script", (dir / "bad.txt").string(), "--start", "5,5,0"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("bad.txt:2"), std::string::npos) << r.err;
  r = run({"--path", "5,5 6,6", "--script", (dir / "bad.txt").string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("exactly one of --path and --script"), std::string::npos) << r.err;
  r = run({"--path", "5,5 6,x"});
  EXPECT_EQ(r.code, 2);
  r = run({"--path", "0.05,5 6,6"});  // starts in the wall
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("touches an obstacle"), std::string::npos) << r.err;
  // a profile without any sensor to simulate
  const auto bare = carenav({"simulate", "--profile", kSrc + "/ini/defaults.ini", "--world", world,
                             "--path", "5,5 6,6", "--out", (dir / "x.rawlog").string()});
  EXPECT_EQ(bare.code, 2);
  EXPECT_NE(bare.err.find("no sensor to simulate"), std::string::npos) << bare.err;
  r = run({"--path", "5,5 6,6", "--set", "sim.odom_std_d=-1"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("odom_std_d"), std::string::npos) << r.err;
}
