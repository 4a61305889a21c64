// The point of a polyline (a route, a recent path) nearest to a position:
// used by goal-dwa's path critic and look-ahead, the recoveries' back-out
// corridor and the navigator's distance left along the route.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

namespace carenav::navigation {

/** Where on a polyline its point nearest to (x, y) lies. */
struct PolylinePoint {
  size_t segment = 0;  ///< from vertex `segment` to `segment + 1`
  double u = 0;        ///< 0..1 along that segment
  double distance = std::numeric_limits<double>::infinity();  ///< +inf for an empty polyline
};

/** The nearest point of `path` (anything with .x and .y) to (x, y); the
 *  first of equally near ones. A one-point path gives its point. */
template <class P>
PolylinePoint nearestOnPolyline(const std::vector<P>& path, double x, double y) {
  PolylinePoint best;
  if (path.size() == 1) best.distance = std::hypot(path[0].x - x, path[0].y - y);
  for (size_t i = 0; i + 1 < path.size(); ++i) {
    const auto& a = path[i];
    const auto& b = path[i + 1];
    const double vx = b.x - a.x, vy = b.y - a.y, l2 = vx * vx + vy * vy;
    const double u = l2 > 0 ? std::clamp(((x - a.x) * vx + (y - a.y) * vy) / l2, 0.0, 1.0) : 0;
    const double d = std::hypot(a.x + u * vx - x, a.y + u * vy - y);
    if (d < best.distance) best = {i, u, d};
  }
  return best;
}

}  // namespace carenav::navigation
