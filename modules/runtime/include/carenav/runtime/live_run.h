// What the live adapters (the TCP bridge, the ROS navigate node) do alike
// around a NavigationSession: the options they both take, the session's
// setup from them, and the run's metrics by the adapter's own clock.
#pragma once

#include <carenav/runtime/scenario.h>

#include <atomic>
#include <optional>
#include <string>
#include <vector>

namespace mrpt::maps {
class COccupancyGridMap2D;
}

namespace carenav::navigation {

struct SessionSetup;
class NavigationSession;

/** The options every live adapter takes, under the same names. */
struct LiveRunOptions {
  std::string profile;            ///< robot profile
  std::vector<std::string> sets;  ///< profile overrides
  std::string plugin;             ///< local method (default: the profile's)
  std::optional<TPose2D> start;   ///< where the robot is on the map
  double control_rate = 10;       ///< Hz, real time
  double duration = 0;            ///< s; 0: no limit
  std::string out_dir;            ///< run.png, navlog.csv, summary.json; empty: none
  const std::atomic<bool>* stop = nullptr;
  bool progress = false;
};

/** Sets the run's part of a session's setup (the profile's part is read
 *  before, by sessionSetup): its name, what errors name (`origin`), the map
 *  (owned by the caller; null: none), whether to localise on it from
 *  `o.start`, the rate, outputs and status line. */
void applyLiveRun(SessionSetup& s, const LiveRunOptions& o, const std::string& name,
                  const std::string& origin, const mrpt::maps::COccupancyGridMap2D* map,
                  bool localise);

/** Ends a live run's metrics (finishMetrics, then times by the adapter's
 *  clock, `elapsed_s`): with no truth, the goal error is the estimate's. */
RunMetrics& finishLiveMetrics(NavigationSession& session, double elapsed_s);

}  // namespace carenav::navigation
