// Fuzzes the ROS map_server reader: the input is the YAML; its image is a
// small valid PGM beside it, so the YAML's keys, thresholds and origin are
// what varies (fuzz_image covers the image readers).
#include "carenav/io/map_io.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const bool pgm = [] {
    std::ofstream(carenav_fuzz::folder() / "map.pgm", std::ios::binary) << "P5\n4 3\n255\n"
                                                                        << std::string(12, '\xfe');
    return true;
  }();
  (void)pgm;
  CARENAV_FUZZ_TRY(carenav::io::readRosMap(carenav_fuzz::asFile(data, size, "map.yaml")));
}
