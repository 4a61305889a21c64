// Fuzzes the navigation scenario reader (carenav::navigation::parseScenario).
#include "carenav/runtime/scenario.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  CARENAV_FUZZ_TRY(carenav::navigation::parseScenario(carenav_fuzz::asText(data, size), "fuzz.yaml",
                                                      carenav_fuzz::folder().string()));
}
