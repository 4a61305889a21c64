// Ray casting into a World: 2D rays for lidars and range arrays, 3D rays for
// depth cameras (floor with its features, walls as full-height obstacles,
// table tops as overhangs, people as cylinders).
#pragma once

#include <carenav/sim/world.h>

#include <limits>
#include <vector>

namespace carenav::sim {

/** A person frozen at one instant: a cylinder from the floor to `h`. */
struct PersonNow {
  double x = 0, y = 0, r = 0.25, h = 1.7;
};

/** The people of `world` at time t. */
std::vector<PersonNow> peopleAt(const World& world, double t);

constexpr double kNoHit = std::numeric_limits<double>::infinity();

/** Range of a horizontal ray at height z from (x, y) along `angle` (rad, map
 *  frame) to the first wall, feature taller than z (steps, stairs, table legs,
 *  a table top whose slab holds z) or person taller than z; kNoHit when
 *  nothing is hit within max_range. Walks the grid cell by cell (DDA),
 *  skipping empty space with World::clearance. */
double castRay2D(const World& world, const std::vector<PersonNow>& people, double x, double y,
                 double z, double angle, double max_range);

/** Parameter t of the first hit of the 3D ray o + t d (t in [0, t_max]):
 *  floor at its height (0, steps, stairs, holes, ramps), sides of height
 *  changes, walls up to World::wallHeight, table slabs, people cylinders
 *  (side and top). kNoHit when nothing is hit. With d's component along the
 *  camera axis equal to 1, t is the depth. Plain floor is intersected
 *  analytically over the clear cells around the ray (empty-space skipping). */
double castRay3D(const World& world, const std::vector<PersonNow>& people, const double o[3],
                 const double d[3], double t_max);

}  // namespace carenav::sim
