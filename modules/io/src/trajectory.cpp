#include <carenav/common/errors.h>
#include <carenav/io/number_table.h>
#include <carenav/io/trajectory.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace carenav::io {

void writeTum(const std::string& path, const Trajectory2D& traj) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream f(tmp);
    if (!f) throw std::runtime_error(path + ": cannot write the trajectory");
    f << "# timestamp x y z qx qy qz qw\n";
    char buf[256];
    for (const auto& p : traj) {
      std::snprintf(buf, sizeof buf, "%.6f %.6f %.6f 0 0 0 %.9f %.9f\n", p.t, p.x, p.y,
                    std::sin(p.yaw / 2), std::cos(p.yaw / 2));
      f << buf;
    }
    if (!f.flush()) throw std::runtime_error(path + ": cannot write the trajectory");
  }
  std::filesystem::rename(tmp, path);
}

Trajectory2D readTum(const std::string& path, size_t* reordered) {
  Trajectory2D out;
  size_t backwards = 0;
  readNumberRows(path, 8, "t x y z qx qy qz qw", [&](const double* v, int lineno) {
    const double qx = v[4], qy = v[5], qz = v[6], qw = v[7];
    if (qx * qx + qy * qy + qz * qz + qw * qw < 1e-18)
      throw InputError(path + ":" + std::to_string(lineno) + ": zero quaternion");
    if (!out.empty() && v[0] < out.back().t) ++backwards;
    TimedPose2D p;
    p.t = v[0];
    p.x = v[1];
    p.y = v[2];
    // Yaw of the rotation; this form needs no normalised quaternion.
    p.yaw = std::atan2(2 * (qw * qz + qx * qy), qw * qw + qx * qx - qy * qy - qz * qz);
    out.push_back(p);
  });
  if (out.empty()) throw InputError(path + ": no poses in the trajectory file");
  if (backwards)
    std::stable_sort(out.begin(), out.end(),
                     [](const TimedPose2D& a, const TimedPose2D& b) { return a.t < b.t; });
  if (reordered) *reordered = backwards;
  return out;
}

}  // namespace carenav::io
