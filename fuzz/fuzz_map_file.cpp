// libFuzzer target: a map file (decodeMapFile), as rgbd-slam --load-map reads it. The
// checksum stops most mutations at the header; the unit test MapFile.RandomDamageNeverCrashes
// reseals it to reach the content checks too.
#include "fuzz_support.h"
#include "rgbdslam/map/map_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  (void)rgbdslam::decodeMapFile(std::vector<uint8_t>(data, data + size), "fuzz.map");
  return 0;
}
