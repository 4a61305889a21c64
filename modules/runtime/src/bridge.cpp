// The robot bridge (see bridge.h and docs/navigate.md).
#include <carenav/common/errors.h>
#include <carenav/common/text.h>
#include <carenav/runtime/bridge.h>
#include <carenav/runtime/line_socket.h>

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservationRange.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/poses/CPose3D.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace carenav::navigation {

namespace {

double number(const std::string& s, const char* what, bool allow_nonfinite = false) {
  const auto d = parseNumber(s, allow_nonfinite ? NonFinite::Allow : NonFinite::Refuse);
  if (!d)
    throw std::invalid_argument(std::string(what) + " '" + printableText(s, 40) +
                                "' is not a finite number");
  return *d;
}

std::string fmt(double v, int prec = 3) { return formatFixed(v, prec); }

/** A finite number within +-limit (`unit` for the message): odometry of
 *  1e300 m is refused here, naming the bridge line, instead of overflowing
 *  the picture and the path length downstream. */
double bounded(const std::string& s, const char* what, double limit, const char* unit) {
  const double d = number(s, what);
  if (std::abs(d) > limit)
    throw std::invalid_argument(std::string(what) + " '" + printableText(s, 40) + "' is beyond +-" +
                                fmt(limit, 0) + " " + unit + " (not a plausible value)");
  return d;
}

}  // namespace

std::optional<BridgeMessage> parseBridgeLine(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> tok;
  for (std::string t; in >> t;) tok.push_back(t);
  if (tok.empty() || tok[0][0] == '#') return std::nullopt;
  BridgeMessage m;
  const std::string& k = tok[0];
  auto need = [&](size_t n, const char* form) {
    if (tok.size() != n)
      throw std::invalid_argument("'" + k + "' with " + std::to_string(tok.size() - 1) +
                                  " fields, expected '" + form + "'");
  };
  if (k == "odom") {
    need(7, "odom T X Y YAW V W");
    m.kind = BridgeMessage::Kind::Odom;
    m.t = bounded(tok[1], "time", kBridgeMaxTime, "s");
    m.pose = {bounded(tok[2], "x", kBridgeMaxCoordinate, "m"),
              bounded(tok[3], "y", kBridgeMaxCoordinate, "m"),
              bounded(tok[4], "yaw", kBridgeMaxYaw, "rad")};
    m.vel = {bounded(tok[5], "v", kBridgeMaxSpeed, "m/s"),
             bounded(tok[6], "w", kBridgeMaxSpeed, "rad/s")};
  } else if (k == "scan") {
    if (tok.size() < 4)
      throw std::invalid_argument("'scan' too short, expected 'scan T LABEL N R1 .. RN'");
    m.kind = BridgeMessage::Kind::Scan;
    m.t = bounded(tok[1], "time", kBridgeMaxTime, "s");
    m.label = tok[2];
    if (m.label.size() > 64) throw std::invalid_argument("scan label longer than 64 bytes");
    const double n = number(tok[3], "N");
    if (n < 1 || n > 100000 || n != std::floor(n))
      throw std::invalid_argument("N '" + printableText(tok[3], 40) +
                                  "' is not a count of ranges (1..100000)");
    const size_t count = static_cast<size_t>(n);
    if (tok.size() - 4 != count)
      throw std::invalid_argument("scan says " + std::to_string(count) + " ranges, has " +
                                  std::to_string(tok.size() - 4) +
                                  (tok.size() - 4 < count ? " (truncated?)" : ""));
    m.ranges.reserve(count);
    for (size_t i = 0; i < count; ++i) {
      const double r = number(tok[4 + i], "range", true);
      if (r < 0)
        throw std::invalid_argument("range '" + printableText(tok[4 + i], 40) + "' is negative");
      m.ranges.push_back(static_cast<float>(r));
    }
  } else if (k == "intent") {
    need(4, "intent T V W");
    m.kind = BridgeMessage::Kind::Intent;
    m.t = bounded(tok[1], "time", kBridgeMaxTime, "s");
    m.vel = {bounded(tok[2], "v", kBridgeMaxSpeed, "m/s"),
             bounded(tok[3], "w", kBridgeMaxSpeed, "rad/s")};
  } else if (k == "bye") {
    need(1, "bye");
    m.kind = BridgeMessage::Kind::Bye;
  } else {
    throw std::invalid_argument("unknown message '" + printableText(k, 40) +
                                "' (expected odom, scan, intent or bye)");
  }
  return m;
}

std::string formatCommand(double t, const Twist& c) {
  return "cmd " + fmt(t) + " " + fmt(c.v, 4) + " " + fmt(c.w, 4);
}

std::vector<float> reduceRanges(const std::vector<float>& ranges, size_t n,
                                const std::function<bool(float)>& valid) {
  if (n == 0 || ranges.size() <= n) return ranges;
  std::vector<float> out(n, 0.0f);
  for (size_t b = 0; b < n; ++b) {
    const size_t i0 = b * ranges.size() / n, i1 = (b + 1) * ranges.size() / n;
    float best = std::numeric_limits<float>::infinity();
    for (size_t i = i0; i < i1; ++i)
      if (valid(ranges[i]) && ranges[i] < best) best = ranges[i];
    if (std::isfinite(best)) out[b] = best;  // else 0: no return
  }
  return out;
}

// A lidar2d's or range array's ranges as the MRPT observation the
// navigator takes: beyond the sensor's beams or segments, each bin keeps
// its nearest valid return.
mrpt::obs::CObservation::Ptr bridgeObservation(const BridgeMessage& scan, const SensorParams& s) {
  if (s.type == "range-array") {
    const auto valid = [&](float r) { return std::isfinite(r) && r > 0 && r < s.range_max; };
    const size_t cap = static_cast<size_t>(std::max(1, s.segments));
    const std::vector<float> ranges = reduceRanges(scan.ranges, cap, valid);
    // Segments spread evenly over the fov, each a cone (the Leddar).
    auto ra = std::make_shared<mrpt::obs::CObservationRange>();
    ra->sensorLabel = s.label;
    ra->minSensorDistance = static_cast<float>(s.range_min);
    ra->maxSensorDistance = static_cast<float>(s.range_max);
    const double seg = mrpt::DEG2RAD(s.fov) / static_cast<double>(ranges.size());
    ra->sensorConeApperture = static_cast<float>(seg);
    for (size_t i = 0; i < ranges.size(); ++i) {
      mrpt::obs::CObservationRange::TMeasurement me;
      me.sensorID = static_cast<uint16_t>(i);
      me.sensorPose = mrpt::math::TPose3D(
          s.x, s.y, s.z, mrpt::DEG2RAD(s.yaw - s.fov / 2) + (static_cast<double>(i) + 0.5) * seg,
          mrpt::DEG2RAD(s.pitch), mrpt::DEG2RAD(s.roll));
      me.sensedDistance = valid(ranges[i]) ? ranges[i] : static_cast<float>(s.range_max);
      ra->sensedData.push_back(me);
    }
    return ra;
  }
  const auto valid = [&](float r) {
    return std::isfinite(r) && r >= s.range_min && r < s.range_max;
  };
  const size_t cap = static_cast<size_t>(std::max(1, s.beams));
  const std::vector<float> ranges = reduceRanges(scan.ranges, cap, valid);
  auto obs = std::make_shared<mrpt::obs::CObservation2DRangeScan>();
  obs->sensorLabel = s.label;
  obs->aperture = static_cast<float>(mrpt::DEG2RAD(s.fov));
  obs->rightToLeft = true;
  obs->maxRange = static_cast<float>(s.range_max);
  obs->sensorPose = mrpt::poses::CPose3D(s.x, s.y, s.z, mrpt::DEG2RAD(s.yaw),
                                         mrpt::DEG2RAD(s.pitch), mrpt::DEG2RAD(s.roll));
  obs->resizeScan(ranges.size());
  for (size_t i = 0; i < ranges.size(); ++i) {
    obs->setScanRange(i, valid(ranges[i]) ? ranges[i] : static_cast<float>(s.range_max));
    obs->setScanRangeValidity(i, valid(ranges[i]));
  }
  return obs;
}

}  // namespace carenav::navigation
