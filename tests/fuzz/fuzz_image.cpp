// Fuzzes the map image readers (PGM P2/P5 and PNG: carenav::io::readImageGrey).
// The first input byte picks the file name's extension.
#include "carenav/io/map_io.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const char* name = (data[0] & 1) ? "map.png" : "map.pgm";
  CARENAV_FUZZ_TRY(carenav::io::readImageGrey(carenav_fuzz::asFile(data + 1, size - 1, name)));
}
