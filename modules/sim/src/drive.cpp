#include <carenav/common/errors.h>
#include <carenav/common/text.h>
#include <carenav/io/number_table.h>
#include <carenav/sim/drive.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace carenav::sim {

namespace {
std::vector<double> numbers(const std::string& text, const std::string& what) {
  std::vector<double> out;
  std::string tok;
  std::stringstream ss(text);
  while (std::getline(ss, tok, ',')) {
    const auto v = parseNumber(tok.substr(0, tok.find_last_not_of(' ') + 1));  // blanks after it
    if (!v) throw InputError(what + ": '" + tok + "' is not a number (in '" + text + "')");
    out.push_back(*v);
  }
  if (!text.empty() && text.back() == ',')
    throw InputError(what + ": missing number after ',' in '" + text + "'");
  return out;
}
}  // namespace

std::vector<Vec2> parsePath(const std::string& text, const std::string& what) {
  std::vector<Vec2> out;
  std::stringstream ss(text);
  std::string pt;
  while (ss >> pt) {
    const auto v = numbers(pt, what);
    if (v.size() != 2)
      throw InputError(what + ": expected points x,y separated by spaces, got '" + pt + "'");
    out.push_back({v[0], v[1]});
  }
  if (out.empty()) throw InputError(what + ": no waypoint (expected \"x,y x,y ...\")");
  return out;
}

Pose2 parseStart(const std::string& text, const std::string& what) {
  const auto v = numbers(text, what);
  if (v.size() != 3) throw InputError(what + ": expected x,y,deg, got '" + text + "'");
  return {v[0], v[1], v[2] * M_PI / 180};
}

WaypointFollower::WaypointFollower(std::vector<Vec2> path, const RobotParams& robot,
                                   double tolerance)
    : path_(std::move(path)), robot_(robot), tol_(tolerance) {}

void WaypointFollower::command(const Pose2& p, double& v, double& w) {
  v = w = 0;
  while (next_ < path_.size()) {
    const bool last = next_ + 1 == path_.size();
    const double d = std::hypot(path_[next_].x - p.x, path_[next_].y - p.y);
    if (d < (last ? tol_ / 2 : tol_))
      ++next_;
    else
      break;
  }
  if (done()) return;
  const Vec2& g = path_[next_];
  const double d = std::hypot(g.x - p.x, g.y - p.y);
  double err = std::atan2(g.y - p.y, g.x - p.x) - p.yaw;
  err = std::atan2(std::sin(err), std::cos(err));
  w = std::clamp(2.0 * err, -robot_.w_max, robot_.w_max);
  if (std::abs(err) > M_PI / 3) return;  // turn on the spot first
  // distance to go along the rest of the path, for braking before the end
  double rest = d;
  for (size_t i = next_ + 1; i < path_.size(); ++i)
    rest += std::hypot(path_[i].x - path_[i - 1].x, path_[i].y - path_[i - 1].y);
  v = robot_.v_max * std::cos(err) * std::cos(err);
  v = std::min(v, std::sqrt(2 * robot_.acc_v * 0.8 * rest));
  v = std::max(v, 0.0);
}

void CommandScript::at(double t, double& v, double& w) const {
  v = w = 0;
  for (const auto& r : rows) {
    if (r.t > t) break;
    v = r.v;
    w = r.w;
  }
}

CommandScript readCommandScript(const std::string& path) {
  CommandScript s;
  const size_t n = io::readNumberRows(path, 3, "t v w", [&](const double* x, int line) {
    if (!s.rows.empty() && x[0] < s.rows.back().t)
      throw InputError(path + ":" + std::to_string(line) + ": time " + std::to_string(x[0]) +
                       " goes back (previous row " + std::to_string(s.rows.back().t) + ")");
    if (x[0] < 0) throw InputError(path + ":" + std::to_string(line) + ": negative time");
    if (x[0] > kMaxSimSeconds)
      throw InputError(path + ":" + std::to_string(line) + ": time " + std::to_string(x[0]) +
                       " s is beyond the longest simulation (" +
                       std::to_string(static_cast<int>(kMaxSimSeconds)) + " s)");
    s.rows.push_back({x[0], x[1], x[2]});
  });
  if (n == 0) throw InputError(path + ": no command rows (expected lines \"t v w\")");
  return s;
}

}  // namespace carenav::sim
