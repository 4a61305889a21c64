// Grid geometry and statistics, MRPT map files, and loading any map by kind.
#include <carenav/common/crash_guard.h>
#include <carenav/common/errors.h>
#include <carenav/common/json.h>
#include <carenav/io/map_io.h>
#include <carenav/io/map_render.h>

#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/io/CFileOutputStream.h>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose3DPDF.h>
#include <mrpt/serialization/CArchive.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "map_io_internal.h"

namespace carenav::io {

namespace fs = std::filesystem;
using map_detail::endsWith;
using map_detail::toLower;

// ------------------------------------------------------------ helpers

namespace map_detail {

std::string toLower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string floatText(float v) {
  if (v == 0.0f) return "0.0";
  char buf[64];
  for (int d = 1; d <= 20; ++d) {
    std::snprintf(buf, sizeof buf, "%.*f", d, static_cast<double>(v));
    if (std::strtof(buf, nullptr) == v) return buf;
  }
  std::snprintf(buf, sizeof buf, "%.9g", static_cast<double>(v));  // tiny numbers
  return buf;
}

TempFile::TempFile(const std::string& path, const std::string& keep_ext) : target_(path) {
  static std::atomic<unsigned> counter{0};
  const fs::path p(path);
  const std::string name = "." + p.filename().string() + ".tmp" + std::to_string(::getpid()) + "-" +
                           std::to_string(counter++) + keep_ext;
  tmp_ = (p.parent_path() / name).string();
}

TempFile::~TempFile() {
  if (!done_) {
    std::error_code ec;
    fs::remove(tmp_, ec);
  }
}

void TempFile::commit() {
  std::error_code ec;
  fs::rename(tmp_, target_, ec);
  if (ec) throw std::runtime_error(target_ + ": cannot write (" + ec.message() + ")");
  done_ = true;
}

void requireParentFolder(const std::string& path) {
  const fs::path parent = fs::path(path).parent_path();
  std::error_code ec;
  if (!parent.empty() && !fs::is_directory(parent, ec))
    throw InputError(path + ": the folder " + parent.string() + " does not exist");
  if (fs::is_directory(path, ec)) throw InputError(path + ": is a folder, expected a file name");
}

}  // namespace map_detail

namespace {

// MRPT exception texts carry a call stack; keep the message line.
std::string mrptMessage(const std::string& what) {
  const auto m = what.rfind("Message:");  // the innermost (original) exception
  std::string s = m == std::string::npos ? what : what.substr(m + 8);
  s = s.substr(0, s.find('\n'));
  const auto b = s.find_first_not_of(' ');
  s = b == std::string::npos ? what.substr(0, what.find('\n')) : s.substr(b);
  for (auto& c : s)
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = '?';
  return s;
}

// What an MRPT object is, in words a user can act on.
std::string describe(const mrpt::serialization::CSerializable& obj) {
  const std::string cls = obj.GetRuntimeClass()->className;
  if (dynamic_cast<const mrpt::maps::CSimpleMap*>(&obj))
    return cls + " (a simple map: keyframe poses and their observations)";
  if (dynamic_cast<const COccupancyGridMap2D*>(&obj)) return cls + " (an occupancy grid map)";
  if (dynamic_cast<const mrpt::obs::CSensoryFrame*>(&obj) ||
      dynamic_cast<const mrpt::obs::CActionCollection*>(&obj) ||
      dynamic_cast<const mrpt::obs::CObservation*>(&obj))
    return cls + " (a rawlog entry: this looks like a rawlog, not a map)";
  return cls;
}

mrpt::serialization::CSerializable::Ptr readMrptObject(const std::string& path,
                                                       const std::string& expected) {
  mrpt::io::CFileGZInputStream in;
  if (!in.open(path)) throw InputError(path + ": cannot open (permissions?)");
  try {
    // MRPT's deserialisers can crash on corrupt size fields; say where.
    const CrashContext guard(path + ": corrupt " + expected + " (MRPT's reader crashed on it)");
    auto arch = mrpt::serialization::archiveFrom(in);
    auto obj = arch.ReadObject();
    if (!obj) throw InputError(path + ": holds a null object, expected " + expected);
    return obj;
  } catch (const InputError&) {
    throw;
  } catch (const mrpt::serialization::CExceptionEOF&) {
    throw InputError(path + ": truncated: the file ends inside the object, expected a complete " +
                     expected);
  } catch (const std::bad_alloc&) {
    throw InputError(path + ": corrupt " + expected +
                     " (a size field asks for more memory than the memory limit allows)");
  } catch (const std::exception& e) {
    // MRPT wraps the end of file in its own exceptions; gzeof tells.
    if (in.checkEOF() || std::string(e.what()).find("(EOF?)") != std::string::npos)
      throw InputError(path + ": truncated: the file ends inside the object, expected a complete " +
                       expected);
    throw InputError(path + ": not a readable " + expected + " (" + mrptMessage(e.what()) + ")");
  }
}

COccupancyGridMap2D gridFromSimpleMap(const std::string& path, const mrpt::maps::CSimpleMap& sm,
                                      double resolution) {
  if (!(resolution >= 0.001 && resolution <= 100))
    throw InputError(path + ": grid resolution " + std::to_string(resolution) +
                     " m is out of range [0.001, 100]");
  if (sm.empty()) throw InputError(path + ": the simple map has no keyframes");
  const auto r = static_cast<float>(resolution);
  COccupancyGridMap2D g(-5 * r, 5 * r, -5 * r, 5 * r, r);  // grows as scans are inserted
  size_t inserted = 0;
  std::set<std::string> classes;
  for (const auto& pair : sm) {
    if (!pair.pose || !pair.sf) continue;
    const mrpt::poses::CPose3D pose = pair.pose->getMeanVal();
    for (const auto& obs : *pair.sf) {
      if (!obs) continue;
      classes.insert(obs->GetRuntimeClass()->className);
      if (g.insertObservation(*obs, pose)) ++inserted;
    }
  }
  if (inserted == 0) {
    std::string cls;
    for (const auto& c : classes) cls += (cls.empty() ? "" : ", ") + c;
    throw InputError(path + ": no observation in this simple map can be drawn into a 2D grid (" +
                     std::to_string(sm.size()) + " keyframes; observations: " +
                     (cls.empty() ? std::string("none") : cls) + ")");
  }
  return g;
}

// Grids are MRPT's COccupancyGridMap2D; its private corner fields are set
// through a derived class (then sliced off) because setSize() rounds them.
class ExactGrid : public COccupancyGridMap2D {
 public:
  void setGeometry(double x_min, double y_min, double res, size_t sx, size_t sy, float p) {
    setSize(0.0f, static_cast<float>(res), 0.0f, static_cast<float>(res), static_cast<float>(res),
            p);
    m_resolution = static_cast<float>(res);
    m_xMin = static_cast<float>(x_min);
    m_yMin = static_cast<float>(y_min);
    m_xMax = static_cast<float>(x_min + sx * res);
    m_yMax = static_cast<float>(y_min + sy * res);
    m_size_x = static_cast<uint32_t>(sx);
    m_size_y = static_cast<uint32_t>(sy);
    m_map.assign(sx * sy, p2l(p));
    m_likelihoodCacheOutDated = true;
    m_is_empty = false;  // a grid built from data, as a loaded map is
  }
};

}  // namespace

// ------------------------------------------------------------ classes, stats

CellClass classifyCell(float p_free, const OccupancyThresholds& t) {
  const double occ = 1.0 - p_free;
  if (occ > t.occupied) return CellClass::Occupied;
  if (occ < t.free) return CellClass::Free;
  return CellClass::Unknown;
}

GridStats gridStats(const COccupancyGridMap2D& map, const OccupancyThresholds& t) {
  GridStats s;
  s.size_x = map.getSizeX();
  s.size_y = map.getSizeY();
  // MRPT keeps floats: report the decimal they were meant to be (0.05, not
  // 0.0500000007).
  auto decimal = [](float v) { return std::strtod(map_detail::floatText(v).c_str(), nullptr); };
  s.resolution = decimal(map.getResolution());
  s.x_min = decimal(map.getXMin());
  s.y_min = decimal(map.getYMin());
  s.x_max = s.x_min + s.size_x * s.resolution;
  s.y_max = s.y_min + s.size_y * s.resolution;
  // One class per possible raw cell value, instead of one l2p per cell.
  using Cell = COccupancyGridMap2D::cellType;
  using UCell = COccupancyGridMap2D::cellTypeUnsigned;
  static_assert(sizeof(Cell) <= 2, "cell type wider than 16 bits");
  std::vector<uint8_t> lut(size_t{1} << (8 * sizeof(Cell)));
  for (size_t u = 0; u < lut.size(); ++u)
    lut[u] = static_cast<uint8_t>(
        classifyCell(COccupancyGridMap2D::l2p(static_cast<Cell>(static_cast<UCell>(u))), t));
  std::array<size_t, 3> n{0, 0, 0};
  for (Cell c : map.getRawMap()) ++n[lut[static_cast<UCell>(c)]];
  s.free = n[static_cast<int>(CellClass::Free)];
  s.occupied = n[static_cast<int>(CellClass::Occupied)];
  s.unknown = n[static_cast<int>(CellClass::Unknown)];
  return s;
}

std::string GridStats::toText() const {
  char b[1024];
  std::snprintf(b, sizeof b,
                "size: %zu x %zu cells (%.2f x %.2f m)\n"
                "resolution: %g m\n"
                "origin: [%g, %g] (lower-left corner)\n"
                "bounds: x [%g, %g], y [%g, %g] m\n"
                "cells: %zu occupied, %zu free, %zu unknown\n",
                size_x, size_y, widthMetres(), heightMetres(), resolution, x_min, y_min, x_min,
                x_max, y_min, y_max, occupied, free, unknown);
  return b;
}

std::string GridStats::toJson(const std::string& source, const std::string& kind,
                              const std::string& output) const {
  JsonWriter j;
  j.beginObject();
  if (!source.empty()) j.key("file").value(source);
  if (!kind.empty()) j.key("kind").value(kind);
  if (!output.empty()) j.key("out").value(output);
  j.key("size_x").value(static_cast<uint64_t>(size_x));
  j.key("size_y").value(static_cast<uint64_t>(size_y));
  j.key("width_m").value(widthMetres());
  j.key("height_m").value(heightMetres());
  j.key("resolution").value(resolution);
  j.key("x_min").value(x_min);
  j.key("y_min").value(y_min);
  j.key("x_max").value(x_max);
  j.key("y_max").value(y_max);
  j.key("occupied").value(static_cast<uint64_t>(occupied));
  j.key("free").value(static_cast<uint64_t>(free));
  j.key("unknown").value(static_cast<uint64_t>(unknown));
  j.endObject();
  return j.str();
}

COccupancyGridMap2D makeGrid(double x_min, double y_min, double resolution, size_t size_x,
                             size_t size_y, float p_free) {
  if (!(resolution > 0) || !std::isfinite(resolution))
    throw InputError("grid resolution must be > 0, got " + std::to_string(resolution));
  if (!std::isfinite(x_min) || !std::isfinite(y_min))
    throw InputError("grid origin must be finite");
  if (size_x == 0 || size_y == 0 || size_x > 200000 || size_y > 200000 ||
      size_x * size_y > (size_t{1} << 31))
    throw InputError("grid size " + std::to_string(size_x) + " x " + std::to_string(size_y) +
                     " cells is empty or too large");
  ExactGrid g;
  g.setGeometry(x_min, y_min, resolution, size_x, size_y, p_free);
  return COccupancyGridMap2D(static_cast<const COccupancyGridMap2D&>(g));
}

// ------------------------------------------------------------ kinds

MapKind mapKindOf(const std::string& path) {
  const std::string p = toLower(path);
  if (endsWith(p, ".gridmap") || endsWith(p, ".gridmap.gz")) return MapKind::GridMap;
  if (endsWith(p, ".simplemap") || endsWith(p, ".simplemap.gz")) return MapKind::SimpleMap;
  if (endsWith(p, ".yaml") || endsWith(p, ".yml")) return MapKind::RosYaml;
  for (const char* e : {".png", ".pgm", ".ppm", ".pnm", ".bmp", ".jpg", ".jpeg", ".tif", ".tiff"})
    if (endsWith(p, e)) return MapKind::Image;
  if (endsWith(p, ".rawlog") || endsWith(p, ".rawlog.gz")) return MapKind::Rawlog;
  // No telling name: look at the first bytes.
  std::ifstream f(path, std::ios::binary);
  char b[8] = {};
  f.read(b, sizeof b);
  const std::string head(b, static_cast<size_t>(f.gcount()));
  if (head.size() >= 8 && head.compare(0, 8, std::string("\x89PNG\r\n\x1a\n", 8)) == 0)
    return MapKind::Image;
  if (head.size() >= 2 && head[0] == 'P' && std::string("2356").find(head[1]) != std::string::npos)
    return MapKind::Image;
  return MapKind::Unknown;
}

const char* mapKindName(MapKind k) {
  switch (k) {
    case MapKind::GridMap:
      return "gridmap";
    case MapKind::SimpleMap:
      return "simplemap";
    case MapKind::RosYaml:
      return "ros-yaml";
    case MapKind::Image:
      return "image";
    case MapKind::Rawlog:
      return "rawlog";
    case MapKind::Unknown:
      break;
  }
  return "unknown";
}

// ------------------------------------------------------------ load, save

COccupancyGridMap2D loadGridMap(const std::string& path, const MapLoadOptions& o) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path + ": no such file");
  if (fs::is_directory(path, ec)) throw InputError(path + ": is a folder, expected a map file");
  if (fs::file_size(path, ec) == 0) throw InputError(path + ": empty file, expected a map");
  static const char* kExpected =
      "expected a map: .gridmap(.gz), .simplemap(.gz), .yaml (ROS map_server) or .png/.pgm";
  const MapKind kind = mapKindOf(path);
  switch (kind) {
    case MapKind::RosYaml:
      return readRosMap(path);
    case MapKind::Image: {
      if (!o.image_resolution)
        throw InputError(path +
                         ": an image map needs its resolution (metres per pixel; "
                         "--resolution on the command line), or load it through a ROS .yaml");
      ImageGridOptions io;
      io.resolution = *o.image_resolution;
      io.origin_x = o.image_origin_x;
      io.origin_y = o.image_origin_y;
      io.negate = o.image_negate;
      io.mode = o.image_mode;
      if (!(io.resolution > 0) || !std::isfinite(io.resolution))
        throw InputError(path + ": image resolution must be > 0 metres per pixel");
      return gridFromImage(readImageGrey(path), io);
    }
    case MapKind::Rawlog:
      throw InputError(path + ": is a rawlog, not a map; " + kExpected +
                       " (build a map from a rawlog first)");
    case MapKind::GridMap:
    case MapKind::SimpleMap:
    case MapKind::Unknown:
      break;
  }
  const std::string expected = kind == MapKind::GridMap     ? "MRPT gridmap (COccupancyGridMap2D)"
                               : kind == MapKind::SimpleMap ? "MRPT simplemap (CSimpleMap)"
                                                            : "map";
  mrpt::serialization::CSerializable::Ptr obj;
  try {
    obj = readMrptObject(path, expected);
  } catch (const InputError&) {
    if (kind != MapKind::Unknown) throw;
    throw InputError(path + ": unknown map format; " + kExpected);
  }
  if (kind != MapKind::SimpleMap) {
    if (auto g = std::dynamic_pointer_cast<COccupancyGridMap2D>(obj)) {
      // MRPT trusts the stored geometry; a damaged file can hold any.
      const double res = g->getResolution();
      if (!(res > 0) || !std::isfinite(res) || !std::isfinite(g->getXMin()) ||
          !std::isfinite(g->getYMin()) || g->getSizeX() == 0 || g->getSizeY() == 0 ||
          g->getRawMap().size() != size_t{g->getSizeX()} * g->getSizeY())
        throw InputError(path + ": holds an occupancy grid with an invalid geometry (" +
                         std::to_string(g->getSizeX()) + " x " + std::to_string(g->getSizeY()) +
                         " cells, resolution " + std::to_string(res) + " m)");
      return *g;
    }
  }
  if (kind != MapKind::GridMap) {
    if (auto sm = std::dynamic_pointer_cast<mrpt::maps::CSimpleMap>(obj))
      return gridFromSimpleMap(path, *sm, o.simplemap_resolution);
  }
  std::string hint;
  if (kind == MapKind::GridMap && std::dynamic_pointer_cast<mrpt::maps::CSimpleMap>(obj))
    hint = "; name it .simplemap(.gz) to build a grid from it";
  if (kind == MapKind::SimpleMap && std::dynamic_pointer_cast<COccupancyGridMap2D>(obj))
    hint = "; name it .gridmap(.gz) to read it as a grid";
  throw InputError(path + ": holds " + describe(*obj) + ", expected " +
                   (kind == MapKind::Unknown ? std::string(kExpected) : "an " + expected) + hint);
}

void saveGridMap(const COccupancyGridMap2D& map, const std::string& path) {
  const std::string p = toLower(path);
  const bool gz = endsWith(p, ".gridmap.gz");
  if (!gz && !endsWith(p, ".gridmap"))
    throw InputError(path + ": a gridmap file name ends in .gridmap.gz or .gridmap");
  map_detail::requireParentFolder(path);
  map_detail::TempFile tmp(path);
  try {
    if (gz) {
      mrpt::io::CFileGZOutputStream out;
      if (!out.open(tmp.path(), 6)) throw std::runtime_error(path + ": cannot write");
      mrpt::serialization::archiveFrom(out) << map;
      out.close();
    } else {
      mrpt::io::CFileOutputStream out;
      if (!out.open(tmp.path())) throw std::runtime_error(path + ": cannot write");
      mrpt::serialization::archiveFrom(out) << map;
      out.close();
    }
  } catch (const std::runtime_error&) {
    throw;
  } catch (const std::exception& e) {
    throw std::runtime_error(path + ": cannot write (" + mrptMessage(e.what()) + ")");
  }
  tmp.commit();
}

void checkMapOutputPath(const std::string& path, bool gridmap_only) {
  const std::string p = toLower(path);
  const bool gridmap = endsWith(p, ".gridmap") || endsWith(p, ".gridmap.gz");
  if (gridmap_only && !gridmap)
    throw InputError(path + ": a gridmap file name ends in .gridmap.gz or .gridmap");
  if (!gridmap && !endsWith(p, ".yaml") && !endsWith(p, ".yml") && !endsWith(p, ".png"))
    throw InputError(path +
                     ": cannot tell the format from the name; use .yaml (ROS map_server: yaml + "
                     "pgm), .gridmap.gz, .gridmap or .png");
  map_detail::requireParentFolder(path);
}

void saveMapByExtension(const COccupancyGridMap2D& map, const std::string& path) {
  const std::string p = toLower(path);
  if (endsWith(p, ".yaml") || endsWith(p, ".yml")) return writeRosMap(map, path);
  if (endsWith(p, ".gridmap") || endsWith(p, ".gridmap.gz")) return saveGridMap(map, path);
  if (endsWith(p, ".png")) return renderGridMapPng(map, path);
  checkMapOutputPath(path);  // throws: an unknown extension
}

}  // namespace carenav::io
