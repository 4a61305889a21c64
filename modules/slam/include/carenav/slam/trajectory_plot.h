// PNG pictures of planar trajectories (optionally over an occupancy grid) and
// of a value over time, drawn with mrpt::img::CImage; no GUI library.
#pragma once

#include <carenav/io/trajectory.h>
#include <mrpt/img/TColor.h>
#include <mrpt/math/TPoint2D.h>

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace mrpt::maps {
class COccupancyGridMap2D;
}

namespace carenav::slam {

/** One track to draw. */
struct NamedTrajectory {
  std::string name;  ///< legend text
  io::Trajectory2D poses;
  /// Line colour; unset: the next colour of a fixed palette (dark grey, blue,
  /// red, green, orange, purple), so "reference" first reads as the ground truth.
  std::optional<mrpt::img::TColor> color;
  unsigned line_width = 2;  ///< px
};

/** How renderTrajectories() lays out the picture. */
struct PlotOptions {
  int width = 1000;            ///< px
  int height = 0;              ///< px; 0: from the data's aspect ratio (300 .. 1400)
  double margin_ratio = 0.05;  ///< empty space around the data, fraction of its extent
  std::string title;           ///< top-left; empty: none
  bool grid = true;            ///< metric grid with labelled lines every 1, 2 or 5 x 10^k m
  bool scale_bar = true;       ///< bar of a round length, top right above the plot
  bool mark_start_end = true;  ///< circle at the first pose, cross at the last
  /// Thin segments drawn under the tracks, e.g. from each estimated pose to
  /// its reference pose (the ATE residuals).
  std::vector<std::pair<mrpt::math::TPoint2D, mrpt::math::TPoint2D>> links;
  mrpt::img::TColor link_color{255, 170, 170};
  /// Optional map under the tracks (occupied dark, free white, unknown grey);
  /// its extent is part of the fitted area. Not owned.
  const mrpt::maps::COccupancyGridMap2D* background = nullptr;
};

/** Draws the trajectories in metric scale (same scale on both axes, y up),
 *  fitted to the picture with margins, with the legend (names and the
 *  start/end marks), grid and scale bar, and writes a PNG. Empty or all-NaN
 *  tracks are allowed (a blank frame). Throws std::runtime_error when the file
 *  cannot be written. */
void renderTrajectories(const std::vector<NamedTrajectory>& trajs, const std::string& png,
                        const PlotOptions& opts = {});

/** A horizontal line across a series plot (e.g. the RMSE). */
struct SeriesMarker {
  double y = 0;
  std::string label;
};

/** How renderSeries() lays out the picture. */
struct SeriesPlotOptions {
  int width = 1000, height = 400;  ///< px
  std::string title, x_label, y_label;
  std::vector<SeriesMarker> markers;
  mrpt::img::TColor color{31, 119, 180};
};

/** Line plot of y over x (e.g. an error over time), axes from the data's
 *  range (y from 0 when all values are non-negative), labelled ticks. Throws
 *  std::runtime_error when the file cannot be written. */
void renderSeries(const std::vector<double>& x, const std::vector<double>& y,
                  const std::string& png, const SeriesPlotOptions& opts = {});

}  // namespace carenav::slam
