// Virtual 2D scans from depth (docs/design.md, 'Virtual scans'): the Kinect Obstacle Scan
// ([InterbotDepth, Alg. 7]), HOBBIT's max-rule scan ([Puente14, App. Sec. IV-A]) and MRPT's
// convertTo2DScan baseline; FSPF+ is in fspf_plus.cpp. KOS bins without atan2 and in one pass
// over the points (docs/BENCHMARKS.md, 'Virtual scans: speed'), with the bins and ranges of the
// plain per-level implementation (tests/unit/perception/virtual_scans_baseline.h).
#include <carenav/perception/virtual_scans.h>

#include "float_order.h"

#include <mrpt/obs/T3DPointsTo2DScanParams.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace carenav::perception {

const char* planeClassName(PlaneClass c) {
  switch (c) {
    case PlaneClass::Ground:
      return "ground";
    case PlaneClass::Ceiling:
      return "ceiling";
    case PlaneClass::LeftWall:
      return "left";
    case PlaneClass::RightWall:
      return "right";
    case PlaneClass::Front:
      return "front";
    case PlaneClass::Other:
      return "other";
    default:
      return "none";
  }
}

mrpt::obs::CObservation2DRangeScan makeScan(const std::vector<float>& ranges, double height,
                                            double max_range, const std::string& label) {
  mrpt::obs::CObservation2DRangeScan s;
  const size_t n = ranges.size();
  const double bin = 2 * M_PI / n;
  s.sensorLabel = label;
  s.aperture = static_cast<float>(bin * (n - 1));  // bin centres from -pi + bin/2
  s.rightToLeft = true;
  s.maxRange = static_cast<float>(max_range);
  s.sensorPose = mrpt::poses::CPose3D(0, 0, height, 0, 0, 0);
  s.resizeScan(n);
  for (size_t k = 0; k < n; ++k) {
    const bool ok = ranges[k] > 0 && ranges[k] <= max_range;
    s.setScanRange(k, ok ? ranges[k] : 0.f);
    s.setScanRangeValidity(k, ok);
  }
  return s;
}

namespace {
size_t binsFor(const PerceptionParams& p) {
  return static_cast<size_t>(std::lround(360.0 / p.scan_resolution));
}

/** Bearing bin of (x, y) as the virtual scans define it: floor((atan2f(y, x) + pi) / bin),
 *  bin = 2 pi / n, clamped to n - 1. */
size_t atanBin(float x, float y, size_t n) {
  const double bin = 2 * M_PI / n;
  return std::min(n - 1, static_cast<size_t>((std::atan2(y, x) + M_PI) / bin));
}

template <class Keep, class Better>
std::vector<float> binRanges(const Cloud& c, size_t n, Keep keep, Better better) {
  std::vector<float> r(n, -1.f);
  for (const auto& q : c.points) {
    if (!validPoint(q) || !keep(q)) continue;
    const float d = std::hypot(q.x, q.y);
    const size_t b = atanBin(q.x, q.y, n);
    if (r[b] < 0 || better(d, r[b])) r[b] = d;
  }
  return r;
}

/** Floats z with |z - h| <= band, the test of the plain implementation (in double): an
 *  interval of floats, found by bisection over the float order (near 0 it reaches below
 *  -1e-17 for h = 0.1, band = 0.1). */
struct ZBand {
  float lo = 1, hi = 0;  // empty
};
ZBand floatBand(double h, double band) {
  const auto in = [&](float z) { return std::abs(static_cast<double>(z) - h) <= band; };
  const float mid = static_cast<float>(h), far = static_cast<float>(std::abs(h) + band + 1);
  if (!in(mid)) return ZBand{};
  // validPoint's |z| < 1e6 as well, so that a point in a band has a valid z
  const float lim = std::nextafter(1e6f, 0.f);
  return ZBand{std::max(-lim, detail::lastInside(mid, -far, in)),
               std::min(lim, detail::lastInside(mid, far, in))};
}

/** KOS as the plain implementation runs it: one binRanges pass per level, merged by the
 *  minimum. Only for clouds with a point at x = y = 0 in a band: its range 0 blocks its
 *  bin in its level, which the single pass does not model. */
std::vector<float> kosPerLevel(const Cloud& c, const PerceptionParams& p, size_t n) {
  std::vector<float> merged(n, -1.f);
  for (double h : p.kosHeights()) {
    auto lv = binRanges(
        c, n, [&](const Point3f& q) { return std::abs(q.z - h) <= p.kos_band; },
        [](float a, float b) { return a < b; });
    for (size_t k = 0; k < n; ++k)
      if (lv[k] > 0 && (merged[k] < 0 || lv[k] < merged[k])) merged[k] = lv[k];
  }
  return merged;
}

/** Per-thread state of kinectObstacleScan, kept between frames. */
struct KosWork {
  std::string heights;  ///< kos_heights and kos_band the bands below were made for
  double band = -1;
  std::vector<ZBand> bands;
  std::vector<double> best2;  ///< per bin: smallest x^2 + y^2 so far
  std::vector<long> best;     ///< per bin: index of that point, -1: none
};

void updateKosBands(const PerceptionParams& p, KosWork& w) {
  if (w.heights == p.kos_heights && w.band == p.kos_band) return;
  w.heights = p.kos_heights;
  w.band = p.kos_band;
  w.bands.clear();
  for (double h : p.kosHeights()) w.bands.push_back(floatBand(h, p.kos_band));
}

constexpr size_t kChunk = 256;
constexpr int32_t kSkip = -1, kExact = -2;  ///< Chunk::bin: not in the scan; bin by atanBin

/** One chunk of points as arrays (the loops below vectorise on arrays, not on Point3f). */
struct Chunk {
  float x[kChunk], y[kChunk], z[kChunk];
  double r2[kChunk];  ///< x^2 + y^2 (exact squares, one rounding: ordered as hypot)
  float u[kChunk];    ///< (atan2(y, x) + pi) / bin, approximately
  int32_t bin[kChunk];
  int32_t flag[kChunk];  ///< 0: skip; 1: in a band and finite; 2: that, and on an axis
};

/** Copies pts[0, m) into the chunk's arrays and flags the points in a band (flag 1); returns
 *  0 when none is (the chunk adds nothing to the scan: a fifth of the chunks of the bench's
 *  stairs frame after FSPF+). */
CARENAV_VECTOR_CLONES int32_t chunkFlags(const Point3f* pts, size_t m,
                                         const std::vector<ZBand>& bands, Chunk& ch) {
  for (size_t j = 0; j < m; ++j) {
    ch.x[j] = pts[j].x;
    ch.y[j] = pts[j].y;
    ch.z[j] = pts[j].z;
    ch.flag[j] = 0;
  }
  for (const ZBand& b : bands)  // in a band: |z| < 1e6
    for (size_t j = 0; j < m; ++j) ch.flag[j] |= (ch.z[j] >= b.lo) & (ch.z[j] <= b.hi);
  int32_t any = 0;
  for (size_t j = 0; j < m; ++j) any |= ch.flag[j];
  return any;
}

/** Per point j of the chunk (its arrays and flags filled by chunkFlags()): bin = its bearing bin,
 * kSkip when invalid (validPoint) or in no band, kExact when within `edge` bins of a bin edge or at
 * x = y = 0 (then possibly (0, 0, 0), invalid). The bearing u = (atan2(y, x) + pi) / bin from an
 * odd degree-15 polynomial for atan on [0, 1] (least-squares fit with Lawson weights, no second
 * division as a range reduction would need), the quadrant by arithmetic blends (a select would keep
 * the compiler from vectorising under trapping math). Error of u against atan2f, measured over 2e7
 * points for n = 120...7200: < 1.3e-6 rad, < 2.1e-7 n bins; bounded here by 5e-7 n. */
CARENAV_VECTOR_CLONES void chunkBins(size_t m, float inv_bin, float edge, int32_t n, Chunk& ch) {
  constexpr float kPi = 3.14159265358979f;
  constexpr float kAtan[8] = {9.9999933558e-01f,  -3.3329860790e-01f, 1.9946565687e-01f,
                              -1.3908629648e-01f, 9.6421974487e-02f,  -5.5912327205e-02f,
                              2.1862957577e-02f,  -4.0545670086e-03f};
  for (size_t j = 0; j < m; ++j) {
    const float x = ch.x[j], y = ch.y[j];
    const float ax = std::abs(x), ay = std::abs(y);
    const int32_t keep = ch.flag[j] & (ax < 1e6f) & (ay < 1e6f);            // (0, 0, 0): on an axis
    const float r = std::min(ax, ay) / std::max(std::max(ax, ay), 1e-30f);  // tan in [0, 1]
    const float z2 = r * r;
    float a0 = kAtan[7];  // atan(r) = r P(r^2), |error| < 4e-8 (1.5e-7 evaluated in float)
    for (int k = 6; k >= 0; --k) a0 = a0 * z2 + kAtan[k];
    a0 *= r;
    const float a1 = a0 + static_cast<float>(ay > ax) * (0.5f * kPi - 2 * a0);  // of (|x|, |y|)
    const float a2 = a1 + static_cast<float>(x < 0.f) * (kPi - 2 * a1);
    const float a3 = a2 - static_cast<float>(y < 0.f) * (2 * a2);  // atan2(y, x)
    ch.u[j] = (a3 + kPi) * inv_bin;  // > -1: truncated to bin 0 and near its edge
    ch.bin[j] = static_cast<int32_t>(ch.u[j]);
    ch.flag[j] = keep + (keep & (ax == 0.f) & (ay == 0.f));
    ch.r2[j] = static_cast<double>(x) * x + static_cast<double>(y) * y;
  }
  for (size_t j = 0; j < m; ++j) {  // a separate loop: fused with the one above it does not
    const int32_t k = ch.bin[j];    // vectorise
    const float fr = ch.u[j] - static_cast<float>(k);
    const int32_t exact = static_cast<int32_t>(std::min(fr, 1.f - fr) < edge) |
                          static_cast<int32_t>(k >= n) | static_cast<int32_t>(ch.flag[j] == 2);
    const int32_t kb = k + exact * (kExact - k);
    ch.bin[j] = kb + static_cast<int32_t>(ch.flag[j] == 0) * (kSkip - kb);
  }
}

/** Per-bin minimum of r2 over one chunk, the earlier point on a tie: per point a load, a
 *  compare and two selected stores, no branch on a change of bin (in a filtered cloud the bin
 *  changes every few points; a running minimum kept in registers until the bin changed was
 *  slower on the bench frames). False: a point at x = y = 0. */
bool chunkMinimum(const Chunk& ch, size_t m, size_t i0, size_t n, double* best2, long* best) {
  for (size_t j = 0; j < m; ++j) {
    long b = ch.bin[j];
    if (b < 0) {
      if (b == kSkip) continue;
      if (ch.x[j] == 0 && ch.y[j] == 0) {
        if (ch.z[j] == 0) continue;  // (0, 0, 0): invalid
        return false;
      }
      b = static_cast<long>(atanBin(ch.x[j], ch.y[j], n));
    }
    const double o = best2[b];
    const bool nearer = ch.r2[j] < o;
    best2[b] = nearer ? ch.r2[j] : o;
    best[b] = nearer ? static_cast<long>(i0 + j) : best[b];
  }
  return true;
}
}  // namespace

mrpt::obs::CObservation2DRangeScan kinectObstacleScan(const Cloud& c, const PerceptionParams& p) {
  // Min over the levels of the min per level = min over the points in any band: one pass,
  // squared ranges compared (ordered as hypot), hypot of the winner only.
  const size_t n = binsFor(p);
  thread_local KosWork w;
  updateKosBands(p, w);
  w.best2.assign(n, std::numeric_limits<double>::infinity());
  w.best.assign(n, -1);
  const Point3f* pts = c.points.data();
  const float inv_bin = static_cast<float>(static_cast<double>(n) / (2 * M_PI));
  // Error of u < 5e-7 n bins (chunkBins); ten times that from an edge the bin is certain;
  // nearer (0.7 % of the points at 0.5 deg) atanBin decides.
  const float edge = std::max(1e-3f, 5e-6f * static_cast<float>(n));
  thread_local Chunk ch;
  for (size_t i0 = 0, m = c.points.size(); i0 < m; i0 += kChunk) {
    const size_t mc = std::min(kChunk, m - i0);
    if (!chunkFlags(pts + i0, mc, w.bands, ch)) continue;  // no point in a band
    chunkBins(mc, inv_bin, edge, static_cast<int32_t>(n), ch);
    if (!chunkMinimum(ch, mc, i0, n, w.best2.data(), w.best.data()))  // x = y = 0 in a band
      return makeScan(kosPerLevel(c, p, n), 0.0, p.depth_max, "KOS");
  }
  std::vector<float> merged(n, -1.f);
  for (size_t k = 0; k < n; ++k)
    if (w.best[k] >= 0) merged[k] = std::hypot(pts[w.best[k]].x, pts[w.best[k]].y);
  return makeScan(merged, 0.0, p.depth_max, "KOS");
}

mrpt::obs::CObservation2DRangeScan maxRuleScan(const Cloud& c, const PerceptionParams& p) {
  const size_t n = binsFor(p);
  auto r = binRanges(
      c, n,
      [&](const Point3f& q) { return std::abs(q.z - p.maxrule_height) <= 0.5 * p.maxrule_slab; },
      [](float a, float b) { return a > b; });
  return makeScan(r, p.maxrule_height, p.depth_max, "MAXRULE");
}

mrpt::obs::CObservation2DRangeScan mrptConvertTo2DScan(mrpt::obs::CObservation3DRangeScan& obs,
                                                       const PerceptionParams& p) {
  mrpt::obs::T3DPointsTo2DScanParams sp;
  sp.sensorLabel = "MRPT2DSCAN";
  sp.use_origin_sensor_pose = true;
  sp.z_min = p.band_z_min;
  sp.z_max = p.band_z_max;
  mrpt::obs::CObservation2DRangeScan out;
  obs.convertTo2DScan(out, sp);
  return out;
}

}  // namespace carenav::perception
