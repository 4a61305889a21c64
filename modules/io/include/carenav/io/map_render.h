// Pictures of occupancy grids with trajectories, places and a scale bar:
// free white, occupied black, unknown grey, north (+y) up like ROS images.
#pragma once

#include <carenav/io/map_io.h>

#include <mrpt/img/CImage.h>
#include <mrpt/math/TPoint2D.h>

#include <cstdint>
#include <string>
#include <vector>

namespace carenav::io {

struct Rgb {
  uint8_t r = 0, g = 0, b = 0;
};

/** A polyline (or a set of points) in map metres drawn over the grid. */
struct Overlay {
  std::vector<mrpt::math::TPoint2D> points;
  Rgb colour{220, 30, 30};
  int thickness = 2;  ///< pixels
  /** A green circle at the first point and a red square at the last. */
  bool start_end_markers = false;
  /** Draw each point as a dot instead of joining them. */
  bool points_only = false;
  /** Text drawn next to the first point (e.g. a place name); empty: none. */
  std::string label;
};

/** Options of renderGridMap. */
struct RenderOptions {
  /** Pixels per cell side; raised so that the picture is at least
   *  `min_width_px` wide (small maps stay readable). */
  int pixels_per_cell = 1;
  int min_width_px = 800;
  /** Cap on either side of the picture, pixels (huge maps stay drawable). */
  int max_side_px = 8000;
  /** Which probabilities are drawn as occupied/free/unknown. */
  OccupancyThresholds thresholds;
  /** Shade every cell by its probability instead of three classes. */
  bool grey_levels = false;
  /** Crop the picture to the known cells plus `crop_margin_m`. */
  bool crop_to_known = false;
  double crop_margin_m = 1.0;
  /** A scale bar at the lower left; its length in metres (0: chosen from
   *  1-2-5 steps so it spans about a fifth of the width). */
  bool scale_bar = true;
  double scale_bar_m = 0;
  /** Text at the top left; empty: none. */
  std::string title;
  std::vector<Overlay> overlays;
};

/** Maps metres to picture pixels (x right, y down). */
struct RenderGeometry {
  double x_min = 0, y_max = 0;  ///< map coordinates of the picture's top-left corner
  double pixels_per_metre = 1;
  int width = 0, height = 0;
  int px(double x) const;
  int py(double y) const;
};

/** Draws the grid (and the overlays) into an RGB image. `geometry`, when
 *  given, receives the metre-to-pixel mapping so callers can draw more. */
mrpt::img::CImage renderGridMap(const COccupancyGridMap2D& map, const RenderOptions& options = {},
                                RenderGeometry* geometry = nullptr);

/** renderGridMap, then saved as PNG (temporary name, then renamed). Throws
 *  std::runtime_error when the file cannot be written. */
void renderGridMapPng(const COccupancyGridMap2D& map, const std::string& path,
                      const RenderOptions& options = {});

}  // namespace carenav::io
