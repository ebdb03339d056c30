// libFuzzer target: the JPEG and PNG decoders (image/codec.h; libjpeg-turbo and libpng,
// which are not instrumented: ASan and coverage stop at their calls, so what is checked is
// our use of them: the header walk, the size checks before allocation, the error jumps).
// The first byte chooses how to read; the rest is the stream, read at the size its header
// declares when that is small (what a receiver expects), else at 64x48 (refused unread).
#include <cstddef>
#include <cstdint>

#include "rgbdslam/image/codec.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const auto read = static_cast<rgbdslam::ImageRead>(data[0] % 3);
  ++data, --size;
  constexpr int kMaxSide = 1024;  // [px]: bounds the fuzzer's allocation per input
  cv::Size expected(64, 48);
  const rgbdslam::Expected<cv::Size> declared = rgbdslam::encodedImageSize(data, size);
  if (declared && declared->width > 0 && declared->height > 0 && declared->width <= kMaxSide &&
      declared->height <= kMaxSide) {
    expected = *declared;
  }
  (void)rgbdslam::decodeImage(data, size, read, expected);
  return 0;
}
