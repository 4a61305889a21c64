// "Rotate in place to relocalise" requests to the navigation layer.
#pragma once

#include <carenav/localization/localization_params.h>

#include <cstddef>
#include <optional>
#include <vector>

namespace carenav::localization {

/** A "rotate in place to relocalise" request to the navigation layer
 *  (HOBBIT, [Puente14, App. Fig. 8]): raised when the filter has not converged for
 *  rotate_after_updates filter updates while the robot turned less than
 *  rotate_turn; it ends when the filter converges or once the robot has turned
 *  rotate_turn since the request. */
struct RotateRequest {
  double t_start = 0;           ///< time of the update that raised it
  std::optional<double> t_end;  ///< time it ended (none: still open)
  bool relocalised = false;     ///< it ended because the filter converged
};

/** Raises and ends rotate requests from the filter's updates. */
class RotateRequestTracker {
 public:
  /** After a filter update ending at t, the robot having turned turned_rad
   *  since the previous one. Nothing unless p.rotate_request. */
  void update(bool converged, double turned_rad, double t, const LocalizationParams& p);
  /** A new start of the filter: an open request ends at t, the counts restart. */
  void reset(double t);
  /** A request is open. */
  bool open() const { return open_; }
  /** Every request so far, the open one last. */
  const std::vector<RotateRequest>& requests() const { return requests_; }

 private:
  void restartCount() {
    stall_updates_ = 0;
    stall_turn_ = 0;
  }
  bool open_ = false;
  size_t stall_updates_ = 0;  // consecutive updates without convergence
  double stall_turn_ = 0;     // rad turned during them (or since the open request)
  std::vector<RotateRequest> requests_;
};

}  // namespace carenav::localization
