// PCD and PLY readers/writers (formats: PCL's PCD v0.7 and Stanford PLY).
#include <carenav/common/errors.h>
#include <carenav/common/text.h>
#include <carenav/perception/cloud.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <optional>
#include <sstream>

namespace carenav::perception {

size_t Cloud::validCount() const {
  return static_cast<size_t>(
      std::count_if(points.begin(), points.end(), [](const Point3f& p) { return validPoint(p); }));
}

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

/** `s` made safe to print: at most `max_len` characters, every byte outside
 *  printable ASCII written as \xHH (a PNG given as .pcd must not send binary
 *  bytes to the terminal). */
std::string printable(const std::string& s, size_t max_len = 60) {
  static const char* hex = "0123456789abcdef";
  std::string out;
  for (size_t i = 0; i < s.size() && i < max_len; ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      out += "\\x";
      out += hex[c >> 4];
      out += hex[c & 15];
    }
  }
  if (s.size() > max_len) out += "...";
  return out;
}

/** True when a header line holds bytes no text header has (NUL and other
 *  control characters than tab/CR; UTF-8 in comments is fine). */
bool binaryBytes(const std::string& line) {
  for (char ch : line) {
    const auto c = static_cast<unsigned char>(ch);
    if ((c < 0x20 && c != '\t' && c != '\r') || c == 0x7f) return true;
  }
  return false;
}

constexpr size_t kMaxHeaderLine = 65536;

/** a * b, or nullopt when it overflows size_t. */
std::optional<size_t> mulSize(size_t a, size_t b) {
  size_t r = 0;
  if (__builtin_mul_overflow(a, b, &r)) return std::nullopt;
  return r;
}

std::string slurpFile(const std::string& path) {
  std::ifstream f(path, std::ios::binary | std::ios::ate);
  if (!f) throw InputError(path + ": cannot open the file");
  const std::streamoff size = f.tellg();
  if (size < 0) throw InputError(path + ": cannot read the file (not a regular file?)");
  if (static_cast<uint64_t>(size) > kMaxCloudFileBytes)
    throw InputError(path + ": the file has " + std::to_string(size) +
                     " bytes, more than the limit for a point cloud file (" +
                     std::to_string(kMaxCloudFileBytes) + ")");
  if (size == 0) throw InputError(path + ": the file is empty");
  f.seekg(0);
  std::string s(static_cast<size_t>(size), '\0');
  f.read(s.data(), size);
  if (f.gcount() != size) throw InputError(path + ": cannot read the whole file");
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
    throw InputError(path + ": " + what + " is not a non-negative integer: '" + printable(s) + "'");
  }
}

double toDouble(const std::string& path, const std::string& where, const std::string& s) {
  const auto v = parseNumber(s, NonFinite::Saturate);
  if (!v) throw InputError(path + ": " + where + ": not a number: '" + printable(s) + "'");
  return *v;
}

/** Refuses a declared point count that exceeds the documented limit or that
 *  the bytes left in the file cannot hold (`min_bytes_per_point` each). */
void checkDeclaredPoints(const std::string& path, const std::string& what, size_t n,
                         size_t bytes_left, size_t min_bytes_per_point) {
  if (n > kMaxCloudPoints)
    throw InputError(path + ": " + what + " declares " + std::to_string(n) +
                     " points, more than the limit of " + std::to_string(kMaxCloudPoints));
  const auto need = mulSize(n, min_bytes_per_point);
  if (!need || *need > bytes_left + 1)  // + 1: the last line may lack its newline
    throw InputError(path + ": " + what + " declares " + std::to_string(n) + " points but the " +
                     std::to_string(bytes_left) + " bytes after the header cannot hold them " +
                     "(truncated file or wrong header)");
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

/** A PCD header as read, and where its body starts. */
struct PcdHeader {
  std::vector<std::string> fields, types;
  std::vector<int> sizes;
  std::vector<size_t> counts;
  long width = -1, height = -1, npoints = -1;
  std::string encoding;
  size_t pos = 0;             ///< after the DATA line (may be data.size() + 1)
  size_t n = 0;               ///< points: WIDTH * HEIGHT
  int idx[3] = {-1, -1, -1};  ///< fields x, y and z
};

/** Byte offset of each field inside a record (binary) and token index (ascii). */
struct PcdLayout {
  std::vector<size_t> off, tok;
  size_t rec = 0, ntok = 0;
};

/** The next PCD header line at `pos` (without '\n' / '\r'), checked for length and binary bytes. */
std::string nextPcdHeaderLine(const std::string& path, const std::string& data, size_t& pos,
                              int& line_no) {
  if (pos >= data.size())
    throw InputError(path + ": PCD header ends before its DATA line (not a PCD file?)");
  size_t eol = data.find('\n', pos);
  if (eol == std::string::npos) eol = data.size();
  std::string line = data.substr(pos, std::min(eol - pos, kMaxHeaderLine));
  if (eol - pos > kMaxHeaderLine)
    throw InputError(path + ": PCD header line " + std::to_string(line_no + 1) +
                     " is longer than " + std::to_string(kMaxHeaderLine) +
                     " bytes (not a PCD file?)");
  pos = eol + 1;  // may be data.size() + 1 when the DATA line has no newline
  ++line_no;
  if (!line.empty() && line.back() == '\r') line.pop_back();
  if (binaryBytes(line))
    throw InputError(path + ": not a PCD file: header line " + std::to_string(line_no) +
                     " holds binary bytes ('" + printable(line, 24) + "')");
  return line;
}

void readPcdSizes(const std::string& path, const std::string& where,
                  const std::vector<std::string>& t, PcdHeader& h) {
  for (size_t i = 1; i < t.size(); ++i) {
    const long s = toLong(path, where, t[i]);
    if (s != 1 && s != 2 && s != 4 && s != 8)
      throw InputError(path + ": " + where + ": field size must be 1, 2, 4 or 8");
    h.sizes.push_back(static_cast<int>(s));
  }
}

void readPcdTypes(const std::string& path, const std::string& where,
                  const std::vector<std::string>& t, PcdHeader& h) {
  for (size_t i = 1; i < t.size(); ++i) {
    if (t[i] != "F" && t[i] != "I" && t[i] != "U")
      throw InputError(path + ": " + where + ": type must be F, I or U, not '" + printable(t[i]) +
                       "'");
    h.types.push_back(t[i]);
  }
}

void readPcdCounts(const std::string& path, const std::string& where,
                   const std::vector<std::string>& t, PcdHeader& h) {
  for (size_t i = 1; i < t.size(); ++i) {
    const long cnt = toLong(path, where, t[i]);
    if (cnt < 1 || static_cast<uint64_t>(cnt) > kMaxFieldCount)
      throw InputError(path + ": " + where + ": COUNT " + std::to_string(cnt) +
                       " must be between 1 and " + std::to_string(kMaxFieldCount));
    h.counts.push_back(static_cast<size_t>(cnt));
  }
}

/** One header line into `h`. */
void readPcdHeaderLine(const std::string& path, const std::string& line, int line_no,
                       PcdHeader& h) {
  auto t = tokens(line);
  if (t.empty() || t[0][0] == '#') return;
  const std::string& k = t[0];
  const std::string where = "header line " + std::to_string(line_no) + " (" + printable(k) + ")";
  if (k == "VERSION" || k == "VIEWPOINT") return;
  if (k == "FIELDS") {
    h.fields.assign(t.begin() + 1, t.end());
  } else if (k == "SIZE") {
    readPcdSizes(path, where, t, h);
  } else if (k == "TYPE") {
    readPcdTypes(path, where, t, h);
  } else if (k == "COUNT") {
    readPcdCounts(path, where, t, h);
  } else if (k == "WIDTH" && t.size() == 2) {
    h.width = toLong(path, where, t[1]);
  } else if (k == "HEIGHT" && t.size() == 2) {
    h.height = toLong(path, where, t[1]);
  } else if (k == "POINTS" && t.size() == 2) {
    h.npoints = toLong(path, where, t[1]);
  } else if (k == "DATA" && t.size() == 2) {
    h.encoding = t[1];
  } else {
    throw InputError(path + ": malformed PCD " + where + ": '" + printable(line) + "'");
  }
}

/** FIELDS, SIZE, TYPE and COUNT agree. */
void checkPcdFields(const std::string& path, PcdHeader& h) {
  if (h.fields.empty()) throw InputError(path + ": PCD header has no FIELDS line");
  if (h.counts.empty()) h.counts.assign(h.fields.size(), 1);
  if (h.sizes.size() != h.fields.size() || h.types.size() != h.fields.size() ||
      h.counts.size() != h.fields.size())
    throw InputError(path + ": PCD header: FIELDS, SIZE, TYPE and COUNT have different lengths");
  for (size_t i = 0; i < h.fields.size(); ++i)
    if (h.types[i] == "F" && h.sizes[i] != 4 && h.sizes[i] != 8)
      throw InputError(path + ": PCD header: float field '" + printable(h.fields[i]) +
                       "' has size " + std::to_string(h.sizes[i]));
}

/** WIDTH, HEIGHT and POINTS agree; sets the point count. */
void checkPcdSize(const std::string& path, PcdHeader& h) {
  if (h.width < 0) throw InputError(path + ": PCD header has no WIDTH");
  if (h.height < 0) h.height = 1;
  const auto wh = mulSize(static_cast<size_t>(h.width), static_cast<size_t>(h.height));
  if (!wh)
    throw InputError(path + ": PCD header: WIDTH " + std::to_string(h.width) + " x HEIGHT " +
                     std::to_string(h.height) + " overflows");
  if (h.npoints < 0) h.npoints = static_cast<long>(std::min<size_t>(*wh, LONG_MAX));
  if (static_cast<size_t>(h.npoints) != *wh)
    throw InputError(path + ": PCD header: POINTS " + std::to_string(h.npoints) +
                     " != WIDTH*HEIGHT " + std::to_string(*wh));
  h.n = *wh;
}

void findPcdXyz(const std::string& path, PcdHeader& h) {
  int ix = -1, iy = -1, iz = -1;
  for (size_t i = 0; i < h.fields.size(); ++i) {
    if (h.fields[i] == "x") ix = static_cast<int>(i);
    if (h.fields[i] == "y") iy = static_cast<int>(i);
    if (h.fields[i] == "z") iz = static_cast<int>(i);
  }
  if (ix < 0 || iy < 0 || iz < 0)
    throw InputError(path + ": PCD has no x, y and z fields (FIELDS lists none of them)");
  h.idx[0] = ix;
  h.idx[1] = iy;
  h.idx[2] = iz;
}

/** The header up to its DATA line, checked. */
PcdHeader readPcdHeader(const std::string& path, const std::string& data) {
  PcdHeader h;
  int line_no = 0;
  while (h.encoding.empty()) {
    const std::string line = nextPcdHeaderLine(path, data, h.pos, line_no);
    readPcdHeaderLine(path, line, line_no, h);
  }
  checkPcdFields(path, h);
  checkPcdSize(path, h);
  findPcdXyz(path, h);
  return h;
}

// Every count is <= kMaxFieldCount and every size <= 8, so the sums over at
// most (file size) fields cannot overflow.
PcdLayout pcdLayout(const PcdHeader& h) {
  PcdLayout l;
  l.off.resize(h.fields.size());
  l.tok.resize(h.fields.size());
  for (size_t i = 0; i < h.fields.size(); ++i) {
    l.off[i] = l.rec;
    l.tok[i] = l.ntok;
    l.rec += static_cast<size_t>(h.sizes[i]) * h.counts[i];
    l.ntok += h.counts[i];
  }
  return l;
}

/** A coordinate of an ascii line: a number or a NaN spelling. */
float asciiCoordinate(const std::string& path, const std::string& where, const std::string& s) {
  return (s == "nan" || s == "NaN" || s == "-nan") ? kNaN
                                                   : static_cast<float>(toDouble(path, where, s));
}

void readPcdAscii(const std::string& path, const std::string& data, size_t body, const PcdHeader& h,
                  const PcdLayout& l, Cloud& c) {
  const size_t n = h.n;
  // A point is ntok numbers, each at least one character and a separator.
  checkDeclaredPoints(path, "PCD header (ascii)", n, data.size() - body, 2 * l.ntok);
  c.points.resize(n);
  std::istringstream ss(data.substr(body));
  std::string line;
  size_t k = 0;
  while (k < n && std::getline(ss, line)) {
    auto t = tokens(line);
    if (t.empty()) continue;
    if (t.size() != l.ntok)
      throw InputError(path + ": PCD point " + std::to_string(k) + " has " +
                       std::to_string(t.size()) + " values, the header says " +
                       std::to_string(l.ntok));
    float v[3];
    for (int a = 0; a < 3; ++a)
      v[a] = asciiCoordinate(path, "point " + std::to_string(k), t[l.tok[h.idx[a]]]);
    c.points[k++] = {v[0], v[1], v[2]};
  }
  if (k < n)
    throw InputError(path + ": PCD truncated: " + std::to_string(k) + " of " + std::to_string(n) +
                     " points");
  while (std::getline(ss, line))
    if (!tokens(line).empty())
      throw InputError(path + ": PCD has more points than POINTS " + std::to_string(n));
}

void readPcdBinary(const std::string& path, const std::string& data, size_t body,
                   const PcdHeader& h, const PcdLayout& l, Cloud& c) {
  const size_t n = h.n, left = data.size() - body;
  const auto need = mulSize(n, l.rec);
  if (!need || left < *need)
    throw InputError(path + ": PCD binary data truncated: " + std::to_string(left) + " bytes of " +
                     (need ? std::to_string(*need) : std::string("(overflow)")) + " for " +
                     std::to_string(n) + " points");
  checkDeclaredPoints(path, "PCD header (binary)", n, left, l.rec);
  c.points.resize(n);
  const char* base = data.data() + body;
  for (size_t k = 0; k < n; ++k) {
    float v[3];
    for (int a = 0; a < 3; ++a)
      v[a] = static_cast<float>(
          readScalar(base + k * l.rec + l.off[h.idx[a]], h.types[h.idx[a]][0], h.sizes[h.idx[a]]));
    c.points[k] = {v[0], v[1], v[2]};
  }
}

/** The LZF-compressed body of a binary_compressed PCD, checked and decompressed. */
std::vector<uint8_t> pcdDecompressed(const std::string& path, const std::string& data, size_t body,
                                     const PcdHeader& h, const PcdLayout& l) {
  const size_t n = h.n, left = data.size() - body;
  if (left < 8) throw InputError(path + ": PCD binary_compressed data truncated (no size header)");
  uint32_t comp = 0, uncomp = 0;
  std::memcpy(&comp, data.data() + body, 4);
  std::memcpy(&uncomp, data.data() + body + 4, 4);
  const auto need = mulSize(n, l.rec);
  if (!need || uncomp != *need)
    throw InputError(path + ": PCD binary_compressed: uncompressed size " + std::to_string(uncomp) +
                     " != POINTS*record " +
                     (need ? std::to_string(*need) : std::string("(overflow)")) + " for " +
                     std::to_string(n) + " points");
  if (left - 8 < comp)
    throw InputError(path + ": PCD binary_compressed data truncated: " + std::to_string(left - 8) +
                     " bytes of " + std::to_string(comp));
  // LZF expands at most 264 bytes out of 3 in (a long back reference).
  if (static_cast<uint64_t>(uncomp) > 88ull * comp + 88)
    throw InputError(path + ": PCD binary_compressed: " + std::to_string(comp) +
                     " compressed bytes cannot hold " + std::to_string(uncomp) + " bytes");
  if (n > kMaxCloudPoints)
    throw InputError(path + ": PCD header declares " + std::to_string(n) +
                     " points, more than the limit of " + std::to_string(kMaxCloudPoints));
  std::vector<uint8_t> raw(uncomp);
  if (n > 0 && !lzfDecompress(reinterpret_cast<const uint8_t*>(data.data() + body + 8), comp,
                              raw.data(), raw.size()))
    throw InputError(path + ": PCD binary_compressed data is corrupt (LZF)");
  return raw;
}

void readPcdCompressed(const std::string& path, const std::string& data, size_t body,
                       const PcdHeader& h, const PcdLayout& l, Cloud& c) {
  const size_t n = h.n;
  const std::vector<uint8_t> raw = pcdDecompressed(path, data, body, h, l);
  c.points.resize(n);
  // Field-major layout: all values of field 0, then field 1, ...
  std::vector<size_t> foff(h.fields.size());
  size_t acc = 0;
  for (size_t i = 0; i < h.fields.size(); ++i) {
    foff[i] = acc;
    acc += n * h.sizes[i] * h.counts[i];  // <= uncomp
  }
  for (size_t k = 0; k < n; ++k) {
    float v[3];
    for (int a = 0; a < 3; ++a) {
      const int f = h.idx[a];
      v[a] = static_cast<float>(readScalar(
          reinterpret_cast<const char*>(raw.data()) + foff[f] + k * h.sizes[f] * h.counts[f],
          h.types[f][0], h.sizes[f]));
    }
    c.points[k] = {v[0], v[1], v[2]};
  }
}

}  // namespace

Cloud readPcd(const std::string& path) {
  const std::string data = slurpFile(path);
  const PcdHeader h = readPcdHeader(path, data);
  const PcdLayout l = pcdLayout(h);
  const size_t body = std::min(h.pos, data.size());
  Cloud c;
  c.width = static_cast<size_t>(h.width);
  c.height = static_cast<size_t>(h.height);
  if (h.encoding == "ascii")
    readPcdAscii(path, data, body, h, l, c);
  else if (h.encoding == "binary")
    readPcdBinary(path, data, body, h, l, c);
  else if (h.encoding == "binary_compressed")
    readPcdCompressed(path, data, body, h, l, c);
  else
    throw InputError(path + ": PCD DATA '" + printable(h.encoding) +
                     "' is not ascii, binary or binary_compressed");
  if (c.height <= 1) c.height = 1;
  return c;
}

namespace {

struct PlyProp {
  std::string name, type;
  int size;
};

/** A PLY header as read: the vertex element's properties and where the body starts. */
struct PlyHeader {
  std::string format;
  long nvert = -1;
  bool in_vertex = false, vertex_seen = false, ended = false, other_elements = false;
  std::vector<PlyProp> props;
  int idx[3] = {-1, -1, -1};  ///< properties x, y and z
};

/** Header lines of a PLY file, numbered for messages. */
struct PlyLines {
  const std::string& path;
  const std::string& data;
  size_t pos = 0;
  int line_no = 0;

  /** Next header line (without '\n' / '\r'); false at the end of the data. */
  bool next(std::string& line) {
    if (pos >= data.size()) return false;
    size_t eol = data.find('\n', pos);
    if (eol == std::string::npos) eol = data.size();
    if (eol - pos > kMaxHeaderLine)
      throw InputError(path + ": PLY header line " + std::to_string(line_no + 1) +
                       " is longer than " + std::to_string(kMaxHeaderLine) +
                       " bytes (not a PLY file?)");
    line = data.substr(pos, eol - pos);
    pos = std::min(eol + 1, data.size());
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (binaryBytes(line))
      throw InputError(path + ": not a PLY file: header line " + std::to_string(line_no) +
                       " holds binary bytes ('" + printable(line, 24) + "')");
    return true;
  }

  int typeSize(const std::string& t) const {
    if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
    if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
    if (t == "int" || t == "uint" || t == "float" || t == "int32" || t == "uint32" ||
        t == "float32")
      return 4;
    if (t == "double" || t == "float64") return 8;
    throw InputError(path + ": PLY header line " + std::to_string(line_no) +
                     ": unknown property type '" + printable(t) + "'");
  }
};

void readPlyElement(const std::string& path, const std::string& where,
                    const std::vector<std::string>& t, PlyHeader& h) {
  if (t[1] == "vertex") {
    if (h.vertex_seen) throw InputError(path + ": " + where + ": a second vertex element");
    h.nvert = toLong(path, where, t[2]);
    h.in_vertex = h.vertex_seen = true;
  } else {
    if (!h.vertex_seen)
      throw InputError(path + ": " + where + ": element '" + printable(t[1]) +
                       "' before the vertex element is not supported");
    h.in_vertex = false;
    h.other_elements = true;
  }
}

/** One header line into `h`; false after end_header. */
bool readPlyHeaderLine(const PlyLines& in, const std::string& line, PlyHeader& h) {
  const std::string& path = in.path;
  auto t = tokens(line);
  if (t.empty() || t[0] == "comment" || t[0] == "obj_info") return true;
  const std::string where = "PLY header line " + std::to_string(in.line_no);
  if (t[0] == "format" && t.size() == 3) {
    h.format = t[1];
  } else if (t[0] == "element" && t.size() == 3) {
    readPlyElement(path, where, t, h);
  } else if (t[0] == "property" && t.size() >= 3) {
    if (h.in_vertex) {
      if (t[1] == "list")
        throw InputError(path + ": " + where + ": list property in the vertex element");
      h.props.push_back({t[2], t[1], in.typeSize(t[1])});
    }
  } else if (t[0] == "end_header") {
    h.ended = true;
    return false;
  } else {
    throw InputError(path + ": malformed " + where + ": '" + printable(line) + "'");
  }
  return true;
}

/** The header up to end_header, checked; `in.pos` is then where the body starts. */
PlyHeader readPlyHeader(PlyLines& in) {
  const std::string& path = in.path;
  std::string line;
  if (!in.next(line) || tokens(line) != std::vector<std::string>{"ply"})
    throw InputError(path + ": not a PLY file (first line is not 'ply')");
  PlyHeader h;
  while (in.next(line))
    if (!readPlyHeaderLine(in, line, h)) break;
  if (!h.ended) throw InputError(path + ": PLY header has no end_header line");
  if (!h.vertex_seen) throw InputError(path + ": PLY header has no vertex element");
  int ix = -1, iy = -1, iz = -1;
  for (size_t i = 0; i < h.props.size(); ++i) {
    if (h.props[i].name == "x") ix = static_cast<int>(i);
    if (h.props[i].name == "y") iy = static_cast<int>(i);
    if (h.props[i].name == "z") iz = static_cast<int>(i);
  }
  if (ix < 0 || iy < 0 || iz < 0)
    throw InputError(path + ": PLY vertex element has no x, y and z properties");
  h.idx[0] = ix;
  h.idx[1] = iy;
  h.idx[2] = iz;
  return h;
}

void readPlyAscii(const std::string& path, const std::string& data, size_t body, const PlyHeader& h,
                  Cloud& c) {
  const size_t n = c.width;
  checkDeclaredPoints(path, "PLY header (ascii vertex element)", n, data.size() - body,
                      2 * h.props.size());
  c.points.resize(n);
  std::istringstream hs(data.substr(body));
  std::string line;
  size_t k = 0;
  while (k < n && std::getline(hs, line)) {
    auto t = tokens(line);
    if (t.empty()) continue;
    if (t.size() < h.props.size())
      throw InputError(path + ": PLY vertex " + std::to_string(k) + " has " +
                       std::to_string(t.size()) + " values, the header says " +
                       std::to_string(h.props.size()));
    float v[3];
    for (int a = 0; a < 3; ++a)
      v[a] = asciiCoordinate(path, "vertex " + std::to_string(k), t[h.idx[a]]);
    c.points[k++] = {v[0], v[1], v[2]};
  }
  if (k < n)
    throw InputError(path + ": PLY truncated: " + std::to_string(k) + " of " + std::to_string(n) +
                     " vertices");
  if (!h.other_elements)  // nothing may follow the vertices
    while (std::getline(hs, line))
      if (!tokens(line).empty())
        throw InputError(path + ": PLY has more vertex lines than 'element vertex " +
                         std::to_string(n) + "'");
}

char plyKind(const std::string& type) {
  return (type == "float" || type == "double" || type == "float32" || type == "float64")
             ? 'F'
             : (type[0] == 'u' ? 'U' : 'I');
}

void readPlyBinary(const std::string& path, const std::string& data, size_t body,
                   const PlyHeader& h, Cloud& c) {
  const size_t n = c.width, left = data.size() - body;
  std::vector<size_t> off(h.props.size());
  size_t rec = 0;
  for (size_t i = 0; i < h.props.size(); ++i) {
    off[i] = rec;
    rec += h.props[i].size;
  }
  const auto need = mulSize(n, rec);
  if (!need || left < *need)
    throw InputError(path + ": PLY binary data truncated: " + std::to_string(left) + " bytes of " +
                     (need ? std::to_string(*need) : std::string("(overflow)")) + " for " +
                     std::to_string(n) + " vertices");
  if (!h.other_elements && left - *need >= rec)
    throw InputError(path + ": PLY has " + std::to_string(left - *need) + " bytes after its " +
                     std::to_string(n) +
                     " vertices (more vertices than 'element vertex' declares?)");
  checkDeclaredPoints(path, "PLY header (binary vertex element)", n, left, rec);
  c.points.resize(n);
  const char* b = data.data() + body;
  for (size_t k = 0; k < n; ++k) {
    float v[3];
    for (int a = 0; a < 3; ++a) {
      const PlyProp& p = h.props[h.idx[a]];
      v[a] = static_cast<float>(readScalar(b + k * rec + off[h.idx[a]], plyKind(p.type), p.size));
    }
    c.points[k] = {v[0], v[1], v[2]};
  }
}

}  // namespace

Cloud readPly(const std::string& path) {
  const std::string data = slurpFile(path);
  PlyLines in{path, data};
  const PlyHeader h = readPlyHeader(in);
  const size_t body = in.pos;  // <= data.size(), also when end_header has no newline
  Cloud c;
  c.width = static_cast<size_t>(h.nvert);
  c.height = 1;
  if (h.format == "ascii")
    readPlyAscii(path, data, body, h, c);
  else if (h.format == "binary_little_endian")
    readPlyBinary(path, data, body, h, c);
  else if (h.format.empty())
    throw InputError(path + ": PLY header has no format line");
  else
    throw InputError(path + ": PLY format '" + printable(h.format) +
                     "' is not supported (ascii or binary_little_endian)");
  return c;
}

Cloud readCloudFile(const std::string& path) {
  std::string ext = path.size() >= 4 ? path.substr(path.size() - 4) : "";
  std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
  if (ext == ".pcd") return readPcd(path);
  if (ext == ".ply") return readPly(path);
  throw InputError(path + ": unknown point cloud format (expected .pcd or .ply)");
}

std::vector<std::string> checkCloudContent(const std::string& path, const Cloud& c) {
  std::vector<std::string> warnings;
  if (c.points.empty()) throw InputError(path + ": the cloud holds no point");
  size_t valid = 0, absurd = 0;
  for (const auto& p : c.points) {
    if (validPoint(p)) {
      ++valid;
      continue;
    }
    const bool nan = std::isnan(p.x) || std::isnan(p.y) || std::isnan(p.z);
    const bool zero = p.x == 0.f && p.y == 0.f && p.z == 0.f;
    if (!nan && !zero) ++absurd;  // infinite or beyond 1e6 m
  }
  const std::string counts = std::to_string(c.points.size()) + " points: " + std::to_string(valid) +
                             " valid, " + std::to_string(absurd) +
                             " infinite or beyond 1e6 m, the rest NaN or zero depth";
  if (valid == 0) throw InputError(path + ": the cloud has no valid point (" + counts + ")");
  if (valid < 3)
    throw InputError(path + ": the cloud has only " + std::to_string(valid) +
                     " valid point(s); a ground plane needs at least 3 (" + counts + ")");
  if (absurd > 0)
    warnings.push_back(path + ": " + std::to_string(absurd) + " of " +
                       std::to_string(c.points.size()) +
                       " points are infinite or beyond 1e6 m and were ignored");
  return warnings;
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
