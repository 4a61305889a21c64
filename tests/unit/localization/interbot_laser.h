// INTERBOT's Hokuyo UTM-30LX as the shipped profile gives it (ini/interbot.ini,
// [sensor.laser]), for the tests that simulate walks with it.
#pragma once

#include <carenav/common/profile.h>
#include <carenav/common/robot.h>

#include <stdexcept>
#include <string>

namespace carenav::localization::fixtures {

/** The profile's laser at `rate_hz` (the profile's 40 Hz would make a walk's
 *  rawlog four times as long for the same test). */
inline SensorParams interbotLaser(double rate_hz = 10) {
  const Profile p = Profile::load(std::string(CARENAV_SOURCE_DIR) + "/ini/interbot.ini");
  for (SensorParams s : loadSensors(p))
    if (s.label == "laser") {
      s.rate_hz = rate_hz;
      return s;
    }
  throw std::runtime_error("ini/interbot.ini has no [sensor.laser]");
}

}  // namespace carenav::localization::fixtures
