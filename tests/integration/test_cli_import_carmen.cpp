// `carenav import carmen` on the real Intel and CSAIL logs, checked against
// the logs themselves (read with zcat/awk), carenav's `rawlog info` and MRPT's
// own `rawlog-edit --info`.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <regex>
#include <sstream>

#include "cli_helpers.h"

using namespace carenav_test;
namespace fs = std::filesystem;

namespace {
const std::string kIntel = kTestData + "/carmen/intel-corrected.log.gz";
const std::string kCsail = kTestData + "/carmen/csail-corrected.log.gz";

/** One number per line of a shell command's output. */
std::vector<double> numbers(const std::string& cmdline) {
  const RunResult r = shell(cmdline);
  EXPECT_EQ(r.code, 0) << cmdline << "\n" << r.err;
  std::vector<double> v;
  std::istringstream is(r.out);
  double x;
  while (is >> x) v.push_back(x);
  return v;
}

struct TumRow {
  double t, x, y;
};
std::vector<TumRow> readTumRows(const fs::path& p) {
  std::vector<TumRow> rows;
  std::istringstream is(slurp(p));
  std::string line;
  while (std::getline(is, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    TumRow r;
    ls >> r.t >> r.x >> r.y;
    rows.push_back(r);
  }
  return rows;
}

double mrptTimestamp(const std::string& out, const std::string& which) {
  std::smatch m;
  if (!std::regex_search(out, m, std::regex(which + " timestamp\\s*:\\s*([0-9.]+)"))) {
    ADD_FAILURE() << "no " << which << " timestamp in " << out;
    return 0;
  }
  return std::stod(m[1]);
}

uint64_t mrptSensorCount(const std::string& out, const std::string& label) {
  std::smatch m;
  if (!std::regex_search(out, m, std::regex(label + " /\\s*(\\d+) /"))) {
    ADD_FAILURE() << "no sensor " << label << " in " << out;
    return 0;
  }
  return std::stoull(m[1]);
}

void checkRealLog(const std::string& log, const std::string& name, uint64_t expected_scans) {
  ASSERT_TRUE(fs::exists(log)) << log;
  ASSERT_TRUE(fs::exists("/usr/bin/rawlog-edit")) << "install mrpt-apps (scripts/setup.sh)";
  // The log, read independently: laser lines, their timestamps and poses.
  const RunResult count = shell("zcat " + quote(log) + " | grep -c '^FLASER '");
  const uint64_t lasers = std::stoull(count.out);
  ASSERT_EQ(lasers, expected_scans);
  auto times = numbers("zcat " + quote(log) + " | awk '$1==\"FLASER\"{print $(NF-2)}'");
  auto xs = numbers("zcat " + quote(log) + " | awk '$1==\"FLASER\"{print $(NF-2), $(NF-8)}'");
  ASSERT_EQ(times.size(), lasers);

  const auto out = scratch() / (name + ".rawlog");
  const RunResult r = carenav({"import", "carmen", log, "--out", out.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("scans:        " + std::to_string(lasers)), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("NEFF lines (unknown message type)"), std::string::npos) << r.err;
  ASSERT_TRUE(fs::exists(out));
  EXPECT_FALSE(fs::exists(out.string() + ".tmp"));

  // carenav reads it back: one scan per laser line, one odometry reading each.
  const RunResult info = carenav({"rawlog", "info", "--json", out.string()});
  ASSERT_EQ(info.code, 0) << info.err;
  EXPECT_NE(info.out.find("\"format\": \"observations\""), std::string::npos);
  EXPECT_EQ(jsonNumber(info.out, "entries"), 2 * lasers);
  EXPECT_NE(info.out.find("\"label\": \"FLASER\",\n      \"class\": "
                          "\"mrpt::obs::CObservation2DRangeScan\",\n      \"count\": " +
                          std::to_string(lasers)),
            std::string::npos)
      << info.out;

  // MRPT reads it back: same counts, and the timestamps of the log to 1 us.
  const RunResult mrpt = shell("/usr/bin/rawlog-edit --info -i " + quote(out.string()));
  ASSERT_EQ(mrpt.code, 0) << mrpt.err;
  EXPECT_EQ(mrptSensorCount(mrpt.out, "FLASER"), lasers) << mrpt.out;
  EXPECT_EQ(mrptSensorCount(mrpt.out, "ODOMETRY"), lasers) << mrpt.out;
  EXPECT_NE(mrpt.out.find("Observations format               : Yes"), std::string::npos);
  const double tmin = *std::min_element(times.begin(), times.end());
  const double tmax = *std::max_element(times.begin(), times.end());
  EXPECT_NEAR(mrptTimestamp(mrpt.out, "Earliest"), tmin, 1e-6);
  EXPECT_NEAR(mrptTimestamp(mrpt.out, "Latest"), tmax, 1e-6);

  // The TUM file: one pose per laser line, the line's time and pose, by time.
  const auto rows = readTumRows(scratch() / (name + ".tum"));
  ASSERT_EQ(rows.size(), lasers);
  std::vector<std::pair<double, double>> tx;
  for (size_t i = 0; i < lasers; ++i) tx.emplace_back(xs[2 * i], xs[2 * i + 1]);
  std::stable_sort(tx.begin(), tx.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  for (size_t i = 0; i < lasers; ++i) {
    EXPECT_NEAR(rows[i].t, tx[i].first, 1e-6) << i;
    EXPECT_NEAR(rows[i].x, tx[i].second, 1e-6) << i;
  }
}
}  // namespace

TEST(CliImportCarmen, Help) {
  const RunResult r = carenav({"import", "carmen", "--help"});
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("Usage:"), std::string::npos);
  EXPECT_NE(r.out.find("--odometry"), std::string::npos);
  EXPECT_NE(r.out.find("--tum"), std::string::npos);
  EXPECT_EQ(carenav({"import", "carmen", kIntel}).code, 2);  // no --out
  EXPECT_EQ(carenav({"import", "carmen", kIntel, "--out", (scratch() / "x.rawlog").string(),
                     "--odometry", "wheels"})
                .code,
            2);
}

TEST(CliImportCarmen, IntelCorrected) { checkRealLog(kIntel, "intel", 910); }

TEST(CliImportCarmen, CsailCorrected) { checkRealLog(kCsail, "csail", 406); }

TEST(CliImportCarmen, OdometryFromOdomLinesTumPathAndJson) {
  const auto odom_lines = std::stoull(shell("zcat " + quote(kIntel) + " | grep -c '^ODOM '").out);
  ASSERT_GT(odom_lines, 1000u);
  const auto out = scratch() / "intel_odom.rawlog";
  const auto tum = scratch() / "reference.txt";
  const RunResult r = carenav({"-q", "import", "carmen", kIntel, "--out", out.string(),
                               "--odometry", "odom", "--tum", tum.string(), "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;  // -q: no notes
  EXPECT_EQ(jsonNumber(r.out, "odometry"), odom_lines);
  EXPECT_EQ(jsonNumber(r.out, "scans"), 910u);
  EXPECT_EQ(jsonNumber(r.out, "tum_poses"), 910u);
  EXPECT_TRUE(fs::exists(tum));
  EXPECT_FALSE(fs::exists(scratch() / "intel_odom.tum"));
  const RunResult mrpt = shell("/usr/bin/rawlog-edit --info -i " + quote(out.string()));
  EXPECT_EQ(mrptSensorCount(mrpt.out, "ODOMETRY"), odom_lines) << mrpt.out;

  const auto out2 = scratch() / "intel_notum.rawlog";
  const RunResult n = carenav({"import", "carmen", kIntel, "--out", out2.string(), "--no-tum"});
  ASSERT_EQ(n.code, 0) << n.err;
  EXPECT_FALSE(fs::exists(scratch() / "intel_notum.tum"));
}

TEST(CliImportCarmen, BadInputsExitTwoNamingFileAndLine) {
  // A log cut in the middle of a laser line (a killed logger): exit 2, the
  // line named, and everything before it converted and readable.
  const auto cut = scratch() / "cut.log";
  ASSERT_EQ(shell("zcat " + quote(kIntel) + " | head -c 200000 > " + quote(cut.string())).code, 0);
  const auto lines = shell("wc -l < " + quote(cut.string()));
  const uint64_t full_lines = std::stoull(lines.out);
  const auto out = scratch() / "cut.rawlog";
  RunResult r = carenav({"import", "carmen", cut.string(), "--out", out.string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(cut.string() + ":" + std::to_string(full_lines + 1) + ": FLASER: "),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("truncated"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("lines before it were converted"), std::string::npos) << r.err;
  const uint64_t scans_before = std::stoull(shell("head -n " + std::to_string(full_lines) + " " +
                                                  quote(cut.string()) + " | grep -c '^FLASER '")
                                                .out);
  const RunResult info = carenav({"rawlog", "info", "--json", out.string()});
  ASSERT_EQ(info.code, 0) << info.err;
  EXPECT_EQ(jsonNumber(info.out, "entries"), 2 * scans_before);

  // A malformed reading on the 5th laser line, in the middle: its line number, exit 2.
  const std::string bad_line = std::to_string(std::stoull(
      shell("zcat " + quote(kIntel) + " | grep -n -m 5 '^FLASER ' | tail -n 1 | cut -d: -f1").out));
  const auto mid = scratch() / "mid.log";
  ASSERT_EQ(shell("zcat " + quote(kIntel) + " | sed '" + bad_line +
                  "s/^FLASER 180 /FLASER 180 x/' > " + quote(mid.string()))
                .code,
            0);
  const auto mid_out = scratch() / "mid.rawlog";
  r = carenav({"import", "carmen", mid.string(), "--out", mid_out.string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(mid.string() + ":" + bad_line + ": FLASER: reading 0 is not a number"),
            std::string::npos)
      << r.err;
  const RunResult mid_info = carenav({"rawlog", "info", "--json", mid_out.string()});
  ASSERT_EQ(mid_info.code, 0) << mid_info.err;
  EXPECT_EQ(jsonNumber(mid_info.out, "entries"), 2u * 4);  // the 4 laser lines before it

  // Missing and empty files: exit 2, nothing written.
  r = carenav({"import", "carmen", (scratch() / "nope.log").string(), "--out",
               (scratch() / "nope.rawlog").string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("nope.log: CARMEN log not found"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(scratch() / "nope.rawlog"));
  const auto empty = scratch() / "empty.log";
  { std::ofstream(empty.string()); }
  r = carenav({"import", "carmen", empty.string(), "--out", (scratch() / "e.rawlog").string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("empty file"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(scratch() / "e.rawlog"));
}

// Real logs with lines stamped before the log's clock started (negative
// ipc_timestamp): those lines are skipped and counted, the rest converted,
// whatever the odometry source.
TEST(CliImportCarmen, NegativeTimestampsAreSkippedAndCounted) {
  for (const std::string name : {"acapulco", "infinite-corridor", "freiburg-campus"}) {
    const std::string log = kTestData + "/carmen/" + name + "-corrected.log.gz";
    ASSERT_TRUE(fs::exists(log)) << log;
    auto count = [&](const std::string& type, const std::string& cond) {
      return std::stoull(shell("zcat " + quote(log) + " | awk '$1==\"" + type + "\" && " + cond +
                               "{n++} END{print n+0}'")
                             .out);
    };
    const uint64_t lasers = count("FLASER", "1"), neg_lasers = count("FLASER", "$(NF-2)<0");
    const uint64_t neg_odom = count("ODOM", "$(NF-2)<0");
    ASSERT_GT(neg_lasers + neg_odom, 0u) << name;
    for (const std::string odo : {"auto", "none", "odom"}) {
      SCOPED_TRACE(name + " --odometry " + odo);
      const auto out = scratch() / (name + "-" + odo + ".rawlog");
      const RunResult r =
          carenav({"import", "carmen", log, "--out", out.string(), "--odometry", odo, "--json"});
      ASSERT_EQ(r.code, 0) << r.err;
      EXPECT_EQ(jsonNumber(r.out, "scans"), lasers - neg_lasers);
      EXPECT_GE(jsonNumber(r.out, "scans"), lasers * 99 / 100);  // most of the log
      std::smatch m;
      ASSERT_TRUE(std::regex_search(r.out, m, std::regex("\"negative_time\": \\{([^}]*)\\}")));
      const std::string neg = m[1];
      if (neg_odom)
        EXPECT_NE(neg.find("\"ODOM\": " + std::to_string(neg_odom)), std::string::npos) << neg;
      if (neg_lasers)
        EXPECT_NE(neg.find("\"FLASER\": " + std::to_string(neg_lasers)), std::string::npos) << neg;
      EXPECT_NE(r.err.find("with a negative ipc_timestamp"), std::string::npos) << r.err;
      const RunResult info = carenav({"rawlog", "info", "--json", out.string()});
      ASSERT_EQ(info.code, 0) << info.err;
    }
  }
}

// Real logs whose scanner wrote its no-return beams as about 51 m (below
// CARMEN's 80 m default): those readings become invalid beams and the summary
// says so; logs whose no-return value is beyond 80 m report none.
namespace {
double jsonReal(const std::string& json, const std::string& key) {
  std::smatch m;
  if (!std::regex_search(json, m, std::regex("\"" + key + "\": ([0-9.eE+-]+)"))) {
    ADD_FAILURE() << "no key " << key << " in " << json;
    return 0;
  }
  return std::stod(m[1]);
}
}  // namespace

TEST(CliImportCarmen, NoReturnValueOfRealLogs) {
  for (const std::string name : {"acapulco", "edmonton", "intel", "csail"}) {
    SCOPED_TRACE(name);
    const std::string log = kTestData + "/carmen/" + name + "-corrected.log.gz";
    const auto out = scratch() / (name + "-noret.rawlog");
    const RunResult r =
        carenav({"import", "carmen", log, "--out", out.string(), "--odometry", "none", "--json"});
    ASSERT_EQ(r.code, 0) << r.err;
    const bool piled = name == "acapulco" || name == "edmonton";
    EXPECT_EQ(r.out.find("\"limit_m\"") != std::string::npos, piled) << r.out;
    EXPECT_EQ(r.err.find("no-return value") != std::string::npos, piled) << r.err;
    if (!piled) continue;
    EXPECT_NEAR(jsonReal(r.out, "level_m"), 51.15, 0.01);
    EXPECT_NEAR(jsonReal(r.out, "limit_m"), 49.61, 0.01);
    EXPECT_GT(jsonNumber(r.out, "readings"), 3000);
  }
}
