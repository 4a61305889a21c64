#include <carenav/sim/raycast.h>

#include <algorithm>
#include <cmath>

namespace carenav::sim {

std::vector<PersonNow> peopleAt(const World& world, double t) {
  std::vector<PersonNow> out;
  for (const auto& p : world.people()) {
    const Vec2 q = p.at(t);
    out.push_back({q.x, q.y, p.radius, p.height});
  }
  return out;
}

namespace {

/** Smallest t >= 0 where the 2D ray (ox,oy)+t(dx,dy) enters the circle; kNoHit if never. */
inline double circleEntry(double ox, double oy, double dx, double dy, double cx, double cy,
                          double r) {
  const double fx = ox - cx, fy = oy - cy;
  const double a = dx * dx + dy * dy;
  if (a <= 0) return (fx * fx + fy * fy <= r * r) ? 0 : kNoHit;
  const double b = fx * dx + fy * dy;
  const double c = fx * fx + fy * fy - r * r;
  if (c <= 0) return 0;  // starts inside
  const double disc = b * b - a * c;
  if (disc < 0) return kNoHit;
  const double t = (-b - std::sqrt(disc)) / a;
  return t >= 0 ? t : kNoHit;
}

}  // namespace

namespace {

/** Amanatides-Woo grid traversal state from the point at parameter t. */
struct Dda {
  int cx, cy, sx, sy;
  double tmx, tmy, tdx, tdy;
  double inv_dx, inv_dy;
  /** Per ray: step directions and cell crossing increments. */
  void setup(const World& w, double dx, double dy) {
    const double res = w.resolution();
    sx = dx > 0 ? 1 : -1;
    sy = dy > 0 ? 1 : -1;
    inv_dx = dx != 0 ? 1.0 / dx : 0;
    inv_dy = dy != 0 ? 1.0 / dy : 0;
    tdx = dx != 0 ? res * std::abs(inv_dx) : kNoHit;
    tdy = dy != 0 ? res * std::abs(inv_dy) : kNoHit;
  }
  /** The cell holding the ray's point at parameter t and its next crossings. */
  void init(const World& w, double ox, double oy, double dx, double dy, double t) {
    const double res = w.resolution(), x0 = w.xMin(), y0 = w.yMin();
    const double inv_res = 1.0 / res;
    const double px = ox + t * dx, py = oy + t * dy;
    const double eps = 1e-9;
    cx = static_cast<int>(std::floor((px + eps * dx - x0) * inv_res));
    cy = static_cast<int>(std::floor((py + eps * dy - y0) * inv_res));
    tmx = dx > 0 ? t + (x0 + (cx + 1) * res - px) * inv_dx
                 : (dx < 0 ? t + (x0 + cx * res - px) * inv_dx : kNoHit);
    tmy = dy > 0 ? t + (y0 + (cy + 1) * res - py) * inv_dy
                 : (dy < 0 ? t + (y0 + cy * res - py) * inv_dy : kNoHit);
  }
  double exit() const { return std::min(tmx, tmy); }
  void next() {
    if (tmx < tmy) {
      cx += sx;
      tmx += tdx;
    } else {
      cy += sy;
      tmy += tdy;
    }
  }
};

/** Where a ray outside the grid box enters it after t (kNoHit: never). */
double gridEntry(const World& w, double ox, double oy, double dx, double dy, double t) {
  const double x0 = w.xMin(), y0 = w.yMin();
  const double x1 = x0 + w.sizeX() * w.resolution(), y1 = y0 + w.sizeY() * w.resolution();
  double t0 = t, t1 = kNoHit;
  auto slab = [&](double o, double d, double lo, double hi) {
    if (d == 0) {
      if (o < lo || o > hi) t0 = kNoHit;
      return;
    }
    double a = (lo - o) / d, b = (hi - o) / d;
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
  };
  slab(ox, dx, x0, x1);
  slab(oy, dy, y0, y1);
  return (t0 < t1 && t0 > t + 1e-9) ? t0 : kNoHit;
}

}  // namespace

double castRay2D(const World& w, const std::vector<PersonNow>& people, double x, double y, double z,
                 double angle, double max_range) {
  const double dx = std::cos(angle), dy = std::sin(angle);
  double best = max_range;
  bool hit = false;
  for (const auto& p : people) {
    if (p.h < z) continue;
    const double t = circleEntry(x, y, dx, dy, p.x, p.y, p.r);
    if (t < best) best = t, hit = true;
  }
  const double skip_unit = w.resolution() / std::max(std::abs(dx), std::abs(dy));
  double t = 0;
  Dda g;
  g.setup(w, dx, dy);
  while (t < best) {
    g.init(w, x, y, dx, dy, t);
    if (!w.inside(g.cx, g.cy)) {
      const double tin = gridEntry(w, x, y, dx, dy, t);
      if (tin == kNoHit) break;
      t = tin + 1e-9;
      continue;
    }
    bool reinit = false;
    while (t < best) {
      const int cl = w.clearance(g.cx, g.cy);  // 0: not plain floor
      if (cl > 0) {
        if (cl >= 3) {  // the next cl-1 cells along either axis are plain floor
          t += (cl - 1) * skip_unit;
          reinit = true;
          break;
        }
      } else if (const Cell& c = w.cell(g.cx, g.cy);
                 c.floor > z || (c.hasSlab() && c.slab_lo <= z && z <= c.slab_hi)) {
        best = t, hit = true;
        break;
      }
      t = g.exit();
      g.next();
      if (!w.inside(g.cx, g.cy)) {
        reinit = true;
        break;
      }
    }
    if (!reinit) break;
  }
  return hit ? best : kNoHit;
}

double castRay3D(const World& w, const std::vector<PersonNow>& people, const double o[3],
                 const double d[3], double t_max) {
  double best = t_max;
  bool hit = false;
  const double h2 = d[0] * d[0] + d[1] * d[1];
  // people: cylinder side, then top disk
  for (const auto& p : people) {
    const double ts = circleEntry(o[0], o[1], d[0], d[1], p.x, p.y, p.r);
    if (ts < best) {
      const double zs = o[2] + ts * d[2];
      if (zs >= 0 && zs <= p.h) {
        best = ts, hit = true;
        continue;
      }
    }
    if (d[2] < 0 && o[2] > p.h) {
      const double tt = (p.h - o[2]) / d[2];
      const double qx = o[0] + tt * d[0] - p.x, qy = o[1] + tt * d[1] - p.y;
      if (tt < best && qx * qx + qy * qy <= p.r * p.r) best = tt, hit = true;
    }
  }
  const double t_floor0 = d[2] < 0 ? -o[2] / d[2] : kNoHit;  // plain floor z = 0
  const float wallh = static_cast<float>(w.wallHeight());
  if (h2 < 1e-18) {
    // vertical ray: only the cell below (or above)
    const int cx = w.cellX(o[0]), cy = w.cellY(o[1]);
    double f = 0;
    if (w.inside(cx, cy)) {
      const Cell& c = w.cell(cx, cy);
      f = c.wall() ? wallh : c.floor;
      if (c.hasSlab()) {
        if (d[2] < 0 && o[2] > c.slab_hi) f = std::max<double>(f, c.slab_hi);
        if (d[2] > 0 && o[2] < c.slab_lo) {
          const double tl = (c.slab_lo - o[2]) / d[2];
          if (tl < best) return tl;
        }
      }
    }
    if (d[2] < 0) {
      const double tf = (f - o[2]) / d[2];
      if (tf >= 0 && tf < best) return tf;
    }
    return hit ? best : kNoHit;
  }
  const double skip_unit = w.resolution() / std::max(std::abs(d[0]), std::abs(d[1]));
  double t = 0;
  Dda g;
  g.setup(w, d[0], d[1]);
  while (t < best) {
    g.init(w, o[0], o[1], d[0], d[1], t);
    if (!w.inside(g.cx, g.cy)) {
      // Outside the grid the floor is plain; find where the ray comes back.
      const double tin = gridEntry(w, o[0], o[1], d[0], d[1], t);
      if (t_floor0 <= std::min(tin, best)) {
        const double th = std::max(t, t_floor0);
        if (th < best) best = th, hit = true;
        break;
      }
      if (tin == kNoHit) break;
      t = tin + 1e-9;
      continue;
    }
    bool reinit = false;
    while (t < best) {
      const int cl = w.clearance(g.cx, g.cy);  // 0: not plain floor
      if (cl > 0) {
        if (cl >= 3) {  // the next cl-1 cells along either axis are plain floor
          const double t_skip = t + (cl - 1) * skip_unit;
          if (t_floor0 <= t_skip) {  // (below z = 0 already, leaving a hole: the side at t)
            const double th = std::max(t, t_floor0);
            if (th < best) best = th, hit = true;
            break;
          }
          t = t_skip;
          reinit = true;
          break;
        }
        const double t_out = g.exit();
        if (t_floor0 <= t_out) {
          const double th = std::max(t, t_floor0);
          if (th < best) best = th, hit = true;
          break;
        }
      } else {
        const Cell& c = w.cell(g.cx, g.cy);
        const double t_out = g.exit();
        const double z_in = o[2] + t * d[2], z_out = o[2] + t_out * d[2];
        double th = kNoHit;
        const double f = c.wall() ? wallh : c.floor;
        if (z_in < f)
          th = t;  // the side of a raised cell (or a wall)
        else if (z_out < f)
          th = (f - o[2]) / d[2];  // its top
        if (c.hasSlab()) {
          if (z_in >= c.slab_lo && z_in <= c.slab_hi)
            th = std::min(th, t);
          else if (z_in > c.slab_hi && z_out <= c.slab_hi)
            th = std::min(th, (c.slab_hi - o[2]) / d[2]);
          else if (z_in < c.slab_lo && z_out >= c.slab_lo)
            th = std::min(th, (c.slab_lo - o[2]) / d[2]);
        }
        if (th < kNoHit) {
          if (th < best) best = th, hit = true;
          break;
        }
      }
      t = g.exit();
      g.next();
      if (!w.inside(g.cx, g.cy)) {
        reinit = true;
        break;
      }
    }
    if (!reinit) break;
  }
  return hit ? best : kNoHit;
}

}  // namespace carenav::sim
