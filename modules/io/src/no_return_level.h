// The value a laser scanner writes for a beam with no return, found from the
// readings of a log that does not state its maximum range (CARMEN's FLASER,
// RLASER and LASERk messages carry none).
#pragma once

#include <carenav/io/carmen.h>

#include <cstdint>
#include <vector>

namespace carenav::io {

/** Collects readings below `below` (m) in 1 cm bins and decides whether
 *  the top of them is a no-return value. A scanner writes every beam that
 *  hits nothing as (nearly) one value, its maximum range: 81.91 m for a SICK
 *  LMS in cm mode, 50-51.2 m on some CARMEN logs. Such readings pile up at
 *  the top of a log's ranges: a 1 cm bin holds a share of all readings that
 *  no real far wall gives, almost nothing lies above it, and the band just
 *  below it holds far more readings per metre than the band below that. Real
 *  returns thin out with range instead. And no-return beams are a minority
 *  of a log made for mapping. Those three tests decide; the limit
 *  is the band's lower edge, kBand below the level (codes spread over about
 *  2.5 % below the maximum: 50.00-51.25 m on one log). Readings beyond
 *  `below` are not collected: they are invalid anyway. */
class NoReturnFinder {
 public:
  explicit NoReturnFinder(double below);
  void add(double range);
  /** The level, when the readings pile up at the top; else empty. */
  bool find(NoReturnLevel& out) const;

  static constexpr double kBand = 0.03;         ///< share of the level below it
  static constexpr double kRepeatShare = 1e-3;  ///< of all readings in the level's bin
  static constexpr uint64_t kMinRepeat = 10;    ///< readings in the level's bin
  static constexpr double kDensityRatio = 10;   ///< band vs the band below, per metre
  static constexpr double kAboveShare = 0.01;   ///< of the band, above the level
  /** At most this share of all readings: a log whose beams mostly return one
   *  value is not a scan of a room (a test scene, a robot facing a wall). */
  static constexpr double kMaxPileShare = 0.5;

 private:
  uint64_t countBins(size_t from, size_t to) const;

  std::vector<uint64_t> bins_;
  uint64_t total_ = 0;
};

}  // namespace carenav::io
