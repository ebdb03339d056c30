// libFuzzer target: bytes as a subscriber receives them on a channel, through the wire check,
// liblcm's decoder (decodeMessage<T>) and the conversion with its range checks (fromLcm).
// FUZZ_MESSAGE_TYPE names the lcmtype (fuzz/CMakeLists.txt builds one target per type).
#include <cstddef>
#include <cstdint>

#include "common/lcm_conversions.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto msg = rgbdslam::decodeMessage<rgbdslam::FUZZ_MESSAGE_TYPE>(data, size);
  if (msg) (void)rgbdslam::fromLcm(*msg);
  return 0;
}
