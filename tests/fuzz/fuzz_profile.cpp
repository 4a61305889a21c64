// Fuzzes the INI robot-profile reader (carenav::Profile::fromText).
#include "carenav/common/profile.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  CARENAV_FUZZ_TRY(carenav::Profile::fromText(carenav_fuzz::asText(data, size), "fuzz.ini"));
}
