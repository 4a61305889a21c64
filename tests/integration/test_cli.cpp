// Runs the real carenav binary, as a user would.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <sstream>

#include "cli_helpers.h"

using namespace carenav_test;
namespace fs = std::filesystem;

TEST(Cli, HelpEverywhereAndExitCodes) {
  for (std::vector<std::string> args : {std::vector<std::string>{"--help"},
                                        {"profile", "--help"},
                                        {"profile", "check", "--help"},
                                        {"rawlog", "info", "--help"},
                                        {"demo", "--help"}}) {
    const RunResult r = carenav(args);
    EXPECT_EQ(r.code, 0) << args[0];
    EXPECT_NE(r.out.find("Usage:"), std::string::npos) << r.out;
  }
  EXPECT_EQ(carenav({}).code, 2);                  // no command
  EXPECT_EQ(carenav({"fly"}).code, 2);             // unknown command
  EXPECT_EQ(carenav({"rawlog", "info"}).code, 2);  // missing argument
  EXPECT_EQ(carenav({"--version"}).code, 0);
}

// Every rawlog MRPT ships. rawlog-edit --info leaves a trailing action that
// no sensory frame follows out of its object count (CRawlog counts it, see the
// unit tests); carenav reports it as "trailing_action".
TEST(Cli, RawlogInfoAgreesWithMrptRawlogEdit) {
  ASSERT_TRUE(fs::exists("/usr/bin/rawlog-edit")) << "install mrpt-apps (scripts/setup.sh)";
  size_t compared = 0;
  for (const auto& de : fs::directory_iterator(kDatasets)) {
    if (de.path().extension() != ".rawlog") continue;
    const std::string path = de.path().string();
    SCOPED_TRACE(path);
    const RunResult mrpt = shell("/usr/bin/rawlog-edit --info -i " + quote(path));
    ASSERT_EQ(mrpt.code, 0) << mrpt.err;
    std::smatch m;
    ASSERT_TRUE(
        std::regex_search(mrpt.out, m, std::regex("Overall number of objects\\s*:\\s*(\\d+)")))
        << mrpt.out;
    const uint64_t mrpt_count = std::stoull(m[1]);
    const RunResult ours = carenav({"rawlog", "info", "--json", path});
    ASSERT_EQ(ours.code, 0) << ours.err;
    const bool trailing = ours.out.find("\"trailing_action\": true") != std::string::npos;
    EXPECT_EQ(jsonNumber(ours.out, "entries"), mrpt_count + (trailing ? 1 : 0));
    const bool mrpt_asf =
        mrpt.out.find("Actions/SensoryFrame format       : Yes") != std::string::npos;
    EXPECT_EQ(ours.out.find("\"format\": \"actions-sensoryframes\"") != std::string::npos,
              mrpt_asf);
    ++compared;
  }
  EXPECT_GE(compared, 10u);  // mrpt-common ships 13 rawlogs
}

TEST(Cli, RawlogInfoTextOnTheSenaLoop) {
  const RunResult r = carenav({"rawlog", "info", kSena});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("entries:            449"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("CObservation2DRangeScan"), std::string::npos);
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.out, m, std::regex("path ([0-9.]+) m")));
  EXPECT_GT(std::stod(m[1]), 50.0);
  EXPECT_LT(std::stod(m[1]), 150.0);
  EXPECT_NE(r.out.find("time span:          59.0"), std::string::npos) << r.out;
  EXPECT_TRUE(r.err.empty()) << r.err;  // stderr is not a terminal: no progress
}

TEST(Cli, TruncatedRawlogExitsTwoNamingTheEntryAndPrintsWhatWasRead) {
  // Uncompress the SENA log and cut it in the middle of entry 224.
  const auto raw = scratch() / "sena.rawlog";
  ASSERT_EQ(shell("gzip -dc " + quote(kSena) + " > " + quote(raw.string())).code, 0);
  const auto size = fs::file_size(raw);
  for (uint64_t cut : {uint64_t(3), size / 2, size - 10}) {
    SCOPED_TRACE(cut);
    const auto cutf = scratch() / "cut.rawlog";
    ASSERT_EQ(shell("head -c " + std::to_string(cut) + " " + quote(raw.string()) + " > " +
                    quote(cutf.string()))
                  .code,
              0);
    const RunResult r = carenav({"rawlog", "info", "--json", cutf.string()});
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find(cutf.string()), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("broken at entry"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("MRPT exception"), std::string::npos) << r.err;
    if (cut > 1000) {  // entries before the break are reported
      EXPECT_NE(r.out.find("\"complete\": false"), std::string::npos) << r.out;
      EXPECT_GT(jsonNumber(r.out, "entries"), 100u);
    }
  }
}

// Corrupt bytes in entry headers (class names, counts, sizes): MRPT trusts
// the sizes it reads, so some of these make it allocate absurd amounts or
// crash. carenav must answer each with exit 0 (the bytes were only data) or 2
// and a message naming the entry: never a crash, never a hang.
TEST(Cli, CorruptEntryHeadersNeverCrash) {
  const auto raw = scratch() / "sena_fuzz_src.rawlog";
  ASSERT_EQ(shell("gzip -dc " + quote(kSena) + " > " + quote(raw.string())).code, 0);
  const std::string bytes = slurp(raw);
  std::vector<size_t> headers;
  for (const char* cls :
       {"CSensoryFrame", "CActionCollection", "CObservation2DRangeScan", "CActionRobotMovement2D"})
    for (size_t p = bytes.find(cls); p != std::string::npos; p = bytes.find(cls, p + 1))
      headers.push_back(p);
  ASSERT_GT(headers.size(), 400u);
  std::mt19937 rng(12345);
  const auto f = scratch() / "fuzz.rawlog";
  int exits[3] = {0, 0, 0};
  for (int trial = 0; trial < 40; ++trial) {
    std::string d = bytes;
    const size_t at = headers[rng() % headers.size()] + rng() % 80;
    const int n = 1 + static_cast<int>(rng() % 4);
    for (int k = 0; k < n && at + k < d.size(); ++k) d[at + k] = static_cast<char>(rng() & 0xff);
    std::ofstream(f, std::ios::binary) << d;
    // A small memory cap makes absurd size fields fail fast.
    const RunResult r = shell("CARENAV_MEMORY_LIMIT_MB=3000 timeout 120 " + quote(kBin) +
                              " -q rawlog info " + quote(f.string()) + " >/dev/null");
    SCOPED_TRACE("corrupt bytes at " + std::to_string(at) + ": " + r.err);
    ASSERT_TRUE(r.code == 0 || r.code == 2) << "exit " << r.code;
    ++exits[r.code];
    if (r.code == 2) {
      EXPECT_NE(r.err.find(f.string() + ": rawlog broken at entry "), std::string::npos);
    }
    // Refused by carenav's own checks, not caught by the crash guard's
    // signal handler or the address-space cap.
    EXPECT_EQ(r.err.find("crashed"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("memory limit"), std::string::npos) << r.err;
  }
  EXPECT_GT(exits[2], 10);  // most header corruptions are detected
}

TEST(Cli, BadRawlogInputs) {
  const auto dir = scratch();
  std::ofstream(dir / "empty.rawlog").close();
  std::ofstream(dir / "text.rawlog") << "not a rawlog\n";
  for (const auto& p : {dir / "empty.rawlog", dir / "text.rawlog", dir / "missing.rawlog", dir}) {
    const RunResult r = carenav({"rawlog", "info", p.string()});
    EXPECT_EQ(r.code, 2) << p;
    EXPECT_NE(r.err.find(p.string()), std::string::npos) << r.err;
  }
}

TEST(Cli, ProfileCheckAndShow) {
  for (const char* name : {"isr-aiwalker", "interbot", "hobbit"}) {
    const RunResult r = carenav({"profile", "check", kSrc + "/ini/" + name + ".ini"});
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("OK"), std::string::npos);
  }
  const RunResult show =
      carenav({"profile", "show", kSrc + "/ini/isr-aiwalker.ini", "--set", "robot.v_max=0.25"});
  ASSERT_EQ(show.code, 0) << show.err;
  EXPECT_NE(show.out.find("v_max = 0.25"), std::string::npos) << show.out;
  EXPECT_NE(show.out.find("safe_distance = 0.325"), std::string::npos);
  EXPECT_NE(show.out.find("[sensor.kinect]"), std::string::npos);

  // Sections a command reads with their defaults when the profile lacks them
  // are listed too, with every key.
  const RunResult defaults = carenav({"profile", "show", kSrc + "/ini/defaults.ini"});
  ASSERT_EQ(defaults.code, 0) << defaults.err;
  for (const std::string key :
       {"[icp]\n", "[rbpf]\n", "[localization]\n", "[navigation]\n",
        "\nmaxIterations = ", "\nparticles = ", "\nparticles_min = ", "\nglobal_particles = "})
    EXPECT_NE(defaults.out.find(key), std::string::npos) << key << defaults.out;
  EXPECT_NE(defaults.out.find("not in the profile"), std::string::npos);
}

TEST(Cli, ProfileErrorsExitTwoNamingTheKey) {
  const std::string walker = kSrc + "/ini/isr-aiwalker.ini";
  struct Case {
    std::vector<std::string> args;
    std::string expect;
  };
  for (const Case& c : std::vector<Case>{
           {{"--set", "robot.v_mx=0.2"}, "[robot] v_mx: unknown key (did you mean 'v_max'?)"},
           {{"--set", "robot.w_max=quick"}, "[robot] w_max: 'quick': not a number"},
           {{"--set", "robot.v_max=12"},
            "[robot] v_max: '12': out of range; allowed: a real number in [0, 3] m/s"},
           {{"--set", "sensor.kinect.width=-5"}, "[sensor.kinect] width"},
           {{"--set", "robot"}, "expected section.key=value"}}) {
    for (const char* verb : {"check", "show"}) {
      std::vector<std::string> args{"profile", verb, walker};
      args.insert(args.end(), c.args.begin(), c.args.end());
      const RunResult r = carenav(args);
      EXPECT_EQ(r.code, 2) << c.expect;
      EXPECT_NE(r.err.find(c.expect), std::string::npos) << r.err;
    }
  }
  const RunResult missing = carenav({"profile", "check", "/no/such/profile.ini"});
  EXPECT_EQ(missing.code, 2);
  EXPECT_NE(missing.err.find("/no/such/profile.ini: profile not found"), std::string::npos);

  const auto bad = scratch() / "misspelt.ini";
  std::ofstream(bad) << "[robot]\nvmax = 1\n";
  const RunResult r = carenav({"profile", "check", bad.string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(bad.string() + ":2: [robot] vmax: unknown key"), std::string::npos) << r.err;
}

TEST(Cli, DemoSummarisesTheSenaRawlogAndMapsIt) {
  const auto out = scratch() / "demo";
  const RunResult r = carenav({"demo", "--out", out.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("entries:            449"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("SENA"), std::string::npos);
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.out, m, std::regex("(\\d+) loop closures"))) << r.out;
  EXPECT_GT(std::stoi(m[1]), 0);
  for (const char* f : {"map.png", "map.yaml", "map.pgm", "map.gridmap.gz", "trajectory.tum"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  // Step 3: the map annotated with the SENA rooms and places, which fit it
  // (no problem against the map) and place the end of the loop in the south hall.
  EXPECT_NE(r.out.find("8 rooms, 5 places, 0 problems against the map"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("robot ends in:      South hall"), std::string::npos) << r.out;
  const std::string places = slurp(out / "map.places.yaml");
  EXPECT_NE(places.find("name: \"West hall\""), std::string::npos) << places;
  const std::string png = slurp(out / "map_places.png");
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_GT(png.size(), fs::file_size(out / "map.png") / 2);
  // Step 4: the walker pushed by a scripted user from the log's start to the
  // Dock in the simulator, on the map just built: reached, no collision.
  EXPECT_NE(r.out.find("walker to the Dock: reached (goal reached)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(", 0 collisions,"), std::string::npos) << r.out;
  const std::string walk = slurp(out / "walk" / "summary.json");
  EXPECT_NE(walk.find("\"success\": true"), std::string::npos) << walk;
  EXPECT_TRUE(fs::exists(out / "walk" / "run.png"));
  // The SLAM summary is still the SLAM summary.
  EXPECT_NE(slurp(out / "summary.json").find("loop_closures"), std::string::npos);
  // The annotated map answers `places where` like any other.
  const RunResult w =
      carenav({"places", "where", "--map", (out / "map.yaml").string(), "--", "-15,-5"});
  EXPECT_EQ(w.code, 0) << w.err;
  EXPECT_NE(w.out.find("West hall"), std::string::npos) << w.out;
  // Without MRPT's datasets the demo says what to install, exit 2.
  const RunResult none = shell("CARENAV_MRPT_DATASETS=/nonexistent " + quote(kBin) + " demo");
  EXPECT_EQ(none.code, 2);
  EXPECT_NE(none.err.find("mrpt-common"), std::string::npos) << none.err;
}
