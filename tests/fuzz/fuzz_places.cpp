// Fuzzes the places YAML reader (carenav::places::parsePlaces).
#include "carenav/places/places.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  CARENAV_FUZZ_TRY(
      carenav::places::parsePlaces(carenav_fuzz::asText(data, size), "fuzz.places.yaml"));
}
