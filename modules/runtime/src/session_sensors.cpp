// The navigation session's sensor data and user (session.h): odometry and
// 2D scans to the obstacle memory and the localiser; depth frames through
// the perception pipeline (2.5D grid, RRT-GPD ground plane, inverse sensor
// model: stairs down and gutters become obstacles).
#include <carenav/localization/localizer.h>
#include <carenav/perception/pipeline.h>
#include <carenav/runtime/session.h>

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>

#include <chrono>
#include <cmath>

namespace carenav::navigation {

namespace {

/** Cells of the perception grid above this occupancy probability are obstacles. */
constexpr double perception_occupied = 0.6;

}  // namespace

void NavigationSession::odometry(const TPose2D& odo, const Twist& measured, double t) {
  odom_ = odo;
  have_odom_ = true;
  measured_v_ = measured.v;
  if (unknown_) unknown_->stoodOn(odo);
  nav_.setOdometry(odo, measured, t);
}

void NavigationSession::observation(const mrpt::obs::CObservation::Ptr& obs, const TPose2D& odo,
                                    double t) {
  if (dynamic_cast<const mrpt::obs::CObservationOdometry*>(obs.get())) return;
  if (dynamic_cast<const mrpt::obs::CObservation3DRangeScan*>(obs.get())) {
    depthFrame(*obs, odo, t);
    return;
  }
  nav_.addObservation(*obs, odo, t);
  if (!loc_ || obs->sensorLabel != loc_sensor_) return;
  const mrpt::poses::CPose2D now_odo(odo.x, odo.y, odo.phi);
  const mrpt::poses::CPose2D inc = loc_started_ ? now_odo - last_loc_odo_ : mrpt::poses::CPose2D();
  last_loc_odo_ = now_odo;
  loc_started_ = true;
  const auto sr =
      loc_->step(inc, std::dynamic_pointer_cast<mrpt::obs::CObservation2DRangeScan>(obs), t);
  dead_reckoning_ = sr.dead_reckoning;
  m_.dead_reckoning_scans += sr.dead_reckoning;
  const auto p = loc_->pose();
  nav_.setMapPose({p.x(), p.y(), p.phi()});
  // HOBBIT: localisation may ask for a turn in place to relocalise.
  nav_.setRotateRequest(loc_->needsRotateInPlace());
}

void NavigationSession::depthFrame(const mrpt::obs::CObservation& obs, const TPose2D& odo,
                                   double t) {
  if (!perceive_) return;
  const auto& depth = dynamic_cast<const mrpt::obs::CObservation3DRangeScan&>(obs);
  if (!perception_sensor_.empty() && depth.sensorLabel != perception_sensor_) return;
  const auto cloud = perception::cloudFromObservation(depth);
  if (!cloud) return;
  perception::FrameInput fi;
  fi.cloud = &*cloud;
  fi.sensor_origin = {static_cast<float>(depth.sensorPose.x()),
                      static_cast<float>(depth.sensorPose.y()),
                      static_cast<float>(depth.sensorPose.z())};
  fi.odometry = mrpt::poses::CPose2D(odo.x, odo.y, odo.phi);
  const auto c0 = std::chrono::steady_clock::now();
  const auto fr = perceive_->process(fi, false);
  perceive_ms_ +=
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - c0).count();
  ++m_.depth_frames;
  // Occupied cells of the local grid are obstacles for navigation.
  const auto& g = perceive_->grid();
  std::vector<TPoint2D> occ;
  for (int j = 0; j < g.cells(); ++j)
    for (int i = 0; i < g.cells(); ++i)
      if (g.prob(i, j) > perception_occupied) occ.push_back({g.centreX(i), g.centreY(j)});
  // Floor no frame has seen ahead within the braking distance: not traversable.
  if (unknown_) {
    unknown_->stoodOn(odo);
    const auto ua = unknown_->cells(g, odo, measured_v_);
    occ.insert(occ.end(), ua.begin(), ua.end());
  }
  nav_.setPerceivedObstacles(std::move(occ), t);
  // The frame's own floor and obstacle voxels: people walking in.
  // (Not the grid's ray-cleared cells: rays pass over a box's top.)
  std::vector<TPoint2D> seen_free, seen_hit;
  const auto& ev = perceive_->elevation();
  const int me = ev.cells();
  const double ca = std::cos(odo.phi), sa = std::sin(odo.phi);
  if (fr.voxel_classes.size() == static_cast<size_t>(me) * me)
    for (int i = 0; i < me; ++i)
      for (int j = 0; j < me; ++j) {
        const auto vc = fr.voxel_classes[static_cast<size_t>(i) * me + j];
        if (vc == perception::VoxelClass::None) continue;
        const double x = ev.centre(i), y = ev.centre(j);
        const TPoint2D w{odo.x + ca * x - sa * y, odo.y + sa * x + ca * y};
        (vc == perception::VoxelClass::Ground ? seen_free : seen_hit).push_back(w);
      }
  nav_.addPerceivedFrame(seen_free, seen_hit, t);
}

void NavigationSession::userIntent(const Twist& cmd, double sample_t, double now) {
  nav_.setUserIntent(cmd, sample_t);
  if (now - sample_t <= s_.nav.intent_timeout) user_ = cmd;
}

void NavigationSession::userPathPoint(const TPoint2D& p) { appendBounded(user_path_, p); }

}  // namespace carenav::navigation
