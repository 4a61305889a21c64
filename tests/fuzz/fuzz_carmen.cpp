// Fuzzes the CARMEN log importer (carenav::io::importCarmen) end to end:
// input log in, rawlog and TUM out.
#include "carenav/io/carmen.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  carenav::io::CarmenImportOptions o;
  o.input = carenav_fuzz::asFile(data, size, "run.log");
  o.output = (carenav_fuzz::folder() / "run.rawlog").string();
  o.compression = 1;
  CARENAV_FUZZ_TRY(carenav::io::importCarmen(o));
}
