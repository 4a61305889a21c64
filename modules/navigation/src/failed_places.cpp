// Places where recoveries started again and again (failed_places.h).
#include <carenav/navigation/failed_places.h>

#include <algorithm>
#include <cmath>

namespace carenav::navigation {

const ParamTable<FailedPlacesParams>& FailedPlacesParams::table() {
  using P = FailedPlacesParams;
  static const auto t = ParamTable<P>().integer(
      "avoid_after", &P::avoid_after, "", 0, 1000,
      "recoveries started at one place (robot centres within the footprint's circumscribed "
      "radius) after which later routes keep clear of it while another way exists; 0: never");
  return t;
}

FailedPlaces::FailedPlaces(const FailedPlacesParams& p, const Footprint& footprint)
    : p_(p), same_place_(footprint.circumscribed) {
  for (const auto& v : footprint.polygon) front_ = std::max(front_, v.x);
}

bool FailedPlaces::add(const TPose2D& pose) {
  if (p_.avoid_after <= 0) return false;
  for (Place& q : places_) {
    if (std::hypot(q.pose.x - pose.x, q.pose.y - pose.y) <= same_place_) {
      q.pose = pose;
      return ++q.recoveries == p_.avoid_after;
    }
  }
  if (places_.size() >= kMaxPlaces) places_.erase(places_.begin());
  places_.push_back({pose, 1});
  return p_.avoid_after == 1;
}

size_t FailedPlaces::avoided() const {
  if (p_.avoid_after <= 0) return 0;
  return static_cast<size_t>(std::count_if(places_.begin(), places_.end(), [&](const Place& q) {
    return q.recoveries >= p_.avoid_after;
  }));
}

std::vector<TPoint2D> FailedPlaces::avoidedPoints(double spacing) const {
  std::vector<TPoint2D> out;
  if (p_.avoid_after <= 0) return out;
  const int n = std::max(1, static_cast<int>(std::ceil(front_ / std::max(spacing, 1e-3))));
  for (const Place& q : places_) {
    if (q.recoveries < p_.avoid_after) continue;
    const double c = std::cos(q.pose.phi), s = std::sin(q.pose.phi);
    for (int k = 0; k <= n; ++k) {
      const double d = front_ * k / n;
      out.push_back({q.pose.x + d * c, q.pose.y + d * s});
    }
  }
  return out;
}

}  // namespace carenav::navigation
