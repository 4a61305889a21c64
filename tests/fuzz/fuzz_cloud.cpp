// Fuzzes the point-cloud readers (PCD ascii/binary/binary_compressed, PLY):
// the first input byte picks the extension.
#include "carenav/perception/cloud.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const char* name = (data[0] & 1) ? "c.ply" : "c.pcd";
  CARENAV_FUZZ_TRY(
      carenav::perception::readCloudFile(carenav_fuzz::asFile(data + 1, size - 1, name)));
}
