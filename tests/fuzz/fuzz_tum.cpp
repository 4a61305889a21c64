// Fuzzes the TUM trajectory reader (carenav::io::readTum).
#include "carenav/io/trajectory.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  CARENAV_FUZZ_TRY(carenav::io::readTum(carenav_fuzz::asFile(data, size, "t.tum")));
}
