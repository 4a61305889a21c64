// The evaluation job of `carenav eval`, called as a library: metrics, its JSON
// and outputs, and a stage's bad input kept for the end.
#include <carenav/common/json.h>
#include <carenav/io/trajectory.h>
#include <carenav/slam/eval_job.h>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include <unistd.h>

namespace fs = std::filesystem;
using namespace carenav;

namespace {

fs::path scratch(const std::string& name) {
  const fs::path d =
      fs::temp_directory_path() / ("carenav_eval_job_" + std::to_string(getpid())) / name;
  fs::create_directories(d);
  return d;
}

/** A curve and the same curve moved by (x 1, y -2, yaw 30 deg). */
void writePair(const fs::path& d) {
  io::Trajectory2D ref, est;
  const double c = std::cos(M_PI / 6), s = std::sin(M_PI / 6);
  for (int k = 0; k < 100; ++k) {
    const double t = 0.1 * k, x = 0.1 * k, y = std::sin(0.1 * k);
    ref.push_back({t, x, y, 0.05 * k});
    est.push_back({t, c * x - s * y + 1, s * x + c * y - 2, 0.05 * k + M_PI / 6});
  }
  io::writeTum((d / "ref.tum").string(), ref);
  io::writeTum((d / "est.tum").string(), est);
}

}  // namespace

TEST(EvalJob, AlignedAteOfAMovedCopyIsZeroAndTheJsonKeepsItsOrder) {
  const fs::path d = scratch("moved");
  writePair(d);
  slam::EvalJobOptions o;
  o.est = (d / "est.tum").string();
  o.ref = (d / "ref.tum").string();
  o.out_dir = (d / "out").string();
  o.progress = false;
  const slam::EvalJobResult r = slam::runEvalJob(o);
  ASSERT_TRUE(r.ate);
  EXPECT_FALSE(r.error);
  EXPECT_LT(r.ate->translation.rmse, 1e-6);
  EXPECT_NEAR(std::abs(r.ate->alignment.phi), M_PI / 6, 1e-6);
  ASSERT_EQ(r.rpe.size(), 2u);  // 1 m and 5 m
  const Json j = parseJson(r.toJson(o), "eval.json");
  std::vector<std::string> keys;
  for (const auto& [k, v] : j.items()) keys.push_back(k);
  EXPECT_EQ(keys, (std::vector<std::string>{"estimate", "reference", "association", "alignment",
                                            "ate", "rpe_step", "rpe", "relations", "outputs"}));
  EXPECT_TRUE(j.at("relations").is_null());
  EXPECT_EQ(j.at("association").at("matched").get<size_t>(), 100u);
  EXPECT_EQ(j.at("outputs").size(), 4u);
  for (const auto& f : j.at("outputs")) EXPECT_TRUE(fs::exists(f.get<std::string>())) << f;
  // Without the alignment the offset is the error.
  o.align = false;
  o.out_dir.clear();
  EXPECT_GT(slam::runEvalJob(o).ate->translation.rmse, 1.0);
}

TEST(EvalJob, RelationsOutsideTheEstimateAreKeptForTheEndWithTheAte) {
  const fs::path d = scratch("relations");
  writePair(d);
  slam::EvalJobOptions o;
  o.ref = (d / "ref.tum").string();
  o.make_relations = (d / "ref.relations").string();
  o.progress = false;
  // Only the relations file: nothing to evaluate.
  EXPECT_FALSE(slam::runEvalJob(o).computed());
  ASSERT_TRUE(fs::exists(o.make_relations));
  // An estimate shifted in time: its poses pair with no relation, the ATE
  // (nearest within 2 s) still works.
  io::Trajectory2D est = io::readTum((d / "est.tum").string());
  for (auto& p : est) p.t += 1000;
  io::Trajectory2D ref = io::readTum(o.ref);
  for (auto& p : ref) p.t += 1000;
  io::writeTum((d / "late_est.tum").string(), est);
  io::writeTum((d / "late_ref.tum").string(), ref);
  o.est = (d / "late_est.tum").string();
  o.ref = (d / "late_ref.tum").string();
  o.relations = o.make_relations;
  o.make_relations.clear();
  const slam::EvalJobResult r = slam::runEvalJob(o);
  EXPECT_TRUE(r.ate);
  EXPECT_FALSE(r.rel);
  ASSERT_TRUE(r.error);
  EXPECT_NE(std::string(r.error->what()).find(o.est + " vs " + o.relations), std::string::npos)
      << r.error->what();
}
