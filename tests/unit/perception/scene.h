// Analytic test scenes seen by a simulated depth camera (ray casting against
// axis-aligned solid boxes), for the perception tests.
#pragma once

#include <carenav/perception/cloud.h>

#include <mrpt/poses/CPose3D.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace carenav_test {
using carenav::perception::Cloud;
using carenav::perception::Point3f;

struct Box {
  double x0, x1, y0, y1, z0, z1;
};

struct Scene {
  std::vector<Box> boxes;
  /** Flat floor (top at z = 0) from x0 to x1. */
  Scene& floor(double x0, double x1, double top = 0.0) {
    boxes.push_back({x0, x1, -10, 10, -2, top});
    return *this;
  }
  Scene& box(Box b) {
    boxes.push_back(b);
    return *this;
  }
  /** A ramp rising along +x from x0 (height 0) to x1 (height `rise`), then a
   *  landing at that height to x = 10; built from 2 mm steps. */
  Scene& ramp(double x0, double x1, double rise) {
    const int n = static_cast<int>(std::ceil(std::abs(rise) / 0.002));
    for (int k = 1; k <= n; ++k)
      boxes.push_back({x0 + (x1 - x0) * (k - 0.5) / n, 10, -10, 10, -2, rise * k / n});
    return *this;
  }
  /** Nearest hit distance along the ray, or +inf. */
  double cast(const double o[3], const double d[3]) const {
    double best = std::numeric_limits<double>::infinity();
    for (const auto& b : boxes) {
      double tmin = 0, tmax = 1e9;
      const double lo[3] = {b.x0, b.y0, b.z0}, hi[3] = {b.x1, b.y1, b.z1};
      bool miss = false;
      for (int a = 0; a < 3 && !miss; ++a) {
        if (std::abs(d[a]) < 1e-12) {
          if (o[a] < lo[a] || o[a] > hi[a]) miss = true;
          continue;
        }
        double t1 = (lo[a] - o[a]) / d[a], t2 = (hi[a] - o[a]) / d[a];
        if (t1 > t2) std::swap(t1, t2);
        tmin = std::max(tmin, t1);
        tmax = std::min(tmax, t2);
        if (tmin > tmax) miss = true;
      }
      if (!miss && tmin > 1e-6 && tmin < best) best = tmin;
    }
    return best;
  }
};

/** Kinect-One-like camera: 512 x 424, 70.6 x 60 deg, 0.5-4.5 m, noise along
 *  the ray growing with range (1.5 mm + 1.5 mm per m, or quadratic_noise t^2). Returns the
 * organised cloud in the robot frame; `camera_frame` (optional) receives the same points in the
 * optical frame (x right, y down, z forward). */
inline Cloud renderDepth(const Scene& s, const mrpt::poses::CPose3D& pose, unsigned seed = 7,
                         double noise_scale = 1.0, Cloud* camera_frame = nullptr, int W = 512,
                         int H = 424, double quadratic_noise = 0.0) {
  const double fx = (W / 2.0) / std::tan(35.3 * M_PI / 180),
               fy = (H / 2.0) / std::tan(30 * M_PI / 180);
  const auto R = pose.getRotationMatrix();
  const double o[3] = {pose.x(), pose.y(), pose.z()};
  std::mt19937 rng(seed);
  std::normal_distribution<double> n01(0, 1);
  Cloud out, cam;
  out.width = cam.width = W;
  out.height = cam.height = H;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int v = 0; v < H; ++v)
    for (int u = 0; u < W; ++u) {
      const double xc = (u + 0.5 - W / 2.0) / fx, yc = (v + 0.5 - H / 2.0) / fy;  // z = 1
      const double ds[3] = {1, -xc, -yc};  // sensor frame (x fwd, y left, z up)
      double d[3];
      for (int i = 0; i < 3; ++i) d[i] = R(i, 0) * ds[0] + R(i, 1) * ds[1] + R(i, 2) * ds[2];
      const double t = s.cast(o, d);  // depth along the optical axis (ds has x = 1)
      const double len = std::sqrt(1 + xc * xc + yc * yc);
      const double range = t * len;
      if (!std::isfinite(t) || t < 0.5 || t > 4.5) {
        out.points.push_back({nan, nan, nan});
        cam.points.push_back({nan, nan, nan});
        continue;
      }
      // quadratic_noise > 0: the simulator's model instead, std quadratic_noise
      // t^2 on the depth t (ini/isr-aiwalker.ini: 5 mm at 1 m).
      const double sd =
          quadratic_noise > 0 ? quadratic_noise * t * t : noise_scale * (0.0015 + 0.0015 * range);
      const double tn = t + sd * n01(rng);
      out.points.push_back({static_cast<float>(o[0] + tn * d[0]),
                            static_cast<float>(o[1] + tn * d[1]),
                            static_cast<float>(o[2] + tn * d[2])});
      cam.points.push_back(
          {static_cast<float>(tn * xc), static_cast<float>(tn * yc), static_cast<float>(tn)});
    }
  if (camera_frame) *camera_frame = cam;
  return out;
}

/** The walker's Kinect: 0.2 m ahead of the axle, 0.9 m high, 30 deg down. */
inline mrpt::poses::CPose3D walkerKinect() {
  return mrpt::poses::CPose3D(0.2, 0, 0.9, 0, 30 * M_PI / 180, 0);
}

}  // namespace carenav_test
