// PCD and PLY readers/writers (formats: PCL's PCD v0.7 and Stanford PLY).
#include <carenav/common/errors.h>
#include <carenav/perception/cloud.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>

namespace carenav::perception {

size_t Cloud::validCount() const {
  return static_cast<size_t>(
      std::count_if(points.begin(), points.end(), [](const Point3f& p) { return validPoint(p); }));
}

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

std::string slurpFile(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw InputError(path + ": cannot open the file");
  std::string s((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  if (s.empty()) throw InputError(path + ": the file is empty");
  return s;
}

std::vector<std::string> tokens(const std::string& line) {
  std::istringstream ss(line);
  std::vector<std::string> out;
  std::string t;
  while (ss >> t) out.push_back(t);
  return out;
}

long toLong(const std::string& path, const std::string& what, const std::string& s) {
  try {
    size_t pos = 0;
    const long v = std::stol(s, &pos);
    if (pos != s.size() || v < 0) throw std::invalid_argument("");
    return v;
  } catch (const std::exception&) {
    throw InputError(path + ": " + what + " is not a non-negative integer: '" + s + "'");
  }
}

double toDouble(const std::string& path, const std::string& where, const std::string& s) {
  const char* b = s.c_str();
  char* e = nullptr;
  const double v = std::strtod(b, &e);
  if (e == b || *e != 0) throw InputError(path + ": " + where + ": not a number: '" + s + "'");
  return v;
}

/** Reads one scalar of the given kind ('F','I','U') and size from bytes. */
double readScalar(const char* p, char type, int size) {
  switch (type) {
    case 'F':
      if (size == 4) {
        float v;
        std::memcpy(&v, p, 4);
        return v;
      } else {
        double v;
        std::memcpy(&v, p, 8);
        return v;
      }
    case 'I':
      if (size == 1) return static_cast<int8_t>(*p);
      if (size == 2) {
        int16_t v;
        std::memcpy(&v, p, 2);
        return v;
      }
      if (size == 4) {
        int32_t v;
        std::memcpy(&v, p, 4);
        return v;
      } else {
        int64_t v;
        std::memcpy(&v, p, 8);
        return static_cast<double>(v);
      }
    default:
      if (size == 1) return static_cast<uint8_t>(*p);
      if (size == 2) {
        uint16_t v;
        std::memcpy(&v, p, 2);
        return v;
      }
      if (size == 4) {
        uint32_t v;
        std::memcpy(&v, p, 4);
        return v;
      } else {
        uint64_t v;
        std::memcpy(&v, p, 8);
        return static_cast<double>(v);
      }
  }
}

/** LZF decompression (the format PCL's binary_compressed uses): a control
 *  byte c < 32 starts a literal run of c+1 bytes; otherwise a back reference
 *  of length (c >> 5) (+ next byte when 7) + 2 at distance ((c & 31) << 8) +
 *  next byte + 1. Returns false on malformed input. */
bool lzfDecompress(const uint8_t* in, size_t n_in, uint8_t* out, size_t n_out) {
  size_t ip = 0, op = 0;
  while (ip < n_in) {
    const unsigned ctrl = in[ip++];
    if (ctrl < 32) {
      const size_t len = ctrl + 1;
      if (ip + len > n_in || op + len > n_out) return false;
      std::memcpy(out + op, in + ip, len);
      ip += len;
      op += len;
    } else {
      size_t len = ctrl >> 5;
      if (len == 7) {
        if (ip >= n_in) return false;
        len += in[ip++];
      }
      if (ip >= n_in) return false;
      const size_t back = ((ctrl & 31u) << 8) + in[ip++] + 1;
      if (back > op) return false;
      len += 2;
      if (op + len > n_out) return false;
      size_t ref = op - back;
      for (size_t k = 0; k < len; ++k) out[op++] = out[ref++];  // may overlap
    }
  }
  return op == n_out;
}

}  // namespace

Cloud readPcd(const std::string& path) {
  const std::string data = slurpFile(path);
  std::vector<std::string> fields, types;
  std::vector<int> sizes, counts;
  long width = -1, height = -1, npoints = -1;
  std::string encoding;
  size_t pos = 0;
  int line_no = 0;
  while (encoding.empty()) {
    if (pos >= data.size())
      throw InputError(path + ": PCD header ends before its DATA line (not a PCD file?)");
    size_t eol = data.find('\n', pos);
    if (eol == std::string::npos) eol = data.size();
    std::string line = data.substr(pos, eol - pos);
    pos = std::min(eol + 1, data.size() + 1);
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    auto t = tokens(line);
    if (t.empty() || t[0][0] == '#') continue;
    const std::string& k = t[0];
    const std::string where = "header line " + std::to_string(line_no) + " (" + k + ")";
    if (k == "VERSION" || k == "VIEWPOINT") continue;
    if (k == "FIELDS") {
      fields.assign(t.begin() + 1, t.end());
    } else if (k == "SIZE") {
      for (size_t i = 1; i < t.size(); ++i) {
        const long s = toLong(path, where, t[i]);
        if (s != 1 && s != 2 && s != 4 && s != 8)
          throw InputError(path + ": " + where + ": field size must be 1, 2, 4 or 8");
        sizes.push_back(static_cast<int>(s));
      }
    } else if (k == "TYPE") {
      for (size_t i = 1; i < t.size(); ++i) {
        if (t[i] != "F" && t[i] != "I" && t[i] != "U")
          throw InputError(path + ": " + where + ": type must be F, I or U, not '" + t[i] + "'");
        types.push_back(t[i]);
      }
    } else if (k == "COUNT") {
      for (size_t i = 1; i < t.size(); ++i)
        counts.push_back(static_cast<int>(toLong(path, where, t[i])));
    } else if (k == "WIDTH" && t.size() == 2) {
      width = toLong(path, where, t[1]);
    } else if (k == "HEIGHT" && t.size() == 2) {
      height = toLong(path, where, t[1]);
    } else if (k == "POINTS" && t.size() == 2) {
      npoints = toLong(path, where, t[1]);
    } else if (k == "DATA" && t.size() == 2) {
      encoding = t[1];
    } else {
      throw InputError(path + ": malformed PCD " + where + ": '" + line + "'");
    }
  }
  if (fields.empty()) throw InputError(path + ": PCD header has no FIELDS line");
  if (counts.empty()) counts.assign(fields.size(), 1);
  if (sizes.size() != fields.size() || types.size() != fields.size() ||
      counts.size() != fields.size())
    throw InputError(path + ": PCD header: FIELDS, SIZE, TYPE and COUNT have different lengths");
  for (size_t i = 0; i < fields.size(); ++i)
    if (types[i] == "F" && sizes[i] != 4 && sizes[i] != 8)
      throw InputError(path + ": PCD header: float field '" + fields[i] + "' has size " +
                       std::to_string(sizes[i]));
  if (width < 0) throw InputError(path + ": PCD header has no WIDTH");
  if (height < 0) height = 1;
  if (npoints < 0) npoints = width * height;
  if (npoints != width * height)
    throw InputError(path + ": PCD header: POINTS " + std::to_string(npoints) +
                     " != WIDTH*HEIGHT " + std::to_string(width * height));
  int ix = -1, iy = -1, iz = -1;
  for (size_t i = 0; i < fields.size(); ++i) {
    if (fields[i] == "x") ix = static_cast<int>(i);
    if (fields[i] == "y") iy = static_cast<int>(i);
    if (fields[i] == "z") iz = static_cast<int>(i);
  }
  if (ix < 0 || iy < 0 || iz < 0)
    throw InputError(path + ": PCD has no x, y and z fields (FIELDS lists none of them)");

  Cloud c;
  c.width = static_cast<size_t>(width);
  c.height = static_cast<size_t>(height);
  const size_t n = static_cast<size_t>(npoints);
  c.points.resize(n);
  // Byte offset of each field inside a record (binary) and token index (ascii).
  std::vector<size_t> off(fields.size()), tok(fields.size());
  size_t rec = 0, ntok = 0;
  for (size_t i = 0; i < fields.size(); ++i) {
    off[i] = rec;
    tok[i] = ntok;
    rec += static_cast<size_t>(sizes[i]) * counts[i];
    ntok += counts[i];
  }
  const int idx[3] = {ix, iy, iz};
  if (encoding == "ascii") {
    std::istringstream ss(data.substr(std::min(pos, data.size())));
    std::string line;
    size_t k = 0;
    while (k < n && std::getline(ss, line)) {
      auto t = tokens(line);
      if (t.empty()) continue;
      if (t.size() != ntok)
        throw InputError(path + ": PCD point " + std::to_string(k) + " has " +
                         std::to_string(t.size()) + " values, the header says " +
                         std::to_string(ntok));
      float v[3];
      for (int a = 0; a < 3; ++a) {
        const std::string& s = t[tok[idx[a]]];
        v[a] = (s == "nan" || s == "NaN" || s == "-nan")
                   ? kNaN
                   : static_cast<float>(toDouble(path, "point " + std::to_string(k), s));
      }
      c.points[k++] = {v[0], v[1], v[2]};
    }
    if (k < n)
      throw InputError(path + ": PCD truncated: " + std::to_string(k) + " of " + std::to_string(n) +
                       " points");
    std::string rest;
    while (std::getline(ss, line))
      if (!tokens(line).empty())
        throw InputError(path + ": PCD has more points than POINTS " + std::to_string(n));
  } else if (encoding == "binary") {
    const size_t need = n * rec;
    if (pos > data.size() || data.size() - pos < need)
      throw InputError(path + ": PCD binary data truncated: " +
                       std::to_string(pos > data.size() ? 0 : data.size() - pos) + " bytes of " +
                       std::to_string(need));
    const char* base = data.data() + pos;
    for (size_t k = 0; k < n; ++k) {
      float v[3];
      for (int a = 0; a < 3; ++a)
        v[a] = static_cast<float>(
            readScalar(base + k * rec + off[idx[a]], types[idx[a]][0], sizes[idx[a]]));
      c.points[k] = {v[0], v[1], v[2]};
    }
  } else if (encoding == "binary_compressed") {
    if (pos > data.size() || data.size() - pos < 8)
      throw InputError(path + ": PCD binary_compressed data truncated (no size header)");
    uint32_t comp = 0, uncomp = 0;
    std::memcpy(&comp, data.data() + pos, 4);
    std::memcpy(&uncomp, data.data() + pos + 4, 4);
    if (uncomp != n * rec)
      throw InputError(path + ": PCD binary_compressed: uncompressed size " +
                       std::to_string(uncomp) + " != POINTS*record " + std::to_string(n * rec));
    if (data.size() - pos - 8 < comp)
      throw InputError(path + ": PCD binary_compressed data truncated: " +
                       std::to_string(data.size() - pos - 8) + " bytes of " + std::to_string(comp));
    std::vector<uint8_t> raw(uncomp);
    if (n > 0 && !lzfDecompress(reinterpret_cast<const uint8_t*>(data.data() + pos + 8), comp,
                                raw.data(), raw.size()))
      throw InputError(path + ": PCD binary_compressed data is corrupt (LZF)");
    // Field-major layout: all values of field 0, then field 1, ...
    std::vector<size_t> foff(fields.size());
    size_t acc = 0;
    for (size_t i = 0; i < fields.size(); ++i) {
      foff[i] = acc;
      acc += n * sizes[i] * counts[i];
    }
    for (size_t k = 0; k < n; ++k) {
      float v[3];
      for (int a = 0; a < 3; ++a) {
        const int f = idx[a];
        v[a] = static_cast<float>(readScalar(
            reinterpret_cast<const char*>(raw.data()) + foff[f] + k * sizes[f] * counts[f],
            types[f][0], sizes[f]));
      }
      c.points[k] = {v[0], v[1], v[2]};
    }
  } else {
    throw InputError(path + ": PCD DATA '" + encoding +
                     "' is not ascii, binary or binary_compressed");
  }
  if (c.height <= 1) c.height = 1;
  return c;
}

Cloud readPly(const std::string& path) {
  const std::string data = slurpFile(path);
  std::istringstream hs(data);
  std::string line;
  if (!std::getline(hs, line) || tokens(line) != std::vector<std::string>{"ply"})
    throw InputError(path + ": not a PLY file (first line is not 'ply')");
  std::string format;
  long nvert = -1;
  bool in_vertex = false, vertex_seen = false, ended = false;
  struct Prop {
    std::string name, type;
    int size;
  };
  std::vector<Prop> props;
  int line_no = 1;
  auto typeSize = [&](const std::string& t) -> int {
    if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
    if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
    if (t == "int" || t == "uint" || t == "float" || t == "int32" || t == "uint32" ||
        t == "float32")
      return 4;
    if (t == "double" || t == "float64") return 8;
    throw InputError(path + ": PLY header line " + std::to_string(line_no) +
                     ": unknown property type '" + t + "'");
  };
  while (std::getline(hs, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    auto t = tokens(line);
    if (t.empty() || t[0] == "comment" || t[0] == "obj_info") continue;
    const std::string where = "PLY header line " + std::to_string(line_no);
    if (t[0] == "format" && t.size() == 3) {
      format = t[1];
    } else if (t[0] == "element" && t.size() == 3) {
      if (t[1] == "vertex") {
        if (vertex_seen) throw InputError(path + ": " + where + ": a second vertex element");
        nvert = toLong(path, where, t[2]);
        in_vertex = vertex_seen = true;
      } else {
        if (!vertex_seen)
          throw InputError(path + ": " + where + ": element '" + t[1] +
                           "' before the vertex element is not supported");
        in_vertex = false;
      }
    } else if (t[0] == "property" && t.size() >= 3) {
      if (in_vertex) {
        if (t[1] == "list")
          throw InputError(path + ": " + where + ": list property in the vertex element");
        props.push_back({t[2], t[1], typeSize(t[1])});
      }
    } else if (t[0] == "end_header") {
      ended = true;
      break;
    } else {
      throw InputError(path + ": malformed " + where + ": '" + line + "'");
    }
  }
  if (!ended) throw InputError(path + ": PLY header has no end_header line");
  if (!vertex_seen) throw InputError(path + ": PLY header has no vertex element");
  int ix = -1, iy = -1, iz = -1;
  for (size_t i = 0; i < props.size(); ++i) {
    if (props[i].name == "x") ix = static_cast<int>(i);
    if (props[i].name == "y") iy = static_cast<int>(i);
    if (props[i].name == "z") iz = static_cast<int>(i);
  }
  if (ix < 0 || iy < 0 || iz < 0)
    throw InputError(path + ": PLY vertex element has no x, y and z properties");
  const size_t n = static_cast<size_t>(nvert);
  Cloud c;
  c.points.resize(n);
  c.width = n;
  c.height = 1;
  const int idx[3] = {ix, iy, iz};
  const size_t body = static_cast<size_t>(hs.tellg());
  if (format == "ascii") {
    size_t k = 0;
    while (k < n && std::getline(hs, line)) {
      auto t = tokens(line);
      if (t.empty()) continue;
      if (t.size() < props.size())
        throw InputError(path + ": PLY vertex " + std::to_string(k) + " has " +
                         std::to_string(t.size()) + " values, the header says " +
                         std::to_string(props.size()));
      float v[3];
      for (int a = 0; a < 3; ++a) {
        const std::string& s = t[idx[a]];
        v[a] = (s == "nan" || s == "NaN" || s == "-nan")
                   ? kNaN
                   : static_cast<float>(toDouble(path, "vertex " + std::to_string(k), s));
      }
      c.points[k++] = {v[0], v[1], v[2]};
    }
    if (k < n)
      throw InputError(path + ": PLY truncated: " + std::to_string(k) + " of " + std::to_string(n) +
                       " vertices");
  } else if (format == "binary_little_endian") {
    std::vector<size_t> off(props.size());
    size_t rec = 0;
    for (size_t i = 0; i < props.size(); ++i) {
      off[i] = rec;
      rec += props[i].size;
    }
    if (data.size() - body < n * rec)
      throw InputError(path + ": PLY binary data truncated: " + std::to_string(data.size() - body) +
                       " bytes of " + std::to_string(n * rec) + " for " + std::to_string(n) +
                       " vertices");
    const char* b = data.data() + body;
    for (size_t k = 0; k < n; ++k) {
      float v[3];
      for (int a = 0; a < 3; ++a) {
        const Prop& p = props[idx[a]];
        const char kind =
            (p.type == "float" || p.type == "double" || p.type == "float32" || p.type == "float64")
                ? 'F'
                : (p.type[0] == 'u' ? 'U' : 'I');
        v[a] = static_cast<float>(readScalar(b + k * rec + off[idx[a]], kind, p.size));
      }
      c.points[k] = {v[0], v[1], v[2]};
    }
  } else if (format.empty()) {
    throw InputError(path + ": PLY header has no format line");
  } else {
    throw InputError(path + ": PLY format '" + format +
                     "' is not supported (ascii or binary_little_endian)");
  }
  return c;
}

Cloud readCloudFile(const std::string& path) {
  std::string ext = path.size() >= 4 ? path.substr(path.size() - 4) : "";
  std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
  if (ext == ".pcd") return readPcd(path);
  if (ext == ".ply") return readPly(path);
  throw InputError(path + ": unknown point cloud format (expected .pcd or .ply)");
}

void writePcd(const std::string& path, const Cloud& c, PcdEncoding enc) {
  std::ofstream f(path, std::ios::binary);
  if (!f) throw InputError(path + ": cannot write the file");
  const bool org = c.organised();
  f << "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\n"
       "TYPE F F F\nCOUNT 1 1 1\nWIDTH "
    << (org ? c.width : c.points.size()) << "\nHEIGHT " << (org ? c.height : 1)
    << "\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << c.points.size() << "\nDATA "
    << (enc == PcdEncoding::Ascii ? "ascii" : "binary") << "\n";
  if (enc == PcdEncoding::Ascii) {
    f.precision(9);
    for (const auto& p : c.points) f << p.x << " " << p.y << " " << p.z << "\n";
  } else {
    f.write(reinterpret_cast<const char*>(c.points.data()),
            static_cast<std::streamsize>(c.points.size() * sizeof(Point3f)));
  }
}

void writePly(const std::string& path, const Cloud& c, PlyEncoding enc) {
  std::ofstream f(path, std::ios::binary);
  if (!f) throw InputError(path + ": cannot write the file");
  f << "ply\nformat " << (enc == PlyEncoding::Ascii ? "ascii" : "binary_little_endian")
    << " 1.0\nelement vertex " << c.points.size()
    << "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  if (enc == PlyEncoding::Ascii) {
    f.precision(9);
    for (const auto& p : c.points) f << p.x << " " << p.y << " " << p.z << "\n";
  } else {
    f.write(reinterpret_cast<const char*>(c.points.data()),
            static_cast<std::streamsize>(c.points.size() * sizeof(Point3f)));
  }
}

}  // namespace carenav::perception
