// What the navigation session records (session.h): the metrics of each
// cycle, the navigation log, the status line, the run's health, and at the
// end its picture and summary.
#include <carenav/common/text.h>
#include <carenav/io/map_io.h>
#include <carenav/runtime/session.h>

#include <unistd.h>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>

namespace carenav::navigation {

namespace fs = std::filesystem;

namespace {

/** Resident memory is sampled every this many seconds of the run, and the
 *  work percentile is reported per window of kWindowSeconds. */
constexpr double kMemorySampleSeconds = 60, kWindowSeconds = 600;

/** Resident memory into the run's samples (none where /proc cannot tell). */
void sampleMemory(RunMetrics& m) {
  const double mb = residentMegabytes();
  if (std::isfinite(mb)) m.rss_mb.push_back(mb);
}

}  // namespace

void appendBounded(std::vector<TPoint2D>& path, const TPoint2D& p) {
  if (path.size() >= kMaxPathPoints) {
    size_t j = 0;
    for (size_t i = 0; i < path.size(); i += 2) path[j++] = path[i];
    path.resize(j);
  }
  path.push_back(p);
}

// One schema for every robot: columns a robot cannot fill (the truth on a
// real robot, its own clock in the simulator) stay empty.
void NavigationSession::openLog() {
  log_.open(fs::path(s_.out_dir) / "navlog.csv");
  log_ << "t,truth_x,truth_y,truth_yaw,est_x,est_y,est_yaw,user_v,user_w,plan_v,plan_w,cmd_v,"
          "cmd_w,action,reason,clearance_m,obstacle_cells,planner_note,collision,recovery,"
          "robot_t,odom_x,odom_y,odom_yaw\n";
}

void NavigationSession::record(double t, const Navigator::Cycle& c,
                               const std::optional<Truth>& truth, double ms) {
  cycle_ms_sum_ += ms;
  m_.cycle_ms_max = std::max(m_.cycle_ms_max, ms);
  ++m_.cycles;
  m_.stops += c.decision.action == SafetyAction::Stop;
  m_.slowed += c.decision.action == SafetyAction::Slow;
  // Clearance and path: the truth's, else the robot's own.
  double cl = c.clearance;
  if (truth) {
    cl = truth->clearance;
    appendBounded(path_, {truth->pose.x, truth->pose.y});
    m_.entered_forbidden = m_.entered_forbidden || truth->forbidden;
    m_.left_map = m_.left_map || truth->off_map;
  } else if (have_odom_) {
    const TPose2D mp = nav_.mapPose();
    if (!path_.empty())
      m_.path_length_m += std::hypot(mp.x - path_.back().x, mp.y - path_.back().y);
    appendBounded(path_, {mp.x, mp.y});
  }
  if (truth || have_odom_) {
    m_.min_clearance_m = std::min(m_.min_clearance_m, cl);
    clear_sum_ += cl;
    ++clear_n_;
  }
  if (!c.recovery.empty()) ++m_.recovery_cycles;
  if (!c.recovery.empty() && last_recovery_.empty()) ++m_.recoveries;
  last_recovery_ = c.recovery;
  // Fidelity where the user's own command is free of collisions.
  if (walker_ && user_)
    if (const auto d = nav_.intentDeviation(*user_, c.decision.cmd)) {
      fid_sum_ += *d;
      ++fid_n_;
    }
  if (m_.cycles == 1 && !s_.out_dir.empty()) openLog();
  if (log_.is_open()) logRow(t, c, truth, cl);
  if (tty_ && k_ % static_cast<size_t>(std::max(1, s_.progress_every)) == 0)
    statusLine(t, c, truth, cl);
}

void NavigationSession::logRow(double t, const Navigator::Cycle& c,
                               const std::optional<Truth>& truth, double cl) {
  const TPose2D est = nav_.mapPose();
  const auto f = [](double v, int prec = 3) { return formatFixed(v, prec); };
  log_ << f(t) << ",";
  if (truth)
    log_ << f(truth->pose.x) << "," << f(truth->pose.y) << "," << f(truth->pose.phi, 4) << ",";
  else
    log_ << ",,,";
  log_ << f(est.x) << "," << f(est.y) << "," << f(est.phi, 4) << "," << (user_ ? f(user_->v) : "")
       << "," << (user_ ? f(user_->w) : "") << "," << f(c.plan.cmd.v) << "," << f(c.plan.cmd.w, 4)
       << "," << f(c.decision.cmd.v) << "," << f(c.decision.cmd.w, 4) << ","
       << safetyActionName(c.decision.action) << ",\"" << c.decision.reason << "\"," << f(cl) << ","
       << c.obstacles << ",\"" << c.plan.note << "\","
       << (truth ? (truth->collided ? "1" : "0") : "") << "," << c.recovery << ","
       << (robot_t_ ? f(*robot_t_) : "") << "," << f(odom_.x) << "," << f(odom_.y) << ","
       << f(odom_.phi, 4) << "\n";
}

void NavigationSession::statusLine(double t, const Navigator::Cycle& c,
                                   const std::optional<Truth>& truth, double cl) {
  const auto f = [](double v, int prec) { return formatFixed(v, prec); };
  std::cerr << "\r[navigate] " << s_.name << " t " << f(t, 1);
  if (std::isfinite(s_.duration)) std::cerr << " / " << f(s_.duration, 0);
  std::cerr << " s";
  if (user_) std::cerr << ", user " << f(user_->v, 2) << " m/s " << f(user_->w, 2) << " rad/s";
  std::cerr << ", cmd " << f(c.decision.cmd.v, 2) << " " << f(c.decision.cmd.w, 2) << " "
            << safetyActionName(c.decision.action) << " " << c.decision.reason << ", clearance "
            << f(cl, 2) << " m";
  if (truth) std::cerr << ", " << truth->collisions << " collisions";
  if (dead_reckoning_) std::cerr << ", localisation: odometry only (nothing in range)";
  std::cerr << "   " << std::flush;
}

// Health of the run: the robot's work per control period (sensor
// processing, localisation, the navigator, replanning), in a histogram of
// fixed size; resident memory sampled every kMemorySampleSeconds.
void NavigationSession::sampleHealth(size_t k) {
  work_all_.add(work_ms_);
  work_window_.add(work_ms_);
  const auto per = [&](double s) { return std::max<size_t>(1, std::llround(s * s_.control_rate)); };
  if (k % per(kMemorySampleSeconds) == 0) sampleMemory(m_);
  if ((k + 1) % per(kWindowSeconds) == 0) {
    m_.work_ms_p99_windows.push_back(work_window_.quantile(0.99));
    work_window_.clear();
  }
}

void NavigationSession::finishMetrics() {
  if (tty_) std::cerr << "\n";
  if (work_window_.count() > 0) m_.work_ms_p99_windows.push_back(work_window_.quantile(0.99));
  m_.work_ms_p99 = work_all_.quantile(0.99);
  m_.work_ms_max = work_all_.max();
  sampleMemory(m_);
  m_.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count();
  m_.mean_clearance_m = clear_n_ ? clear_sum_ / static_cast<double>(clear_n_) : 0;
  m_.cycle_ms_mean = m_.cycles ? cycle_ms_sum_ / static_cast<double>(m_.cycles) : 0;
  m_.perception_ms_mean = m_.depth_frames ? perceive_ms_ / static_cast<double>(m_.depth_frames) : 0;
  m_.intent_fidelity =
      fid_n_ ? fid_sum_ / static_cast<double>(fid_n_) : std::numeric_limits<double>::quiet_NaN();
}

std::vector<io::Overlay> NavigationSession::overlays(std::vector<io::Overlay> extra) const {
  std::vector<io::Overlay> out;
  io::Overlay blue;  // the user's intended path, or the route
  blue.colour = {40, 80, 220};
  if (walker_) {
    blue.points = user_path_;
  } else if (route_) {
    blue.points.push_back(route_origin_);
    blue.points.insert(blue.points.end(), route_->waypoints.begin(), route_->waypoints.end());
  }
  if (walker_ || route_) out.push_back(blue);
  io::Overlay obs;
  obs.points = nav_.obstaclesInMap();
  obs.colour = {255, 140, 0};
  obs.points_only = true;
  out.push_back(obs);
  for (auto& e : extra) out.push_back(std::move(e));
  io::Overlay tr;
  tr.points = path_;
  tr.colour = {220, 30, 30};
  tr.start_end_markers = true;
  out.push_back(tr);
  return out;
}

namespace {

// Without a map: an unknown canvas around what the robot drove and saw, 5
// cm cells, coarser when that is larger than 200 m (at most about 4000
// cells a side).
mrpt::maps::COccupancyGridMap2D canvasAround(const std::vector<io::Overlay>& overlays) {
  double x0 = -1, y0 = -1, x1 = 1, y1 = 1;
  for (const auto& o : overlays)
    for (const auto& p : o.points) {
      x0 = std::min(x0, p.x - 1);
      y0 = std::min(y0, p.y - 1);
      x1 = std::max(x1, p.x + 1);
      y1 = std::max(y1, p.y + 1);
    }
  const double res = std::max(0.05, std::max(x1 - x0, y1 - y0) / 4000);
  return io::makeGrid(x0, y0, res, static_cast<size_t>((x1 - x0) / res) + 1,
                      static_cast<size_t>((y1 - y0) / res) + 1, 0.5f);
}

}  // namespace

void NavigationSession::writeOutputs(const std::string& title, std::vector<io::Overlay> extra) {
  if (s_.out_dir.empty()) return;
  io::RenderOptions ro;
  ro.title = title + " (" + s_.nav.plugin + "): robot red, " +
             (walker_  ? "user's intended path blue, "
              : route_ ? "route blue, "
                       : "") +
             "obstacles orange, " + m_.outcome;
  ro.overlays = overlays(std::move(extra));
  const std::string png = (fs::path(s_.out_dir) / "run.png").string();
  if (s_.map)
    io::renderGridMapPng(*s_.map, png, ro);
  else
    io::renderGridMapPng(canvasAround(ro.overlays), png, ro);
  if (!log_.is_open()) openLog();  // no cycle ran: the header alone
  log_.flush();
  m_.writeSummary(s_.out_dir, png);
}

}  // namespace carenav::navigation
