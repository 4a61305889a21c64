// Tracks of moving obstacles (people) and where they will be: the points
// that moved into open space (FreeSpaceHistory::movedIn) are clustered each
// cycle, clusters are associated with the tracks of the cycle before, and
// each track's velocity is the least-squares slope of its centroids over a
// short window (one cycle's displacement is mostly the noise of which of
// the body's cells happened to be new).
#pragma once

#include <mrpt/math/TPoint2D.h>

#include <utility>
#include <vector>

namespace carenav::navigation {

using mrpt::math::TPoint2D;

/** Settings of the tracker ([navigation] sets gate, from track_gate). */
struct MovingTrackerParams {
  double link = 0.3;  ///< m, points closer than this belong to one cluster
  double gate = 0.6;  ///< m, a cluster continues a track whose predicted centroid is this close
  double max_speed = 1.5;      ///< m/s, estimated speeds are capped here (a person walks below)
  double min_speed = 0.15;     ///< m/s, slower tracks are not swept (centroid jitter)
  double fresh = 0.6;          ///< s, a track seen this recently is walking where it was seen
  double keep = 3.0;           ///< s, a track not seen this long is dropped (till then: hidden)
  double hidden_speed = 0.5;   ///< m/s, a hidden person may be this much farther each second
  double hidden_growth = 0.5;  ///< m, ... up to this much
  double window = 1.5;  ///< s, the velocity is the least-squares slope of the centroids this long
  /** m, a cluster spread farther than this from its centroid is no person
   *  (a wall's face flickering under grazing rays, chained along metres):
   *  it is not tracked, so it neither sweeps a lane nor leaves a hidden
   *  region the size of its spread. A person's body fits well within. */
  double max_radius = 0.6;
  /** Cells (`cell` metres wide) a cluster must cover to start a track: a
   *  body moving in, not the one or two edge cells of a post or a wall that
   *  grazing rays had seen free. (In cluttered worlds holding no people,
   *  the would-be tracks were one cell in the median, and their lanes and
   *  growth closed gaps; a person's moved-in cells at a lidar's ranges: 12
   *  in the median.) A smaller cluster continues a track that exists (a
   *  person partly hidden). */
  int min_cells = 3;
  double cell = 0.05;  ///< m, the grid min_cells counts on (the navigation resolution)
  /** m, a track walks (sweeps a lane, may be hidden nearby) only once its
   *  centroid moved this far within the window: the edge cells of a post
   *  slide around it as the robot passes, their centroid "walking" a few
   *  centimetres; a person walking at 0.5 m/s is this far after 0.4 s. */
  double min_travel = 0.2;
};

/** One tracked moving obstacle (odometry frame). */
struct MovingTrack {
  TPoint2D centroid;    ///< m, centroid of its points at the last sighting
  TPoint2D velocity;    ///< m/s, estimated
  double radius = 0;    ///< m, largest distance of its points from the centroid
  double seen = 0;      ///< s, time of the last sighting
  int sightings = 0;    ///< cycles it was seen in
  bool walked = false;  ///< it was seen walking (min_speed, min_travel) at some time
  std::vector<std::pair<double, TPoint2D>> history;  ///< (time, centroid) within the window
};

class MovingTracker {
 public:
  explicit MovingTracker(const MovingTrackerParams& p = {}) : p_(p) {}
  /** The points that moved in, seen at time `t`. */
  void update(const std::vector<TPoint2D>& moved_in, double t);
  const std::vector<MovingTrack>& tracks() const { return tracks_; }
  /** The points of the last update that belong to a track (that started
   *  or continued one): the moving obstacles; the others are left to the
   *  obstacle memory as what they are, hits. */
  const std::vector<TPoint2D>& bodies() const { return bodies_; }
  /** Where the tracks with a velocity go within `horizon` seconds: points
   *  every `step` metres along each track's velocity from its centroid
   *  (excluded), across a lane as wide as the track's spread (its radius)
   *  plus `widen` on each side. Empty for horizon <= 0. */
  std::vector<TPoint2D> predictedPath(double horizon, double step, double widen = 0) const;
  /** Where people who walked and went out of sight (not seen for more than
   *  `fresh` seconds, but for less than `keep`) may be now: a disc per
   *  track, its radius the track's spread grown by hidden_speed per second
   *  unseen (at most hidden_growth), points every `step` metres. A person
   *  who stepped out of a narrow field of view beside the robot may step
   *  back into it. */
  std::vector<TPoint2D> hiddenRegions(double now, double step) const;
  void clear() { tracks_.clear(); }

 private:
  MovingTrackerParams p_;
  std::vector<MovingTrack> tracks_;
  std::vector<TPoint2D> bodies_;
  double latest_ = -1e300;  // time of the last update
};

/** Single-link clusters of points (link distance `link`): indices per
 *  cluster, in order of their first point. */
std::vector<std::vector<size_t>> clusterPoints(const std::vector<TPoint2D>& pts, double link);
/** m, how far a track's centroid moved over its window (first to last). */
double travelled(const MovingTrack& k);
/** How many distinct cells of a grid `cell` metres wide the points `idx` of
 *  `pts` lie in. */
size_t distinctCells(const std::vector<TPoint2D>& pts, const std::vector<size_t>& idx, double cell);

}  // namespace carenav::navigation
