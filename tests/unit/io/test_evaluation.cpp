// Trajectory evaluation: association, SE(2) alignment, ATE, RPE, relations.
#include <carenav/common/errors.h>
#include <carenav/io/evaluation.h>
#include <carenav/io/trajectory.h>

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

using namespace carenav;
using namespace carenav::io;
using io::TimedPose2D;
using io::Trajectory2D;
using mrpt::math::TPose2D;
namespace fs = std::filesystem;

namespace {

constexpr double kDeg = M_PI / 180.0;

fs::path scratch() {
  auto d = fs::temp_directory_path() / ("carenav_eval_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

std::string writeText(const std::string& name, const std::string& text) {
  const auto p = (scratch() / name).string();
  std::ofstream(p, std::ios::binary) << text;
  return p;
}

/** A curvy closed-ish path, 10 Hz, yaw along the tangent. */
Trajectory2D curvyPath(size_t n = 400, double t0 = 1000.0) {
  Trajectory2D t;
  for (size_t k = 0; k < n; ++k) {
    const double s = 0.02 * k;
    TimedPose2D p;
    p.t = t0 + 0.1 * k;
    p.x = 6 * std::cos(s) + 0.5 * s;
    p.y = 3 * std::sin(2 * s);
    p.yaw = std::atan2(6 * std::cos(2 * s), -6 * std::sin(s) + 0.5);
    t.push_back(p);
  }
  return t;
}

/** Straight line along x, `step` metres apart, 1 s apart. */
Trajectory2D line(size_t n, double step) {
  Trajectory2D t;
  for (size_t k = 0; k < n; ++k) t.push_back({static_cast<double>(k), step * k, 0.0, 0.0});
  return t;
}

/** InputError's message, or "" when none was thrown. */
template <class F>
std::string inputError(F f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

// ---------------------------------------------------------------- alignment

TEST(Evaluation, AlignmentRecoversAKnownTransform) {
  const Trajectory2D ref = curvyPath();
  const TPose2D T(3.0, -2.0, 40 * kDeg);
  const Trajectory2D est = transformTrajectory(ref, T);  // est = T ⊕ ref

  const TPose2D A = alignSE2(est, ref);  // should be T⁻¹
  const Trajectory2D back = transformTrajectory(est, A);
  for (size_t k = 0; k < ref.size(); ++k) {
    EXPECT_NEAR(back[k].x, ref[k].x, 1e-9);
    EXPECT_NEAR(back[k].y, ref[k].y, 1e-9);
    EXPECT_NEAR(wrapAngle(back[k].yaw - ref[k].yaw), 0, 1e-9);
  }
  EXPECT_NEAR(A.phi, -40 * kDeg, 1e-12);
  const double c = std::cos(T.phi), s = std::sin(T.phi);  // T⁻¹ translation = -Rᵀ t
  EXPECT_NEAR(A.x, -(c * T.x + s * T.y), 1e-9);
  EXPECT_NEAR(A.y, -(-s * T.x + c * T.y), 1e-9);

  const Association a = associate(est, ref);
  ASSERT_EQ(a.size(), ref.size());
  const AteResult aligned = computeAte(a, true);
  EXPECT_LT(aligned.translation.rmse, 1e-9);
  EXPECT_LT(aligned.rotation.max, 1e-6);
  const AteResult raw = computeAte(a, false);
  EXPECT_GT(raw.translation.rmse, 2.0);
  EXPECT_NEAR(raw.rotation.mean, 40.0, 1e-6);
  EXPECT_FALSE(raw.aligned);
  EXPECT_EQ(raw.alignment.x, 0);
}

TEST(Evaluation, AlignmentWithoutRotationInformation) {
  // All estimated positions coincide: no rotation can be told; shift only.
  Trajectory2D est{{0, 1, 1, 0}, {1, 1, 1, 0}}, ref{{0, 0, 0, 0}, {1, 2, 0, 0}};
  const TPose2D A = alignSE2(est, ref);
  EXPECT_EQ(A.phi, 0);
  EXPECT_NEAR(A.x, 0, 1e-12);  // centroid (1,1) -> (1,0)
  EXPECT_NEAR(A.y, -1, 1e-12);
}

// ---------------------------------------------------------------- ATE

TEST(Evaluation, AteOfAKnownConstantOffsetIsExact) {
  const Trajectory2D ref = curvyPath();
  Trajectory2D est = ref;
  for (size_t k = 0; k < est.size(); ++k) {
    const double dir = 2.399963 * k;  // golden angle: directions spread evenly
    est[k].x += 0.1 * std::cos(dir);
    est[k].y += 0.1 * std::sin(dir);
    est[k].yaw += 2 * kDeg;
  }
  const AteResult r = computeAte(associate(est, ref), false);
  EXPECT_NEAR(r.translation.rmse, 0.1, 1e-9);
  EXPECT_NEAR(r.translation.mean, 0.1, 1e-9);
  EXPECT_NEAR(r.translation.median, 0.1, 1e-9);
  EXPECT_NEAR(r.translation.max, 0.1, 1e-9);
  EXPECT_NEAR(r.translation.std, 0, 1e-9);
  EXPECT_NEAR(r.rotation.mean, 2.0, 1e-9);
  EXPECT_EQ(r.trans_errors.size(), ref.size());
  // The alignment can only make the fit better, and cannot absorb noise.
  const AteResult al = computeAte(associate(est, ref), true);
  EXPECT_LE(al.translation.rmse, 0.1 + 1e-12);
  EXPECT_GT(al.translation.rmse, 0.09);
}

TEST(Evaluation, AteOfGaussianNoiseMatchesItsSigma) {
  const Trajectory2D ref = curvyPath(2000);
  const TPose2D T(-4.0, 7.0, -120 * kDeg);
  Trajectory2D est = transformTrajectory(ref, T);
  std::mt19937 rng(42);
  std::normal_distribution<double> n(0.0, 0.05);
  for (auto& p : est) p.x += n(rng), p.y += n(rng);
  const AteResult r = computeAte(associate(est, ref), true);
  // 2D isotropic noise of sigma per axis: RMSE of the distance = sigma * sqrt(2).
  EXPECT_NEAR(r.translation.rmse, 0.05 * std::sqrt(2.0), 0.005);
  EXPECT_NEAR(r.alignment.phi, 120 * kDeg, 0.01);
  EXPECT_GT(computeAte(associate(est, ref), false).translation.rmse, 5.0);
}

TEST(Evaluation, ErrorStats) {
  const ErrorStats s = ErrorStats::of({4, 1, 3, 2});
  EXPECT_EQ(s.n, 4u);
  EXPECT_DOUBLE_EQ(s.mean, 2.5);
  EXPECT_DOUBLE_EQ(s.median, 2.5);
  EXPECT_DOUBLE_EQ(s.min, 1);
  EXPECT_DOUBLE_EQ(s.max, 4);
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(30.0 / 4));
  EXPECT_DOUBLE_EQ(s.std, std::sqrt(1.25));
  EXPECT_DOUBLE_EQ(ErrorStats::of({5, 1, 3}).median, 3);
  const ErrorStats e = ErrorStats::of({});
  EXPECT_EQ(e.n, 0u);
  EXPECT_TRUE(std::isnan(e.rmse));
  EXPECT_TRUE(std::isnan(e.max));
}

// ---------------------------------------------------------------- RPE

TEST(Evaluation, RpeOfAConstantScaleDriftPerMetre) {
  const Trajectory2D ref = line(101, 0.25);  // 25 m
  Trajectory2D est = ref;
  for (auto& p : est) p.x *= 1.02;  // 2 cm too far per metre
  const Association a = associate(est, ref);

  const RpeResult r1 = computeRpe(a, 1.0);
  EXPECT_EQ(r1.translation.n, 97u);  // i = 0..96, j = i + 4
  EXPECT_NEAR(r1.translation.rmse, 0.02, 1e-9);
  EXPECT_NEAR(r1.translation.mean, 0.02, 1e-9);
  EXPECT_NEAR(r1.translation.max, 0.02, 1e-9);
  EXPECT_NEAR(r1.drift_percent, 2.0, 1e-7);
  EXPECT_NEAR(r1.rotation.mean, 0, 1e-9);

  const RpeResult r5 = computeRpe(a, 5.0);
  EXPECT_EQ(r5.translation.n, 81u);
  EXPECT_NEAR(r5.translation.mean, 0.1, 1e-9);
  EXPECT_NEAR(r5.drift_percent, 2.0, 1e-7);

  const RpeResult step = computeRpe(a, 0);
  EXPECT_EQ(step.translation.n, 100u);
  EXPECT_NEAR(step.translation.mean, 0.005, 1e-9);

  // Longer than the path: no pairs, no numbers.
  const RpeResult none = computeRpe(a, 100.0);
  EXPECT_EQ(none.translation.n, 0u);
  EXPECT_TRUE(std::isnan(none.translation.rmse));
}

TEST(Evaluation, RpeOfAConstantHeadingDriftPerMetre) {
  const Trajectory2D ref = line(101, 0.25);
  Trajectory2D est = ref;
  for (auto& p : est) p.yaw = 1.0 * kDeg * p.x;  // 1 deg of heading error per metre
  const Association a = associate(est, ref);
  EXPECT_NEAR(computeRpe(a, 1.0).rotation.mean, 1.0, 1e-9);
  EXPECT_NEAR(computeRpe(a, 1.0).rot_drift_deg_per_m, 1.0, 1e-9);
  EXPECT_NEAR(computeRpe(a, 5.0).rotation.mean, 5.0, 1e-9);
  EXPECT_NEAR(computeRpe(a, 5.0).rotation.max, 5.0, 1e-9);
}

TEST(Evaluation, RpeIgnoresAGlobalTransform) {
  const Trajectory2D ref = curvyPath();
  const Association a = associate(transformTrajectory(ref, TPose2D(10, 20, 1.0)), ref);
  for (double d : {0.0, 1.0, 5.0}) {
    const RpeResult r = computeRpe(a, d);
    EXPECT_GT(r.translation.n, 10u);
    EXPECT_LT(r.translation.max, 1e-9) << d;
    EXPECT_LT(r.rotation.max, 1e-6) << d;
  }
}

// ---------------------------------------------------------------- association

TEST(Evaluation, AssociationWithTimestampOffsets) {
  const Trajectory2D ref = curvyPath(100);
  Trajectory2D est = ref;
  for (auto& p : est) p.t += 0.005;  // within the default 0.02 s
  Association a = associate(est, ref);
  EXPECT_EQ(a.size(), 100u);
  EXPECT_EQ(a.est_index[7], 7u);
  EXPECT_DOUBLE_EQ(a.ref[7].x, ref[7].x);
  EXPECT_DOUBLE_EQ(a.ref[7].t, est[7].t);  // pairs carry the estimate's time

  // Half the estimate before the reference starts: only the overlap matches.
  Trajectory2D early = ref;
  for (auto& p : early) p.t -= 5.0;
  EXPECT_EQ(associate(early, ref).size(), 50u);

  // Offset by more than max-dt: nothing matches; the message gives both ranges.
  for (auto& p : est) p.t += 0.04;
  const std::string msg = inputError([&] { associate(est, ref); });
  EXPECT_NE(msg.find("do not overlap"), std::string::npos) << msg;
  EXPECT_NE(msg.find("1000.000000 .. 1009.900000"), std::string::npos) << msg;
  EXPECT_NE(msg.find("1000.045000 .. 1009.945000"), std::string::npos) << msg;
  AssociationParams loose;
  loose.max_dt = 0.05;
  EXPECT_EQ(associate(est, ref, loose).size(), 100u);

  // Disjoint times.
  Trajectory2D later = ref;
  for (auto& p : later) p.t += 1000;
  EXPECT_NE(inputError([&] { associate(later, ref); }).find("do not overlap"), std::string::npos);
  EXPECT_NE(inputError([&] { associate({}, ref); }).find("no poses"), std::string::npos);
}

TEST(Evaluation, AssociationUsesEachReferencePoseOnce) {
  // Estimate at 100 Hz, reference at 10 Hz: one pair per reference pose.
  Trajectory2D est, ref;
  for (int k = 0; k < 1000; ++k) est.push_back({0.01 * k, 0.01 * k, 0, 0});
  for (int k = 0; k < 100; ++k) ref.push_back({0.1 * k + 0.003, 0.1 * k, 0, 0});
  const Association a = associate(est, ref);
  EXPECT_EQ(a.size(), 100u);
  for (size_t k = 0; k < a.size(); ++k) EXPECT_EQ(a.est_index[k], 10 * k);
}

TEST(Evaluation, AssociationByInterpolation) {
  // Reference at 1 Hz moving 1 m/s; estimate at the half seconds.
  Trajectory2D ref, est;
  for (int k = 0; k <= 10; ++k) ref.push_back({double(k), double(k), 0, 0});
  for (int k = 0; k < 10; ++k) est.push_back({k + 0.5, k + 0.5, 0, 0});
  EXPECT_NE(inputError([&] { associate(est, ref); }).find("do not overlap"), std::string::npos);
  AssociationParams p;
  p.interpolate = true;
  p.max_gap = 1.5;
  const Association a = associate(est, ref, p);
  EXPECT_EQ(a.size(), 10u);
  EXPECT_EQ(a.interpolated, 10u);
  EXPECT_NEAR(a.ref[3].x, 3.5, 1e-12);
  EXPECT_LT(computeAte(a, false).translation.max, 1e-12);
  // Gaps longer than max-gap are not bridged.
  p.max_gap = 0.5;
  EXPECT_THROW(associate(est, ref, p), InputError);
  // Yaw takes the short way across ±180 deg.
  const Trajectory2D wrap{{0, 0, 0, 170 * kDeg}, {1, 1, 0, -170 * kDeg}};
  p.max_gap = 2;
  const auto q = poseAt(wrap, 0.5, p);
  ASSERT_TRUE(q.has_value());
  EXPECT_NEAR(std::abs(q->yaw), M_PI, 1e-9);
  EXPECT_FALSE(poseAt(wrap, 1.5, p).has_value());  // outside: nearest only, 0.5 s away
}

// ---------------------------------------------------------------- relations

TEST(Evaluation, RelationsMetricOnAHandComputedExample) {
  const Trajectory2D est{{0, 0, 0, 0}, {1, 1, 0, 90 * kDeg}, {2, 1, 1, 90 * kDeg}};
  const std::string path = writeText("hand.relations",
                                     "# t1 t2 x y z roll pitch yaw\n"
                                     "0 1 1 0 0 0 0 1.5707963267948966\n"  // exact
                                     "1 2 1.1 0 0 0 0 0\n"  // 0.1 m too long in the frame at t1
                                     "\n"
                                     "0 2 1 1 0 0 0 1.4707963267948966\n"  // 0.1 rad off
                                     "5 6 1 0 0 0 0 0\n");  // no estimated poses there
  const auto rels = readRelations(path);
  ASSERT_EQ(rels.size(), 4u);
  EXPECT_EQ(rels[2].line, 5);
  const RelationsResult r = computeRelationsError(est, rels);
  EXPECT_EQ(r.total, 4u);
  EXPECT_EQ(r.used, 3u);
  EXPECT_NEAR(r.translation.mean, 0.1 / 3, 1e-9);
  EXPECT_NEAR(r.translation.max, 0.1, 1e-9);
  EXPECT_NEAR(r.translation_sq.mean, 0.01 / 3, 1e-9);
  const double deg = 0.1 / kDeg;  // 5.7296 deg
  EXPECT_NEAR(r.rotation.mean, deg / 3, 1e-7);
  EXPECT_NEAR(r.rotation_sq.mean, deg * deg / 3, 1e-6);
  EXPECT_NEAR(r.rotation.std, std::sqrt(deg * deg / 3 - deg * deg / 9), 1e-7);

  // None of the relations' times in the estimate: an input error.
  Trajectory2D later = est;
  for (auto& p : later) p.t += 100;
  const std::string msg = inputError([&] { computeRelationsError(later, rels); });
  EXPECT_NE(msg.find("do not overlap"), std::string::npos) << msg;
}

TEST(Evaluation, MadeRelationsRoundTripAndScoreZeroOnTheReference) {
  const Trajectory2D ref = curvyPath();
  const auto rels = makeRelations(ref, 1.0);
  ASSERT_GT(rels.size(), 300u);
  const std::string path = (scratch() / "made.relations").string();
  writeRelations(path, rels);
  const auto back = readRelations(path);
  ASSERT_EQ(back.size(), rels.size());
  EXPECT_NEAR(back[10].delta.x, rels[10].delta.x, 1e-6);
  EXPECT_NEAR(back[10].delta.phi, rels[10].delta.phi, 1e-8);
  // Each pair spans at least 1 m of path.
  EXPECT_GE(std::hypot(back[0].delta.x, back[0].delta.y), 0.9);
  // A globally moved copy of the reference has no relation error.
  const RelationsResult r = computeRelationsError(transformTrajectory(ref, {5, 5, 2}), back);
  EXPECT_EQ(r.used, rels.size());
  EXPECT_LT(r.translation.max, 1e-5);
  EXPECT_LT(r.rotation.max, 1e-5);
  EXPECT_TRUE(makeRelations(line(3, 0.1), 1.0).empty());
}

// ---------------------------------------------------------------- bad input

TEST(Evaluation, MalformedRelationsFilesNameFileAndLine) {
  struct Case {
    const char* name;
    const char* text;
    const char* expect;
  };
  const Case cases[] = {
      {"empty", "", ": no relations"},
      {"comments", "# nothing\n\n", ": no relations"},
      {"garbage", "hello world\n", ":1: expected 8 numbers"},
      {"binary", "\x89PNG\r\n\x1a\n\x00\x01", ":1: expected 8 numbers"},
      {"few", "0 1 1 0 0 0 0 0\n0 1 2 3\n", ":2: expected 8 numbers"},
      {"truncated", "0 1 1 0 0 0 0 0\n1 2 1 0 0 0", ":2: expected 8 numbers"},
      {"many", "0 1 1 0 0 0 0 0 9\n", ":1: expected 8 numbers"},
      {"nan", "# c\n0 1 nan 0 0 0 0 0\n", ":2: "},
      {"inf", "0 1 1 0 0 0 0 1e999\n", ":1: "},
  };
  for (const auto& c : cases) {
    const std::string path =
        writeText(std::string("bad_") + c.name + ".relations",
                  std::string(c.text, c.name == std::string("binary") ? 10 : std::strlen(c.text)));
    const std::string msg = inputError([&] { readRelations(path); });
    EXPECT_NE(msg.find(path + c.expect), std::string::npos) << c.name << ": " << msg;
  }
  EXPECT_NE(inputError([] {
              readRelations("/nonexistent/x.relations");
            }).find("/nonexistent/x.relations: cannot open"),
            std::string::npos);
  EXPECT_NE(inputError([] { readRelations(scratch().string()); }).find("directory"),
            std::string::npos);
}

TEST(Evaluation, MalformedTumFilesNameFileAndLine) {
  struct Case {
    const char* name;
    const char* text;
    const char* expect;
  };
  const Case cases[] = {
      {"empty", "", ": no poses"},
      {"garbage", "this is not a trajectory\n", ":1: expected 8 numbers"},
      {"few", "# h\n0 1 2 0 0 0 0 1\n1 1 2 0\n", ":3: expected 8 numbers"},
      {"truncated", "0 1 2 0 0 0 0 1\n1 1 2 0 0 0 0.7", ":2: expected 8 numbers"},
      {"nan", "0 nan 2 0 0 0 0 1\n", ":1: "},
  };
  {  // Timestamps that step back (real logs have them) are sorted, and counted.
    const std::string path =
        writeText("backwards.tum", "2 2 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n3 3 0 0 0 0 0 1\n");
    size_t reordered = 0;
    const auto t = io::readTum(path, &reordered);
    EXPECT_EQ(reordered, 1u);
    ASSERT_EQ(t.size(), 3u);
    EXPECT_DOUBLE_EQ(t[0].t, 1);
    EXPECT_DOUBLE_EQ(t[0].x, 1);
    EXPECT_DOUBLE_EQ(t[2].t, 3);
  }
  for (const auto& c : cases) {
    const std::string path = writeText(std::string("bad_") + c.name + ".tum", c.text);
    const std::string msg = inputError([&] { io::readTum(path); });
    EXPECT_NE(msg.find(path + c.expect), std::string::npos) << c.name << ": " << msg;
  }
}
