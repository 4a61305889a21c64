// `carenav eval` on trajectories the tests write, and on the SLAM-corrected
// reference of the Intel Research Lab log (tests/data/carmen).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>

#include "cli_helpers.h"

using namespace carenav_test;
namespace fs = std::filesystem;

namespace {

const std::string kIntel = kTestData + "/carmen/intel-corrected.log.gz";

fs::path dirFor(const std::string& name) {
  const fs::path d = scratch() / ("eval_" + name);
  fs::create_directories(d);
  return d;
}

std::string writeFile(const fs::path& p, const std::string& text) {
  std::ofstream(p, std::ios::binary) << text;
  return p.string();
}

/** The number after the last key of a path of keys, each searched after the
 *  previous one: jsonAt(j, {"ate", "translation_m", "rmse"}). NaN if absent. */
double jsonAt(const std::string& json, const std::vector<std::string>& keys) {
  size_t pos = 0;
  for (const auto& k : keys) {
    pos = json.find("\"" + k + "\":", pos);
    if (pos == std::string::npos) {
      ADD_FAILURE() << "no key " << k << " in " << json;
      return std::nan("");
    }
    pos += k.size() + 3;
  }
  std::smatch m;
  const std::string rest = json.substr(pos, 40);
  if (!std::regex_search(rest, m, std::regex("^\\s*(-?[0-9.eE+-]+)"))) {
    ADD_FAILURE() << "no number after " << keys.back() << ": " << rest;
    return std::nan("");
  }
  return std::stod(m[1]);
}

/** A PNG: signature, IHDR first, IEND last; returns its width (0 if not). */
uint32_t pngWidth(const fs::path& p) {
  const std::string b = slurp(p);
  if (b.size() < 45 || b.compare(0, 8, "\x89PNG\r\n\x1a\n") != 0 || b.compare(12, 4, "IHDR") != 0 ||
      b.compare(b.size() - 8, 4, "IEND") != 0)
    return 0;
  const auto u = [&](size_t i) { return static_cast<uint32_t>(static_cast<unsigned char>(b[i])); };
  return (u(16) << 24) | (u(17) << 16) | (u(18) << 8) | u(19);
}

/** TUM reference from the Intel log's corrected poses (FLASER n r1..rn x y
 *  theta odom_x odom_y odom_theta timestamp ...), sorted by time: the log has
 *  four timestamps that step back a little. */
std::string intelReference(const fs::path& dir, bool sorted = true) {
  const std::string out = (dir / (sorted ? "intel_ref.tum" : "intel_unsorted.tum")).string();
  const RunResult r = shell(
      "zcat " + quote(kIntel) +
      " | awk '$1==\"FLASER\" {n=$2; th=$(n+5); printf \"%.6f %.6f %.6f 0 0 0 %.9f %.9f\\n\", "
      "$(n+9), $(n+3), $(n+4), sin(th/2), cos(th/2)}'" +
      (sorted ? " | sort -g -k1,1" : "") + " > " + quote(out));
  EXPECT_EQ(r.code, 0) << r.err;
  return out;
}

/** The reference moved by (x, y, yaw) = (3, -1, 0.5 rad), each position
 *  pushed 5 cm in a direction that turns by 2.4 rad per pose, `dt` added to
 *  the times. */
std::string perturb(const std::string& ref, const fs::path& out, double dt = 0.003) {
  const RunResult r =
      shell("awk -v dt=" + std::to_string(dt) +
            " 'BEGIN {c=cos(0.5); s=sin(0.5)} {th=2*atan2($7,$8)+0.5; x=$2+0.05*cos(NR*2.4); "
            "y=$3+0.05*sin(NR*2.4); printf \"%.6f %.6f %.6f 0 0 0 %.9f %.9f\\n\", $1+dt, "
            "c*x-s*y+3, s*x+c*y-1, sin(th/2), cos(th/2)}' " +
            quote(ref) + " > " + quote(out.string()));
  EXPECT_EQ(r.code, 0) << r.err;
  return out.string();
}

}  // namespace

TEST(CliEval, HelpAndUsageErrors) {
  const RunResult h = carenav({"eval", "--help"});
  EXPECT_EQ(h.code, 0);
  EXPECT_NE(h.out.find("Usage:"), std::string::npos);
  EXPECT_NE(h.out.find("--relations"), std::string::npos);
  EXPECT_EQ(carenav({"eval"}).code, 2);  // no --est
  const fs::path d = dirFor("usage");
  const std::string t = writeFile(d / "t.tum", "0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n");
  EXPECT_EQ(carenav({"eval", "--est", t}).code, 2);  // nothing to compare with
  EXPECT_EQ(carenav({"eval", "--est", t, "--ref", t, "--max-dt", "x"}).code, 2);
  EXPECT_EQ(carenav({"eval", "--est", t, "--ref", t, "--rpe-dist", "1,-5"}).code, 2);
  EXPECT_EQ(carenav({"eval", "--est", t, "--ref", t}).code, 0);
}

TEST(CliEval, IntelPerturbedReference) {
  const fs::path d = dirFor("intel");
  const std::string ref = intelReference(d);
  const std::string est = perturb(ref, d / "est.tum");
  const fs::path out = d / "out";
  const RunResult r = carenav({"eval", "--est", est, "--ref", ref, "--out", out.string(), "--json",
                               "--rpe-dist", "1,5,10"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(jsonAt(r.out, {"estimate", "poses"}), 910);
  EXPECT_EQ(jsonAt(r.out, {"association", "matched"}), 910);
  // The alignment undoes the known transform and leaves the 5 cm pushes.
  EXPECT_NEAR(jsonAt(r.out, {"alignment", "yaw_deg"}), -0.5 * 180 / M_PI, 0.1);
  EXPECT_NEAR(jsonAt(r.out, {"ate", "translation_m", "rmse"}), 0.05, 0.002);
  EXPECT_NEAR(jsonAt(r.out, {"ate", "translation_m", "max"}), 0.05, 0.005);
  EXPECT_LT(jsonAt(r.out, {"ate", "rotation_deg", "mean"}), 0.1);
  EXPECT_EQ(jsonAt(r.out, {"rpe", "delta_m"}), 1);
  EXPECT_GT(jsonAt(r.out, {"rpe", "pairs"}), 800);
  // Two independent 5 cm pushes: relative errors of 0 .. 10 cm.
  EXPECT_LT(jsonAt(r.out, {"rpe", "translation_m", "max"}), 0.1 + 1e-3);

  EXPECT_EQ(slurp(out / "eval.json"), r.out);
  EXPECT_EQ(pngWidth(out / "trajectories.png"), 1000u);
  EXPECT_EQ(pngWidth(out / "ate.png"), 1000u);
  ASSERT_TRUE(fs::exists(out / "estimate_aligned.tum"));
  // The saved aligned estimate lies on the reference: ATE without alignment.
  const RunResult again = carenav({"eval", "--est", (out / "estimate_aligned.tum").string(),
                                   "--ref", ref, "--json", "--no-align"});
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_NEAR(jsonAt(again.out, {"ate", "translation_m", "rmse"}), 0.05, 0.002);

  // Without the alignment the transform is all error.
  const RunResult raw = carenav({"eval", "--est", est, "--ref", ref, "--json", "--no-align"});
  ASSERT_EQ(raw.code, 0) << raw.err;
  EXPECT_GT(jsonAt(raw.out, {"ate", "translation_m", "rmse"}), 3.0);
  EXPECT_NEAR(jsonAt(raw.out, {"ate", "rotation_deg", "mean"}), 0.5 * 180 / M_PI, 0.01);

  // Text output names the sections.
  const RunResult text = carenav({"eval", "--est", est, "--ref", ref});
  ASSERT_EQ(text.code, 0) << text.err;
  EXPECT_NE(text.out.find("ATE (absolute trajectory error)"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("matched     910 of 910"), std::string::npos) << text.out;
}

TEST(CliEval, IntelRelationsMadeFromTheReference) {
  const fs::path d = dirFor("relations");
  const std::string ref = intelReference(d);
  const std::string rel = (d / "intel.relations").string();
  const RunResult mk = carenav({"eval", "--ref", ref, "--make-relations", rel, "--rel-dist", "2"});
  ASSERT_EQ(mk.code, 0) << mk.err;
  ASSERT_TRUE(fs::exists(rel));

  // The reference itself scores (almost) zero; the file holds 6 decimals.
  const RunResult self = carenav({"eval", "--est", ref, "--relations", rel, "--json"});
  ASSERT_EQ(self.code, 0) << self.err;
  EXPECT_GT(jsonAt(self.out, {"relations", "total"}), 800);
  EXPECT_EQ(jsonAt(self.out, {"relations", "used"}), jsonAt(self.out, {"relations", "total"}));
  EXPECT_LT(jsonAt(self.out, {"relations", "translation_m", "mean"}), 1e-4);

  // The perturbed estimate: relative errors between 0 and 10 cm; the
  // relations metric needs no --ref and ignores the global transform.
  const std::string est = perturb(ref, d / "est.tum", 0.0);
  const RunResult r = carenav({"eval", "--est", est, "--relations", rel, "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const double mean = jsonAt(r.out, {"relations", "translation_m", "mean"});
  EXPECT_GT(mean, 0.03);
  EXPECT_LT(mean, 0.1);
  EXPECT_NEAR(jsonAt(r.out, {"relations", "translation_sq_m2", "mean"}),
              std::pow(jsonAt(r.out, {"relations", "translation_m", "mean"}), 2) +
                  std::pow(jsonAt(r.out, {"relations", "translation_m", "std"}), 2),
              1e-6);
  EXPECT_NE(r.out.find("\"ate\": null"), std::string::npos);
}

TEST(CliEval, RpeOfAWrittenTrajectoryWithScaleDrift) {
  const fs::path d = dirFor("drift");
  std::string ref, est;
  for (int k = 0; k <= 100; ++k) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "%d.0 %.6f 0 0 0 0 0 1\n", 100 + k, 0.25 * k);
    ref += buf;
    std::snprintf(buf, sizeof buf, "%d.0 %.6f 0 0 0 0 0 1\n", 100 + k, 0.25 * 1.02 * k);
    est += buf;
  }
  const RunResult r = carenav({"eval", "--est", writeFile(d / "est.tum", est), "--ref",
                               writeFile(d / "ref.tum", ref), "--json", "--rpe-dist", "1,5"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NEAR(jsonAt(r.out, {"rpe", "delta_m"}), 1, 1e-9);
  EXPECT_NEAR(jsonAt(r.out, {"rpe", "translation_m", "mean"}), 0.02, 1e-5);
  EXPECT_NEAR(jsonAt(r.out, {"rpe", "drift_percent"}), 2.0, 1e-3);
  EXPECT_NEAR(jsonAt(r.out, {"rpe", "delta_m", "delta_m"}), 5, 1e-9);  // second entry
  EXPECT_NEAR(jsonAt(r.out, {"rpe", "delta_m", "delta_m", "translation_m", "mean"}), 0.1, 1e-5);
  EXPECT_NEAR(jsonAt(r.out, {"rpe_step", "translation_m", "mean"}), 0.005, 1e-5);
}

TEST(CliEval, TimestampsThatDoNotOverlapExit2WithBothRanges) {
  const fs::path d = dirFor("overlap");
  const std::string ref = intelReference(d);
  const std::string est = perturb(ref, d / "late.tum", 10000.0);
  const fs::path out = d / "out";
  const RunResult r = carenav({"eval", "--est", est, "--ref", ref, "--out", out.string()});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("do not overlap"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("t = 32.906800 .. 2683.770000 s"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("t = 10032.906800 .. 12683.770000 s"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out / "eval.json"));  // nothing was computed
  // A larger --max-dt does not help; the message says which rule was used.
  EXPECT_NE(carenav({"eval", "--est", est, "--ref", ref, "--max-dt", "1"}).err.find("within 1 s"),
            std::string::npos);
}

TEST(CliEval, PartialResultsAreKeptWhenTheRelationsDoNotOverlap) {
  const fs::path d = dirFor("partial");
  const std::string ref = intelReference(d);
  const std::string est = perturb(ref, d / "est.tum");
  const std::string rel = writeFile(d / "far.relations", "1 2 1 0 0 0 0 0\n");
  const fs::path out = d / "out";
  const RunResult r =
      carenav({"eval", "--est", est, "--ref", ref, "--relations", rel, "--out", out.string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("far.relations"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("ATE"), std::string::npos) << r.out;  // ATE still printed
  EXPECT_TRUE(fs::exists(out / "eval.json"));
  EXPECT_EQ(pngWidth(out / "trajectories.png"), 1000u);
}

TEST(CliEval, IntelLogInFileOrderIsSortedWithANote) {
  // The raw Intel log has timestamps that step back: the estimate is sorted
  // by time, the user told, and the result equals the sorted file's.
  const fs::path d = dirFor("unsorted");
  const std::string unsorted = intelReference(d, false);
  const std::string sorted = intelReference(d);
  const RunResult r = carenav({"eval", "--est", unsorted, "--ref", sorted, "--json"});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find(unsorted + ": 4 timestamps step back"), std::string::npos) << r.err;
  const RunResult s = carenav({"eval", "--est", sorted, "--ref", sorted, "--json"});
  // Same numbers (the file names differ).
  const auto tail = [](const std::string& j) { return j.substr(j.find("\"association\"")); };
  EXPECT_EQ(tail(r.out), tail(s.out));
}

TEST(CliEval, MalformedFilesExit2NamingFileAndLine) {
  const fs::path d = dirFor("malformed");
  const std::string good =
      writeFile(d / "good.tum", "0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n2 2 0 0 0 0 0 1\n");
  struct Case {
    const char* name;
    std::string text;
    std::string expect;  // after the path
  };
  const std::vector<Case> tum_cases = {
      {"empty.tum", "", ": no poses"},
      {"garbage.tum", "GARBAGE\n", ":1: expected 8 numbers"},
      {"columns.tum", "0 0 0 0 0 0 0 1\n1 1 0 0\n", ":2: expected 8 numbers"},
      {"truncated.tum", "0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0.", ":2: expected 8 numbers"},
      {"binary.tum", std::string("\x1f\x8b\x08\x00\x00\x00", 6), ":1: expected 8 numbers"},
  };
  for (const auto& c : tum_cases) {
    const std::string p = writeFile(d / c.name, c.text);
    for (const auto& args : {std::vector<std::string>{"eval", "--est", p, "--ref", good},
                             std::vector<std::string>{"eval", "--est", good, "--ref", p}}) {
      const RunResult r = carenav(args);
      EXPECT_EQ(r.code, 2) << c.name;
      EXPECT_NE(r.err.find(p + c.expect), std::string::npos) << c.name << ": " << r.err;
    }
  }
  const std::vector<Case> rel_cases = {
      {"empty.relations", "", ": no relations"},
      {"garbage.relations", "t1 t2 x y z roll pitch yaw\n", ":1: expected 8 numbers"},
      {"columns.relations", "# c\n0 1 1 0 0 0\n", ":2: expected 8 numbers"},
      {"truncated.relations", "0 1 1 0 0 0 0 0\n1 2 1", ":2: expected 8 numbers"},
  };
  for (const auto& c : rel_cases) {
    const std::string p = writeFile(d / c.name, c.text);
    const RunResult r = carenav({"eval", "--est", good, "--relations", p});
    EXPECT_EQ(r.code, 2) << c.name;
    EXPECT_NE(r.err.find(p + c.expect), std::string::npos) << c.name << ": " << r.err;
  }
  const RunResult missing = carenav({"eval", "--est", (d / "nope.tum").string(), "--ref", good});
  EXPECT_EQ(missing.code, 2);
  EXPECT_NE(missing.err.find("nope.tum: cannot open"), std::string::npos) << missing.err;
  // An output directory that cannot be made.
  const std::string file_not_dir = writeFile(d / "plainfile", "x");
  const RunResult o =
      carenav({"eval", "--est", good, "--ref", good, "--out", file_not_dir + "/sub"});
  EXPECT_EQ(o.code, 2) << o.err;
  EXPECT_NE(
      o.err.find("--out " + file_not_dir + "/sub: " + file_not_dir + " is a file, not a folder"),
      std::string::npos)
      << o.err;
}

// Trajectories whose timestamps all repeat (one pose per scan of a log
// stamped with one time): by time only one pair matches, and the message
// says why; --by-index pairs the k-th poses.
TEST(CliEval, RepeatedTimestampsNeedByIndexAndItPairsByOrder) {
  const fs::path d = dirFor("by_index");
  std::string ref_text, est_text, short_text;
  for (int k = 0; k < 50; ++k) {
    const double x = 0.2 * k, y = 0.1 * k;
    ref_text += "5 " + std::to_string(x) + " " + std::to_string(y) + " 0 0 0 0 1\n";
    // The estimate: the same path shifted by 1 m (alignment removes it), every
    // pose 1 cm off in y, alternately up and down (alignment cannot remove it).
    est_text += "5 " + std::to_string(x + 1) + " " + std::to_string(y + (k % 2 ? 0.01 : -0.01)) +
                " 0 0 0 0 1\n";
    if (k < 40) short_text += "5 0 0 0 0 0 0 1\n";
  }
  const std::string ref = writeFile(d / "ref.tum", ref_text);
  const std::string est = writeFile(d / "est.tum", est_text);
  const std::string shorter = writeFile(d / "short.tum", short_text);
  RunResult r = carenav({"eval", "--est", est, "--ref", ref});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("do not tell the poses apart"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("49 repeat the time before"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--by-index"), std::string::npos) << r.err;

  r = carenav({"eval", "--est", est, "--ref", ref, "--by-index", "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(jsonNumber(r.out, "matched"), 50u);
  std::smatch m;  // the first rmse: the ATE's translation
  ASSERT_TRUE(std::regex_search(r.out, m, std::regex("\"rmse\": ([-0-9.eE+]+)"))) << r.out;
  const double rmse = std::stod(m[1]);
  EXPECT_LT(rmse, 0.0105);
  EXPECT_GT(rmse, 0.005);
  r = carenav({"eval", "--est", est, "--ref", ref, "--by-index"});
  EXPECT_NE(r.out.find("(by index)"), std::string::npos) << r.out;

  r = carenav({"eval", "--est", shorter, "--ref", ref, "--by-index"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("as many estimated as reference poses"), std::string::npos) << r.err;
  EXPECT_EQ(carenav({"eval", "--est", est, "--ref", ref, "--by-index", "--interpolate"}).code, 2);
}
