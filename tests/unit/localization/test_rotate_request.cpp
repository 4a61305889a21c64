// The "rotate in place to relocalise" request (HOBBIT, [Puente14, App. Fig. 8]) and the
// filter's state, on MRPT's real localization_demo data.
#include <carenav/common/profile.h>
#include <carenav/io/map_io.h>
#include <carenav/io/scan_stream.h>
#include <carenav/localization/localize_job.h>
#include <carenav/localization/localizer.h>

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace carenav::localization {
namespace {

const std::string kDatasets = CARENAV_MRPT_DATASETS;
const std::string kRawlog = kDatasets + "/localization_demo.rawlog";

const io::COccupancyGridMap2D& demoMap() {
  static const auto m = io::loadGridMap(kDatasets + "/localization_demo.simplemap.gz");
  return m;
}

mrpt::obs::CObservation2DRangeScan::Ptr firstScan() {
  io::ScanStream stream(kRawlog, "");
  io::ScanStep s;
  EXPECT_TRUE(stream.next(s));
  return s.scan;
}

LocalizationParams rotateParams(int after, double turn_deg) {
  LocalizationParams p;
  p.rotate_request = true;
  p.rotate_after_updates = after;
  p.rotate_turn = turn_deg;
  return p;
}

// A global start on a robot that stands still: the first scan again and
// again. Over 40000 particles spread over the whole map the filter cannot
// converge in three updates, so after the third the request is raised.
TEST(RotateRequest, RaisedAfterNUnconvergedUpdatesWhileStandingStill) {
  Localizer loc(demoMap(), rotateParams(3, 360));
  loc.initGlobal();
  EXPECT_EQ(loc.state(), Localizer::State::Converging);
  const auto scan = firstScan();
  for (int i = 1; i <= 3; ++i) {
    const auto r = loc.step(mrpt::poses::CPose2D(), scan, 10.0 * i);
    ASSERT_TRUE(r.updated);
    ASSERT_FALSE(loc.converged()) << "converged after " << i << " updates";
    EXPECT_EQ(r.rotate_in_place, i == 3) << i;
    EXPECT_EQ(loc.needsRotateInPlace(), i == 3) << i;
  }
  ASSERT_EQ(loc.rotateRequests().size(), 1u);
  EXPECT_DOUBLE_EQ(loc.rotateRequests()[0].t_start, 30.0);
  EXPECT_FALSE(loc.rotateRequests()[0].t_end.has_value());
}

TEST(RotateRequest, OffByDefault) {
  EXPECT_FALSE(LocalizationParams{}.rotate_request);
  Localizer loc(demoMap(), LocalizationParams{});
  loc.initGlobal();
  const auto scan = firstScan();
  for (int i = 1; i <= 6; ++i) loc.step(mrpt::poses::CPose2D(), scan, i);
  EXPECT_FALSE(loc.needsRotateInPlace());
  EXPECT_TRUE(loc.rotateRequests().empty());
}

// A robot that is already turning (60 deg per update, rotate_turn 90 deg)
// gets no request however long the filter stays unconverged; the same
// filter standing still gets one (the test above).
TEST(RotateRequest, NotRaisedWhileTheRobotTurns) {
  Localizer loc(demoMap(), rotateParams(3, 90));
  loc.initGlobal();
  const auto scan = firstScan();
  for (int i = 1; i <= 8; ++i) {
    loc.step(mrpt::poses::CPose2D(0, 0, mrpt::DEG2RAD(60.0)), scan, i);
    EXPECT_FALSE(loc.needsRotateInPlace()) << i;
  }
  EXPECT_TRUE(loc.rotateRequests().empty());
}

// Raised while standing still, then the robot turns in place: once it has
// turned rotate_turn without the filter converging, the request ends (not
// relocalised); standing still again raises a new one.
TEST(RotateRequest, EndsAfterTurningRotateTurnAndMayBeRaisedAgain) {
  Localizer loc(demoMap(), rotateParams(2, 90));
  loc.initGlobal();
  const auto scan = firstScan();
  double t = 0;
  for (int i = 0; i < 2; ++i) loc.step(mrpt::poses::CPose2D(), scan, ++t);
  ASSERT_TRUE(loc.needsRotateInPlace());
  // 3 x 40 deg = 120 deg >= 90 deg; two steps (80 deg) are not enough.
  for (int i = 0; i < 2; ++i) {
    loc.step(mrpt::poses::CPose2D(0, 0, mrpt::DEG2RAD(40.0)), scan, ++t);
    ASSERT_FALSE(loc.converged());
    EXPECT_TRUE(loc.needsRotateInPlace()) << i;
  }
  loc.step(mrpt::poses::CPose2D(0, 0, mrpt::DEG2RAD(40.0)), scan, ++t);
  ASSERT_FALSE(loc.converged());
  EXPECT_FALSE(loc.needsRotateInPlace());
  ASSERT_EQ(loc.rotateRequests().size(), 1u);
  ASSERT_TRUE(loc.rotateRequests()[0].t_end.has_value());
  EXPECT_DOUBLE_EQ(*loc.rotateRequests()[0].t_end, t);
  EXPECT_FALSE(loc.rotateRequests()[0].relocalised);
  for (int i = 0; i < 2; ++i) loc.step(mrpt::poses::CPose2D(), scan, ++t);
  ASSERT_FALSE(loc.converged());
  EXPECT_TRUE(loc.needsRotateInPlace());
  EXPECT_EQ(loc.rotateRequests().size(), 2u);
}

// The whole demo from a global start: a request after two updates, ended by
// the convergence (relocalised, at the convergence time); the state goes
// Converging -> Tracking.
TEST(RotateRequest, EndsWhenTheFilterConverges) {
  Localizer loc(demoMap(), rotateParams(2, 360));
  loc.initGlobal();
  io::ScanStream stream(kRawlog, "");
  io::ScanStep s;
  bool seen_request = false;
  while (stream.next(s)) {
    const auto r = loc.step(s.odometry.value_or(mrpt::poses::CPose2D()), s.scan, s.time);
    seen_request = seen_request || r.rotate_in_place;
    if (!loc.convergenceTime()) EXPECT_EQ(loc.state(), Localizer::State::Converging);
  }
  EXPECT_TRUE(seen_request);
  ASSERT_TRUE(loc.convergenceTime().has_value());
  EXPECT_EQ(loc.state(), Localizer::State::Tracking);
  EXPECT_FALSE(loc.needsRotateInPlace());
  ASSERT_GE(loc.rotateRequests().size(), 1u);
  const auto& q = loc.rotateRequests().front();
  ASSERT_TRUE(q.t_end.has_value());
  EXPECT_TRUE(q.relocalised);
  EXPECT_DOUBLE_EQ(*q.t_end, *loc.convergenceTime());
  EXPECT_LT(q.t_start, *q.t_end);
}

// A kidnapped start (5 m off along the corridor, tight spread): Tracking at
// first, Lost when the loss is reported.
TEST(LocalizerState, TrackingThenLostOnAKidnappedStart) {
  Localizer loc(demoMap(), LocalizationParams{});
  loc.initPose(mrpt::poses::CPose2D(8.7, -10.1, mrpt::DEG2RAD(-40.0)), 0.1, 0.1,
               mrpt::DEG2RAD(3.0));
  EXPECT_EQ(loc.state(), Localizer::State::Tracking);
  io::ScanStream stream(kRawlog, "");
  io::ScanStep s;
  bool seen_lost = false;
  while (stream.next(s)) {
    loc.step(s.odometry.value_or(mrpt::poses::CPose2D()), s.scan, s.time);
    const bool lost_event =
        !loc.events().empty() && loc.events().back().kind == LocalizationEvent::Kind::Loss;
    if (lost_event) {
      EXPECT_EQ(loc.state(), Localizer::State::Lost);
      seen_lost = true;
    }
  }
  EXPECT_TRUE(seen_lost);
}

// summary.json lists the requests: how many, when, and how each ended.
TEST(RotateRequest, WrittenToSummaryJson) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("carenav_rotate_summary_" + std::to_string(::getpid()));
  LocalizeJobOptions o;
  o.map = kDatasets + "/localization_demo.simplemap.gz";
  o.rawlog = kRawlog;
  o.out_dir = dir.string();
  o.progress = false;
  o.global = true;
  o.params = rotateParams(2, 360);
  const auto r = runLocalize(o);
  ASSERT_TRUE(r.convergence_time.has_value());
  ASSERT_EQ(r.rotate_requests.size(), 1u);
  std::ifstream f(dir / "summary.json");
  std::stringstream ss;
  ss << f.rdbuf();
  const std::string s = ss.str();
  const auto at = s.find("\"rotate_in_place\": {");
  ASSERT_NE(at, std::string::npos) << s;
  const std::string part = s.substr(at, s.find('}', s.find("\"outcome\"", at)) - at);
  EXPECT_NE(part.find("\"enabled\": true"), std::string::npos) << part;
  EXPECT_NE(part.find("\"requests\": 1"), std::string::npos) << part;
  EXPECT_NE(part.find("\"outcome\": \"converged\""), std::string::npos) << part;
  // times are relative to the first scan, like convergence_time
  std::ostringstream end;
  end << "\"end_t\": ";
  EXPECT_NE(part.find(end.str()), std::string::npos) << part;
  EXPECT_LE(*r.rotate_requests[0].t_end, *r.convergence_time + 1e-9);
  EXPECT_GE(*r.rotate_requests[0].t_end, *r.convergence_time - 1e-9);
  EXPECT_GT(r.rotate_requests[0].t_start, 0.0);
  std::filesystem::remove_all(dir);
}

// HOBBIT's profile asks for the request; the others keep the default (off).
TEST(RotateRequest, OnInTheHobbitProfile) {
  registerProfileSections();
  const std::string src = CARENAV_SOURCE_DIR;
  const auto hobbit = Profile::load(src + "/ini/hobbit.ini");
  EXPECT_TRUE(hobbit.section<LocalizationParams>("localization").rotate_request);
  const auto defaults = Profile::load(src + "/ini/defaults.ini");
  EXPECT_FALSE(defaults.section<LocalizationParams>("localization").rotate_request);
}

}  // namespace
}  // namespace carenav::localization
