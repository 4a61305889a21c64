// ROS map_server maps: the YAML description, PGM/PNG images, and the
// pixel-to-cell rules of map_server's loader and map_saver.
#include <carenav/common/errors.h>
#include <carenav/common/file.h>
#include <carenav/common/text.h>
#include <carenav/common/yaml.h>
#include <carenav/io/map_io.h>

#include <mrpt/img/CImage.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <vector>

#include "map_io_internal.h"

namespace carenav::io {

namespace fs = std::filesystem;
using map_detail::endsWith;
using map_detail::toLower;

namespace {

// ------------------------------------------------------------ map_server YAML
//
// A map_server YAML is a flat mapping of scalars plus one short list
// (origin), read by the common YAML reader (lines kept); values nested
// deeper are kept only as "nested", for the keys carenav does not read.

struct YamlValue {
  int line = 0;
  bool is_list = false;
  bool is_nested = false;  ///< a mapping or something else we do not read
  std::string scalar;
  std::vector<std::string> items;
};

class YamlError {
 public:
  YamlError(std::string path) : path_(std::move(path)) {}
  [[noreturn]] void at(int line, const std::string& what) const {
    throw InputError(path_ + ":" + std::to_string(line) + ": " + what);
  }
  [[noreturn]] void file(const std::string& what) const { throw InputError(path_ + ": " + what); }

 private:
  std::string path_;
};

/** A list item as text, for messages ("[1, 2]" for a nested list). */
std::string itemText(const yaml::Node& n) {
  if (n.kind == yaml::Node::Kind::Scalar) return n.scalar;
  if (n.kind == yaml::Node::Kind::Map) return "{...}";
  std::string s = "[";
  for (size_t i = 0; i < n.seq.size(); ++i) s += (i ? ", " : "") + itemText(n.seq[i]);
  return s + "]";
}

std::map<std::string, YamlValue> parseFlatYaml(const std::string& path, const std::string& text) {
  const YamlError err(path);
  const yaml::Node root = yaml::parse(text, path);
  if (root.kind != yaml::Node::Kind::Map)
    err.at(root.line, "expected 'key: value', got '" + itemText(root) + "'");
  std::map<std::string, YamlValue> out;
  for (size_t i = 0; i < root.map.size(); ++i) {
    const yaml::Node& n = root.map[i].second;
    YamlValue v;
    v.line = root.key_lines[i];
    v.is_nested = n.kind == yaml::Node::Kind::Map;
    v.is_list = n.kind == yaml::Node::Kind::Seq;
    for (const yaml::Node& item : n.seq) v.items.push_back(itemText(item));
    v.scalar = n.scalar;
    out[root.map[i].first] = v;
  }
  return out;
}

bool parseDouble(const std::string& s, double& out) {
  const auto v = parseNumber(s);
  if (v) out = *v;
  return v.has_value();
}

// ------------------------------------------------------------ images

/** The bytes of a map file; `what` names it in messages ("an image"). */
std::string readMapFile(const std::string& path, const std::string& what,
                        std::uintmax_t max_bytes) {
  return readWholeFile(
      path, {"no such file", "is a folder, expected " + what, "cannot open (permissions?)", what},
      max_bytes);
}

/** Refuses an image larger than kMaxImageSide per side or kMaxImagePixels in
 *  all before anything is allocated for it. */
void checkImageSize(const std::string& path, uint64_t w, uint64_t h) {
  if (w > kMaxImageSide || h > kMaxImageSide || w * h > kMaxImagePixels)
    throw InputError(path + ": image size " + std::to_string(w) + " x " + std::to_string(h) +
                     " is too large (at most " + std::to_string(kMaxImageSide) + " per side and " +
                     std::to_string(kMaxImagePixels) + " pixels)");
}

/** A PNG's declared size, from its IHDR chunk (bytes 16-23, big-endian). */
void checkPngSize(const std::string& path, const std::string& data) {
  if (data.size() < 24 || data.compare(12, 4, "IHDR") != 0)
    throw InputError(path + ": PNG without its IHDR header chunk (corrupt or truncated)");
  auto be32 = [&](size_t at) {
    uint64_t v = 0;
    for (size_t k = 0; k < 4; ++k) v = (v << 8) | static_cast<unsigned char>(data[at + k]);
    return v;
  };
  checkImageSize(path, be32(16), be32(20));
}

// A PNM header: magic, width, height, maxval with blanks and comments between.
class PnmParser {
 public:
  PnmParser(const std::string& path, const std::string& data) : path_(path), d_(data) {}

  GreyImage parse() {
    const char kind = d_[1];
    const bool ascii = kind == '2' || kind == '3';
    const int channels = (kind == '3' || kind == '6') ? 3 : 1;
    pos_ = 2;
    const uint64_t w = headerNumber("width");
    const uint64_t h = headerNumber("height");
    const uint64_t maxval = headerNumber("maxval");
    if (w == 0 || h == 0)
      fail("image size " + std::to_string(w) + " x " + std::to_string(h) + " is empty");
    checkImageSize(path_, w, h);
    if (maxval == 0) fail("maxval 0 is invalid");
    if (maxval > 255)
      fail("maxval " + std::to_string(maxval) + " > 255: 16-bit images are not supported");
    // Exactly one blank separates the header from binary pixel data.
    if (pos_ >= d_.size() || !std::isspace(static_cast<unsigned char>(d_[pos_])))
      fail("truncated header (no pixel data after maxval)");
    ++pos_;
    GreyImage img;
    img.width = w;
    img.height = h;
    img.channels = channels;
    const uint64_t n = w * h * channels;
    // The pixels must be in the file before any room is made for them: n bytes
    // (binary), at least 2 n (ascii: a digit and a blank each).
    const uint64_t avail = d_.size() - pos_;
    if (avail < (ascii ? 2 * n - 1 : n))
      fail("truncated pixel data: " + std::to_string(avail) + " bytes for " + std::to_string(w) +
           " x " + std::to_string(h) + (channels == 3 ? " x 3" : "") + " = " + std::to_string(n) +
           " values");
    img.sums.resize(w * h);
    auto scale = [&](uint64_t v) -> uint16_t {
      return static_cast<uint16_t>(maxval == 255 ? v : (v * 255 + maxval / 2) / maxval);
    };
    if (!ascii) {
      const auto* p = reinterpret_cast<const unsigned char*>(d_.data() + pos_);
      for (uint64_t i = 0; i < w * h; ++i) {
        uint16_t s = 0;
        for (int c = 0; c < channels; ++c) {
          const unsigned v = p[i * channels + c];
          if (v > maxval)
            fail("pixel value " + std::to_string(v) + " > maxval " + std::to_string(maxval));
          s += scale(v);
        }
        img.sums[i] = s;
      }
    } else {
      for (uint64_t i = 0; i < w * h; ++i) {
        uint16_t s = 0;
        for (int c = 0; c < channels; ++c) {
          skipBlanks();
          if (pos_ >= d_.size())
            fail("truncated pixel data: " + std::to_string(i) + " of " + std::to_string(w * h) +
                 " pixels");
          const uint64_t v = number("pixel value");
          if (v > maxval)
            fail("pixel value " + std::to_string(v) + " > maxval " + std::to_string(maxval));
          s += scale(v);
        }
        img.sums[i] = s;
      }
    }
    return img;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const { throw InputError(path_ + ": " + what); }
  void skipBlanks() {
    while (pos_ < d_.size()) {
      const char c = d_[pos_];
      if (c == '#') {
        while (pos_ < d_.size() && d_[pos_] != '\n') ++pos_;
      } else if (std::isspace(static_cast<unsigned char>(c))) {
        ++pos_;
      } else {
        break;
      }
    }
  }
  uint64_t number(const char* what) {
    uint64_t v = 0;
    size_t digits = 0;
    while (pos_ < d_.size() && std::isdigit(static_cast<unsigned char>(d_[pos_]))) {
      v = v * 10 + static_cast<uint64_t>(d_[pos_++] - '0');
      if (++digits > 12) fail(std::string("absurd ") + what);
    }
    if (digits == 0)
      fail(std::string("bad ") + what + " (expected a number" +
           (pos_ < d_.size() ? ", got '" + std::string(1, d_[pos_]) + "'" : ", got end of file") +
           ")");
    return v;
  }
  uint64_t headerNumber(const char* what) {
    skipBlanks();
    if (pos_ >= d_.size()) fail(std::string("truncated header (no ") + what + ")");
    return number(what);
  }

  std::string path_;
  const std::string& d_;
  size_t pos_ = 0;
};

GreyImage decodeWithOpenCv(const std::string& path) {
  mrpt::img::CImage img;
  bool ok = false;
  try {
    ok = img.loadFromFile(path, 1);  // 3 channels, the alpha channel dropped
  } catch (const std::exception&) {
    ok = false;
  }
  if (!ok || img.getWidth() == 0 || img.getHeight() == 0)
    throw InputError(path + ": cannot decode the image (corrupt or truncated?)");
  GreyImage out;
  out.width = img.getWidth();
  out.height = img.getHeight();
  out.channels = img.channelCount() >= 3 ? 3 : 1;
  out.sums.resize(out.width * out.height);
  for (size_t r = 0; r < out.height; ++r) {
    const uint8_t* row = img.ptrLine<uint8_t>(r);
    for (size_t c = 0; c < out.width; ++c) {
      uint16_t s = 0;
      for (int k = 0; k < out.channels; ++k) s += row[c * out.channels + k];
      out.sums[r * out.width + c] = s;
    }
  }
  return out;
}

// Reads everything a map_server YAML entry refers to as a number.
double yamlNumber(const std::map<std::string, YamlValue>& y, const std::string& key,
                  const YamlError& err, std::optional<double> fallback) {
  const auto it = y.find(key);
  if (it == y.end()) {
    if (fallback) return *fallback;
    err.file("missing key '" + key + "' (a map_server YAML needs image, resolution and origin)");
  }
  const YamlValue& v = it->second;
  double d = 0;
  if (v.is_list || v.is_nested || !parseDouble(v.scalar, d))
    err.at(v.line, "'" + key + "' must be a number, got " +
                       (v.is_list     ? std::string("a list")
                        : v.is_nested ? std::string("a mapping")
                                      : "'" + v.scalar + "'"));
  return d;
}

}  // namespace

// ------------------------------------------------------------ public

RosMapYaml readRosMapYaml(const std::string& yaml_path) {
  const YamlError err(yaml_path);
  const std::string text = readMapFile(yaml_path, "a ROS map YAML file", kMaxTextFileBytes);
  if (yaml::isBlank(text))
    err.file(std::string(text.empty() ? "empty file" : "empty file (only blanks and comments)") +
             ", expected a ROS map_server YAML (image, resolution, origin)");
  const auto y = parseFlatYaml(yaml_path, text);

  RosMapYaml m;
  m.yaml_path = yaml_path;

  const auto img = y.find("image");
  if (img == y.end())
    err.file("missing key 'image' (a map_server YAML needs image, resolution and origin)");
  if (img->second.is_list || img->second.is_nested || img->second.scalar.empty())
    err.at(img->second.line, "'image' must be a file name");
  m.image = img->second.scalar;
  const fs::path ip(m.image);
  m.image_path = ip.is_absolute()
                     ? ip.string()
                     : (fs::path(yaml_path).parent_path() / ip).lexically_normal().string();
  if (m.image_path.empty()) m.image_path = m.image;
  std::error_code ec;
  if (!fs::is_regular_file(m.image_path, ec))
    err.at(img->second.line, "image '" + m.image + "' not found (looked for " + m.image_path + ")");

  m.resolution = yamlNumber(y, "resolution", err, std::nullopt);
  if (!(m.resolution > 0))
    err.at(y.at("resolution").line,
           "'resolution' must be > 0 metres per pixel, got " + y.at("resolution").scalar);
  if (!(m.resolution >= kMinResolution && m.resolution <= kMaxResolution))
    err.at(y.at("resolution").line,
           "'resolution' must be within [0.001, 100] metres per pixel, got " +
               y.at("resolution").scalar);

  const auto org = y.find("origin");
  if (org == y.end())
    err.file("missing key 'origin' (a map_server YAML needs image, resolution and origin)");
  {
    const YamlValue& v = org->second;
    double xyz[3];
    bool ok = v.is_list && v.items.size() == 3;
    for (size_t i = 0; ok && i < 3; ++i) ok = parseDouble(v.items[i], xyz[i]);
    if (!ok) {
      std::string got = v.scalar;
      if (v.is_list) {
        got = "[";
        for (size_t i = 0; i < v.items.size(); ++i) got += (i ? ", " : "") + v.items[i];
        got += "]";
      }
      err.at(v.line, "'origin' must be a list of 3 numbers [x, y, yaw], got " +
                         (v.is_nested ? std::string("a mapping") : got));
    }
    m.origin_x = xyz[0];
    m.origin_y = xyz[1];
    m.origin_yaw = xyz[2];
  }

  if (const auto it = y.find("negate"); it != y.end()) {
    const std::string s = toLower(it->second.scalar);
    if (s == "0" || s == "false")
      m.negate = false;
    else if (s == "1" || s == "true")
      m.negate = true;
    else
      err.at(it->second.line, "'negate' must be 0 or 1, got '" + it->second.scalar + "'");
  }
  m.thresholds.occupied = yamlNumber(y, "occupied_thresh", err, 0.65);
  m.thresholds.free = yamlNumber(y, "free_thresh", err, 0.196);
  auto lineOf = [&](const char* k) { return y.count(k) ? y.at(k).line : 0; };
  if (m.thresholds.occupied < 0 || m.thresholds.occupied > 1)
    err.at(lineOf("occupied_thresh"), "'occupied_thresh' must be in [0, 1]");
  if (m.thresholds.free < 0 || m.thresholds.free > 1)
    err.at(lineOf("free_thresh"), "'free_thresh' must be in [0, 1]");
  if (m.thresholds.free > m.thresholds.occupied)
    err.at(std::max(lineOf("free_thresh"), lineOf("occupied_thresh")),
           "'free_thresh' must not exceed 'occupied_thresh'");
  if (const auto it = y.find("mode"); it != y.end()) {
    const std::string s = toLower(it->second.scalar);
    if (s == "trinary")
      m.mode = RosMapMode::Trinary;
    else if (s == "scale")
      m.mode = RosMapMode::Scale;
    else if (s == "raw")
      m.mode = RosMapMode::Raw;
    else
      err.at(it->second.line,
             "'mode' must be trinary, scale or raw, got '" + it->second.scalar + "'");
  }
  return m;
}

GreyImage readImageGrey(const std::string& path) {
  // At most 16-bit RGB pixels of the largest image accepted, plus a header.
  const std::string data = readMapFile(path, "an image", 6 * kMaxImagePixels + 4096);
  if (data.empty()) throw InputError(path + ": empty file, expected an image");
  const std::string ext = toLower(fs::path(path).extension().string());
  const bool pnm_ext = ext == ".pgm" || ext == ".ppm" || ext == ".pnm";
  if (data.size() >= 2 && data[0] == 'P' &&
      (data[1] == '2' || data[1] == '3' || data[1] == '5' || data[1] == '6'))
    return PnmParser(path, data).parse();
  auto magicText = [&] {
    std::string m;
    for (size_t i = 0; i < std::min<size_t>(4, data.size()); ++i) {
      const unsigned char c = data[i];
      m += (c >= 0x20 && c < 0x7f) ? std::string(1, static_cast<char>(c)) : std::string("?");
    }
    return m;
  };
  if (pnm_ext ||
      (data.size() >= 2 && data[0] == 'P' && std::isdigit(static_cast<unsigned char>(data[1]))))
    throw InputError(path + ": bad magic '" + magicText() +
                     "', expected a PGM (P5 or P2) or PPM (P6 or P3) image");
  static const char kPng[] = "\x89PNG\r\n\x1a\n";
  const bool png = data.compare(0, 8, std::string(kPng, 8)) == 0;
  if (ext == ".png" && !png)
    throw InputError(path + ": bad magic '" + magicText() + "', not a PNG image");
  // Caught here, a cut PNG gets a clear message (libpng would only complain
  // on stderr): its last chunk, IEND, is missing.
  if (png && data.find("IEND", data.size() > 64 ? data.size() - 64 : 0) == std::string::npos)
    throw InputError(path + ": truncated PNG (no IEND chunk at the end); cannot decode the image");
  if (png) checkPngSize(path, data);
  return decodeWithOpenCv(path);
}

COccupancyGridMap2D gridFromImage(const GreyImage& img, const ImageGridOptions& o) {
  if (!(o.resolution >= kMinResolution && o.resolution <= kMaxResolution))
    throw InputError("image resolution must be within [0.001, 100] metres per pixel");
  const size_t w = img.width, h = img.height;
  using Cell = COccupancyGridMap2D::cellType;
  const Cell occupied = COccupancyGridMap2D::p2l(0.0f);
  const Cell freec = COccupancyGridMap2D::p2l(1.0f);
  const Cell unknown = COccupancyGridMap2D::p2l(0.5f);
  const OccupancyThresholds& t = o.thresholds;
  // Cell value of every pixel, in image order (row 0 at the top).
  auto cellOf = [&](size_t i) -> Cell {
    double avg = static_cast<double>(img.sums[i]) / img.channels;
    if (o.negate) avg = 255.0 - avg;
    if (o.mode == RosMapMode::Raw) {
      const auto v = static_cast<unsigned>(avg);  // map_server truncates too
      return v <= 100 ? COccupancyGridMap2D::p2l(1.0f - v / 100.0f) : unknown;
    }
    const double occ = (255.0 - avg) / 255.0;
    if (occ > t.occupied) return occupied;
    if (occ < t.free) return freec;
    if (o.mode == RosMapMode::Trinary || t.occupied <= t.free) return unknown;
    const double ratio = (occ - t.free) / (t.occupied - t.free);
    const double pct = 1.0 + 98.0 * ratio;
    return COccupancyGridMap2D::p2l(static_cast<float>(1.0 - pct / 100.0));
  };

  const double yaw = o.origin_yaw;
  if (std::abs(yaw) < 1e-12) {
    COccupancyGridMap2D g = makeGrid(o.origin_x, o.origin_y, o.resolution, w, h);
    for (size_t r = 0; r < h; ++r) {
      Cell* row = g.getRow(static_cast<int>(h - 1 - r));  // image top = highest y
      for (size_t c = 0; c < w; ++c) row[c] = cellOf(r * w + c);
    }
    return g;
  }
  // Rotated origin: resample into the axis-aligned box around the image,
  // each cell taking the pixel under its centre.
  const double cy = std::cos(yaw), sy = std::sin(yaw);
  const double W = w * o.resolution, H = h * o.resolution;
  double xs[4], ys[4];
  const double lx[4] = {0, W, 0, W}, ly[4] = {0, 0, H, H};
  for (int k = 0; k < 4; ++k) {
    xs[k] = o.origin_x + cy * lx[k] - sy * ly[k];
    ys[k] = o.origin_y + sy * lx[k] + cy * ly[k];
  }
  const double x0 = *std::min_element(xs, xs + 4), x1 = *std::max_element(xs, xs + 4);
  const double y0 = *std::min_element(ys, ys + 4), y1 = *std::max_element(ys, ys + 4);
  const auto nx = static_cast<size_t>(std::ceil((x1 - x0) / o.resolution - 1e-9));
  const auto ny = static_cast<size_t>(std::ceil((y1 - y0) / o.resolution - 1e-9));
  COccupancyGridMap2D g =
      makeGrid(x0, y0, o.resolution, std::max<size_t>(nx, 1), std::max<size_t>(ny, 1));
  for (size_t j = 0; j < g.getSizeY(); ++j) {
    Cell* row = g.getRow(static_cast<int>(j));
    const double y = y0 + (j + 0.5) * o.resolution - o.origin_y;
    for (size_t i = 0; i < g.getSizeX(); ++i) {
      const double x = x0 + (i + 0.5) * o.resolution - o.origin_x;
      const double u = (cy * x + sy * y) / o.resolution;   // image column
      const double v = (-sy * x + cy * y) / o.resolution;  // image row from the bottom
      if (u < 0 || v < 0 || u >= w || v >= h) continue;
      const auto c = static_cast<size_t>(u), rb = static_cast<size_t>(v);
      row[i] = cellOf((h - 1 - rb) * w + c);
    }
  }
  return g;
}

COccupancyGridMap2D readRosMap(const std::string& yaml_path) {
  const RosMapYaml y = readRosMapYaml(yaml_path);
  ImageGridOptions o;
  o.resolution = y.resolution;
  o.origin_x = y.origin_x;
  o.origin_y = y.origin_y;
  o.origin_yaw = y.origin_yaw;
  o.negate = y.negate;
  o.thresholds = y.thresholds;
  o.mode = y.mode;
  GreyImage img;
  try {
    img = readImageGrey(y.image_path);
  } catch (const InputError& e) {
    throw InputError(std::string(e.what()) + " (the image of " + yaml_path + ")");
  }
  return gridFromImage(img, o);
}

void writeRosMap(const COccupancyGridMap2D& map, const std::string& yaml_path,
                 const RosMapWriteOptions& options) {
  map_detail::requireParentFolder(yaml_path);
  const size_t w = map.getSizeX(), h = map.getSizeY();
  if (w == 0 || h == 0) throw InputError(yaml_path + ": the map has no cells to write");
  const fs::path yp(yaml_path);
  const std::string image_name =
      options.image_name.empty() ? yp.stem().string() + ".pgm" : options.image_name;
  const std::string image_path = (yp.parent_path() / image_name).string();
  const OccupancyThresholds& t = options.thresholds;

  // map_saver: black occupied, white (254) free, grey 205 unknown; top row first.
  std::string pgm;
  char header[128];
  std::snprintf(header, sizeof header, "P5\n# CREATOR: carenav %.3f m/pix\n%zu %zu\n255\n",
                map.getResolution(), w, h);
  pgm = header;
  const size_t head = pgm.size();
  pgm.resize(head + w * h);
  for (size_t r = 0; r < h; ++r) {
    const size_t cy = h - 1 - r;
    for (size_t cx = 0; cx < w; ++cx) {
      const float p = map.getCell(static_cast<int>(cx), static_cast<int>(cy));
      const CellClass k = classifyCell(p, t);
      pgm[head + r * w + cx] = static_cast<char>(k == CellClass::Occupied ? 0
                                                 : k == CellClass::Free   ? 254
                                                                          : 205);
    }
  }
  std::string yaml = "image: " + image_name + "\n";
  yaml += "resolution: " + map_detail::floatText(map.getResolution()) + "\n";
  yaml += "origin: [" + map_detail::floatText(map.getXMin()) + ", " +
          map_detail::floatText(map.getYMin()) + ", 0.0]\n";
  yaml += "negate: 0\n";
  char th[96];
  std::snprintf(th, sizeof th, "occupied_thresh: %.15g\nfree_thresh: %.15g\n", t.occupied, t.free);
  yaml += th;

  auto put = [](const std::string& path, const std::string& bytes) {
    std::ofstream f(path, std::ios::binary);
    f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    f.flush();
    if (!f) throw std::runtime_error(path + ": cannot write");
  };
  map_detail::TempFile tpgm(image_path), tyaml(yaml_path);
  put(tpgm.path(), pgm);
  put(tyaml.path(), yaml);
  // The image first: a YAML never names an image that is not there yet.
  tpgm.commit();
  tyaml.commit();
}

}  // namespace carenav::io
