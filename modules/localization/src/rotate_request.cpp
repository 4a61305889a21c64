#include <carenav/localization/rotate_request.h>

#include <mrpt/core/bits_math.h>

namespace carenav::localization {

void RotateRequestTracker::reset(double t) {
  if (open_) requests_.back().t_end = t;
  open_ = false;
  restartCount();
}

void RotateRequestTracker::update(bool converged, double turned_rad, double t,
                                  const LocalizationParams& p) {
  if (!p.rotate_request) return;
  if (converged) {
    if (open_) {
      requests_.back().t_end = t;
      requests_.back().relocalised = true;
      open_ = false;
    }
    restartCount();
    return;
  }
  stall_turn_ += turned_rad;
  const double limit = mrpt::DEG2RAD(p.rotate_turn);
  if (open_) {
    // Turned a full rotate_turn since the request and still not converged:
    // the request ends; another may follow after rotate_after_updates.
    if (stall_turn_ >= limit) {
      requests_.back().t_end = t;
      open_ = false;
      restartCount();
    }
    return;
  }
  ++stall_updates_;
  if (stall_turn_ >= limit) {  // the robot is turning by itself: count afresh
    restartCount();
    return;
  }
  if (stall_updates_ >= static_cast<size_t>(p.rotate_after_updates)) {
    open_ = true;
    requests_.push_back({t, std::nullopt, false});
    stall_turn_ = 0;
  }
}

}  // namespace carenav::localization
