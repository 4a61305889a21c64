// Places the robot could not get through: where recoveries started again
// and again. Backing out and replanning alone sends the robot back into the
// same wedge (the route there is still clear on the map: the posts of a
// gap the footprint fits straight but not at the angle the robot came
// from). Once the robot has had to recover `avoid_after` times at one
// place, later routes keep clear of it while another way exists (with
// none, the route stays as it was).
#pragma once

#include <carenav/common/params.h>
#include <carenav/navigation/local_map.h>

#include <mrpt/math/TPoint2D.h>
#include <mrpt/math/TPose2D.h>

#include <vector>

namespace carenav::navigation {

using mrpt::math::TPoint2D;
using mrpt::math::TPose2D;

/** [nav.failed_places]: when a place where recoveries started is avoided. */
struct FailedPlacesParams {
  /** Recoveries started at one place (robot centres within the footprint's
   *  circumscribed radius of each other) after which later routes keep
   *  clear of it, while another way exists; 0: never. */
  int avoid_after = 2;
  static const ParamTable<FailedPlacesParams>& table();
};

/** The places of a goal's recoveries (map frame). Bounded: at most
 *  kMaxPlaces are kept, the oldest dropped first. */
class FailedPlaces {
 public:
  static constexpr size_t kMaxPlaces = 64;
  FailedPlaces(const FailedPlacesParams& p, const Footprint& footprint);
  /** A recovery started with the robot at `pose`. True when its place is
   *  now avoided (this was its avoid_after-th recovery there). */
  bool add(const TPose2D& pose);
  /** Points (map frame) for the route to keep clear of: per avoided place,
   *  the robot's centre and the middle of its front edge when it got stuck
   *  (the gap it was trying to enter), every `spacing` metres between. */
  std::vector<TPoint2D> avoidedPoints(double spacing) const;
  size_t avoided() const;
  /** A new goal: the places are forgotten. */
  void clear() { places_.clear(); }

 private:
  struct Place {
    TPose2D pose;  ///< where the latest recovery there started
    int recoveries = 0;
  };
  FailedPlacesParams p_;
  double same_place_ = 0;  ///< m, the footprint's circumscribed radius
  double front_ = 0;       ///< m, forward extent of the footprint
  std::vector<Place> places_;
};

}  // namespace carenav::navigation
