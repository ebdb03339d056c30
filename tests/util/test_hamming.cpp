// The inline descriptor distance against OpenCV's, on random and extreme descriptors. (The
// tests are built without -mpopcnt, so this checks the bit-parallel count; the library uses
// the instruction on x86-64.)
#include "rgbdslam/util/hamming.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <iterator>
#include <opencv2/core.hpp>
#include <opencv2/core/hal/hal.hpp>

namespace rgbdslam {
namespace {

TEST(Hamming, AgreesWithOpenCvOnRandomDescriptors) {
  cv::Mat a(500, kBinaryDescriptorBytes, CV_8UC1), b(500, kBinaryDescriptorBytes, CV_8UC1);
  cv::RNG rng(20261124);
  rng.fill(a, cv::RNG::UNIFORM, 0, 256);
  rng.fill(b, cv::RNG::UNIFORM, 0, 256);
  for (int i = 0; i < a.rows; ++i) {
    EXPECT_EQ(hamming256(a.ptr<uint8_t>(i), b.ptr<uint8_t>(i)),
              cv::hal::normHamming(a.ptr<uint8_t>(i), b.ptr<uint8_t>(i), kBinaryDescriptorBytes));
  }
}

TEST(Hamming, CountsEveryBit) {
  uint8_t zeros[kBinaryDescriptorBytes] = {}, ones[kBinaryDescriptorBytes];
  std::fill(std::begin(ones), std::end(ones), 0xff);
  EXPECT_EQ(hamming256(zeros, zeros), 0);
  EXPECT_EQ(hamming256(zeros, ones), 256);
  uint8_t one_bit[kBinaryDescriptorBytes] = {};
  one_bit[kBinaryDescriptorBytes - 1] = 0x80;
  EXPECT_EQ(hamming256(zeros, one_bit), 1);
  EXPECT_EQ(popcount64(~0ULL), 64);
}

}  // namespace
}  // namespace rgbdslam
