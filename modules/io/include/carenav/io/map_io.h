// Occupancy grid maps in and out: ROS map_server YAML + PGM/PNG, MRPT
// .gridmap(.gz) and .simplemap(.gz), bare images; cell counts for summaries.
//
// Cell values: mrpt::maps::COccupancyGridMap2D::getCell() returns the
// probability that a cell is FREE (1 = free, 0 = occupied, 0.5 = unknown).
// ROS and this module's thresholds speak of the probability that a cell is
// OCCUPIED, p_occ = 1 - getCell(). Row 0 of an MRPT grid is its lowest y;
// row 0 of a ROS image is its highest y.
#pragma once

#include <carenav/common/errors.h>

#include <mrpt/maps/COccupancyGridMap2D.h>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace carenav::io {

using mrpt::maps::COccupancyGridMap2D;

/** How a cell probability becomes a class. Defaults are map_server's. */
struct OccupancyThresholds {
  /** p_occ above this: occupied (map_server `occupied_thresh`). */
  double occupied = 0.65;
  /** p_occ below this: free (map_server `free_thresh`). */
  double free = 0.196;
};

enum class CellClass : uint8_t { Free, Occupied, Unknown };

/** Class of a cell from MRPT's value (p_free, as getCell returns it). */
CellClass classifyCell(float p_free, const OccupancyThresholds& t = {});

/** Geometry and cell counts of a grid (`map info`, import summaries). */
struct GridStats {
  size_t size_x = 0, size_y = 0;  ///< cells
  double resolution = 0;          ///< metres per cell
  double x_min = 0, y_min = 0;    ///< lower-left corner of cell (0,0), metres
  double x_max = 0, y_max = 0;    ///< upper-right corner of the last cell, metres
  size_t occupied = 0, free = 0, unknown = 0;
  double widthMetres() const { return size_x * resolution; }
  double heightMetres() const { return size_y * resolution; }
  /** Several lines, "key: value" each, for people. */
  std::string toText() const;
  /** A JSON object (no trailing newline); `source` ("file"), `kind` and
   *  `output` ("out") are added when not empty. */
  std::string toJson(const std::string& source = "", const std::string& kind = "",
                     const std::string& output = "") const;
};

GridStats gridStats(const COccupancyGridMap2D& map, const OccupancyThresholds& t = {});

/** An empty grid (every cell `p_free`) whose cell (0,0) has its lower-left
 *  corner exactly at (x_min, y_min). COccupancyGridMap2D::setSize would
 *  round the corner to a multiple of the resolution, moving a ROS map by up
 *  to half a cell. Throws InputError on a size or resolution out of range. */
COccupancyGridMap2D makeGrid(double x_min, double y_min, double resolution, size_t size_x,
                             size_t size_y, float p_free = 0.5f);

// ---------------------------------------------------------------- ROS maps

/** map_server's `mode`. */
enum class RosMapMode { Trinary, Scale, Raw };

/** Options of writeRosMap. */
struct RosMapWriteOptions {
  /** Which cells are written black (occupied) and white (free); the same
   *  values go into the YAML so a reader classifies them back identically. */
  OccupancyThresholds thresholds;
  /** Name of the image, next to the YAML. Empty: the YAML's stem + ".pgm". */
  std::string image_name;
};

/** Writes `yaml_path` and its PGM as ROS map_saver does: an 8-bit binary
 *  PGM (P5) whose first row is the top of the map (highest y), pixel 0 for
 *  occupied, 254 for free and 205 for unknown; the YAML holds the image name
 *  (relative), resolution, origin [x_min, y_min, 0.0] (the lower-left
 *  pixel's corner), negate 0, occupied_thresh and free_thresh. Both files are
 *  written to temporary names and renamed into place. Numbers are written
 *  with the fewest digits that read back as the same float, so a round trip
 *  is exact. Throws std::runtime_error when a file cannot be written. */
void writeRosMap(const COccupancyGridMap2D& map, const std::string& yaml_path,
                 const RosMapWriteOptions& options = {});

/** The contents of a map_server YAML file. */
struct RosMapYaml {
  std::string yaml_path;
  std::string image;                                  ///< as written in the file
  std::string image_path;                             ///< resolved against the YAML's folder
  double resolution = 0;                              ///< metres per pixel
  double origin_x = 0, origin_y = 0, origin_yaw = 0;  ///< lower-left pixel corner
  bool negate = false;
  OccupancyThresholds thresholds;  ///< defaults when the keys are absent
  RosMapMode mode = RosMapMode::Trinary;
};

/** Parses a map_server YAML. `image`, `resolution` and `origin` are
 *  required; `negate` (0), `occupied_thresh` (0.65), `free_thresh` (0.196)
 *  and `mode` (trinary) are optional; other keys are ignored, as map_server
 *  does. Throws InputError naming the file, the line and the key: missing
 *  or duplicated keys, wrong types, resolution <= 0, thresholds out of
 *  order, an image file that does not exist, an empty file. */
RosMapYaml readRosMapYaml(const std::string& yaml_path);

/** Loads a ROS map as map_server does: the image (PGM P5/P2, PPM P6/P3, or
 *  PNG and what else OpenCV decodes) with colour channels averaged, negate,
 *  then p_occ = (255 - value) / 255 and the mode:
 *   - trinary: p_occ > occupied_thresh occupied, < free_thresh free, else unknown;
 *   - scale: the same, but cells in between keep map_server's value
 *     (1 + 98 (p_occ - free_thresh) / (occupied_thresh - free_thresh)) / 100;
 *   - raw: the pixel value v in 0..100 is p_occ = v / 100, other values unknown.
 *  A non-zero origin yaw is supported: the image is resampled (nearest
 *  cell) into an axis-aligned grid covering it; cells outside are unknown.
 *  Throws InputError naming the file for any defect (see readRosMapYaml,
 *  readImageGrey). */
COccupancyGridMap2D readRosMap(const std::string& yaml_path);

/** Largest map image read: 65536 pixels per side and 2^27 pixels in all
 *  (e.g. 11585 x 11585: 579 m square at 5 cm), checked from the header
 *  before anything is allocated. */
inline constexpr uint64_t kMaxImageSide = 65536;
inline constexpr uint64_t kMaxImagePixels = uint64_t{1} << 27;

/** Map resolutions read from files, metres per cell: 1 mm to 100 m (MRPT's
 *  grids hold the resolution as a float; 0 or 1e-300 would become 0). */
inline constexpr double kMinResolution = 0.001;
inline constexpr double kMaxResolution = 100;

/** An 8-bit image reduced to one value per pixel, row 0 at the top. The
 *  channel sum is kept because map_server averages channels in floating
 *  point: a colour pixel's mean need not be a whole number. */
struct GreyImage {
  size_t width = 0, height = 0;
  int channels = 1;            ///< 1 (grey) or 3 (colour)
  std::vector<uint16_t> sums;  ///< width * height channel sums (0..255 * channels), row-major
  double value(size_t i) const { return static_cast<double>(sums[i]) / channels; }
};

/** Reads a PGM (P5, P2) or PPM (P6, P3) with maxval <= 255 (other maxvals
 *  are rescaled to 0..255), or any image OpenCV decodes (PNG...). Colour
 *  pixels become the mean of their channels, as map_server does. Throws
 *  InputError naming the file: missing, empty, bad magic, bad header,
 *  maxval > 255, truncated pixel data, larger than kMaxImagePixels,
 *  undecodable. */
GreyImage readImageGrey(const std::string& path);

/** How image pixels become cells (the part of a ROS YAML about values). */
struct ImageGridOptions {
  double resolution = 0.05;                           ///< metres per pixel
  double origin_x = 0, origin_y = 0, origin_yaw = 0;  ///< lower-left pixel corner
  bool negate = false;
  OccupancyThresholds thresholds;
  RosMapMode mode = RosMapMode::Trinary;
};

/** The grid of an image, as map_server interprets it. */
COccupancyGridMap2D gridFromImage(const GreyImage& img, const ImageGridOptions& options);

// ------------------------------------------------------------- any map

/** What a map file holds, judged by its name (and its first bytes when the
 *  name says nothing). */
enum class MapKind { GridMap, SimpleMap, RosYaml, Image, Rawlog, Unknown };
MapKind mapKindOf(const std::string& path);
const char* mapKindName(MapKind k);

/** Options of loadGridMap. */
struct MapLoadOptions {
  /** Cell size of the grid built from a .simplemap, metres. */
  double simplemap_resolution = 0.05;
  /** Pixel size of a bare .png/.pgm, metres: required for images. */
  std::optional<double> image_resolution;
  /** Lower-left corner of a bare image in the map frame, metres. */
  double image_origin_x = 0, image_origin_y = 0;
  /** Negate and mode for bare images (ROS YAMLs carry their own). */
  bool image_negate = false;
  RosMapMode image_mode = RosMapMode::Trinary;
};

/** Loads any map as a grid:
 *   - .gridmap / .gridmap.gz: an MRPT-serialised COccupancyGridMap2D;
 *   - .yaml / .yml: a ROS map_server map (readRosMap);
 *   - .simplemap / .simplemap.gz: every observation inserted at its pose
 *     into a grid of `simplemap_resolution`;
 *   - .png / .pgm / .ppm: an image with `image_resolution` and origin.
 *  Throws InputError naming the file: missing, empty, truncated, a file of
 *  another kind (e.g. a rawlog, or a .gridmap holding a CSimpleMap: the
 *  message says what it holds and what was expected). */
COccupancyGridMap2D loadGridMap(const std::string& path, const MapLoadOptions& options = {});

/** Writes a grid as an MRPT-serialised COccupancyGridMap2D: gzip for
 *  .gridmap.gz, plain for .gridmap. Written to a temporary name and renamed.
 *  Throws InputError for another extension, std::runtime_error when the
 *  file cannot be written. */
void saveGridMap(const COccupancyGridMap2D& map, const std::string& path);

/** Checks, before any work, that saveMapByExtension can write `path`: a
 *  known extension (.yaml/.yml, .gridmap(.gz), .png; only .gridmap(.gz) when
 *  `gridmap_only`) in an existing folder. Throws InputError otherwise. */
void checkMapOutputPath(const std::string& path, bool gridmap_only = false);

/** Writes a grid in the format its extension names: .yaml/.yml (ROS,
 *  writeRosMap), .gridmap(.gz) (saveGridMap), .png (renderGridMapPng with
 *  default options). Throws InputError for any other extension. */
void saveMapByExtension(const COccupancyGridMap2D& map, const std::string& path);

}  // namespace carenav::io
