// Fuzzes the MRPT rawlog reader (carenav::io::RawlogReader): every entry of
// the input is read until the end or a refusal.
#include "carenav/io/rawlog_reader.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  CARENAV_FUZZ_TRY({
    carenav::io::RawlogReader r(carenav_fuzz::asFile(data, size, "run.rawlog"));
    carenav::io::RawlogEntry e;
    while (r.next(e)) {
    }
  });
}
