// libFuzzer target: a map file (decodeMapFile), as rgbd-slam --load-map reads it. The
// checksum stops most mutations at the header, so each input is also decoded with its
// checksum recomputed (the header's CRC-32 of the payload, bytes 20-23, little-endian),
// which lets mutations reach the content checks.
#include <zlib.h>

#include "fuzz_support.h"
#include "rgbdslam/map/map_file.h"

namespace {
constexpr size_t kMapFileHeaderBytes = 24, kMapFileCrcOffset = 20;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::vector<uint8_t> bytes(data, data + size);
  (void)rgbdslam::decodeMapFile(bytes, "fuzz.map");
  if (size < kMapFileHeaderBytes) return 0;
  const uLong crc = crc32(0L, bytes.data() + kMapFileHeaderBytes, static_cast<uInt>(size - kMapFileHeaderBytes));
  for (size_t k = 0; k < 4; ++k) bytes[kMapFileCrcOffset + k] = static_cast<uint8_t>((crc >> (8 * k)) & 0xff);
  (void)rgbdslam::decodeMapFile(bytes, "fuzz.map");
  return 0;
}
