// Fuzzes the TCP bridge's line protocol (carenav::navigation::parseBridgeLine):
// every line of the input is parsed as the robot would send it.
#include "carenav/runtime/bridge.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text = carenav_fuzz::asText(data, size);
  size_t at = 0;
  while (at <= text.size()) {
    const size_t end = std::min(text.find('\n', at), text.size());
    try {
      (void)carenav::navigation::parseBridgeLine(text.substr(at, end - at));
    } catch (const std::exception&) {
    }
    at = end + 1;
  }
  return 0;
}
