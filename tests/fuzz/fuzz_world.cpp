// Fuzzes the simulator's world YAML reader (carenav::sim::worldFromText).
// Map images are looked for beside the (non-existent) file: the harness
// exercises the YAML and the geometry, not the image readers.
#include "carenav/sim/world.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  CARENAV_FUZZ_TRY(carenav::sim::worldFromText(carenav_fuzz::asText(data, size), "fuzz.yaml",
                                               carenav_fuzz::folder().string()));
}
