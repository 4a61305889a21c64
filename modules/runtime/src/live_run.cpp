#include <carenav/runtime/live_run.h>
#include <carenav/runtime/session.h>

#include <cmath>

namespace carenav::navigation {

void applyLiveRun(SessionSetup& s, const LiveRunOptions& o, const std::string& name,
                  const std::string& origin, const mrpt::maps::COccupancyGridMap2D* map,
                  bool localise) {
  s.name = name;
  s.origin = origin;
  s.map = map;
  s.localise = localise;
  s.start = o.start;
  s.control_rate = o.control_rate;
  s.out_dir = o.out_dir;
  s.progress = o.progress;
  s.progress_every = 2;
  if (o.duration > 0) s.duration = o.duration;
}

RunMetrics& finishLiveMetrics(NavigationSession& session, double elapsed_s) {
  session.finishMetrics();
  RunMetrics& m = session.metrics();
  m.wall_seconds = m.duration_s = elapsed_s;
  m.mean_speed_mps = m.duration_s > 0 ? m.path_length_m / m.duration_s : 0;
  if (!std::isfinite(m.min_clearance_m)) m.min_clearance_m = 0;
  if (const auto& g = session.goal()) {
    const TPose2D mp = session.navigator().mapPose();
    m.final_goal_error_m = std::hypot(mp.x - g->x, mp.y - g->y);
  }
  return m;
}

}  // namespace carenav::navigation
