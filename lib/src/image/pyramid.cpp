#include "rgbdslam/image/pyramid.h"

#include <cassert>
#include <cstdint>

namespace rgbdslam {
namespace {
constexpr int kRoundHalf = 2;  // added before dividing a sum of 4 pixels by 4 (>> 2)
constexpr int kSumShift = 2;   // log2 of the 4 pixels averaged
}  // namespace

void halfSample(const cv::Mat& src, cv::Mat* dst) {
  assert(src.type() == CV_8UC1);
  const int width = src.cols / 2;
  const int height = src.rows / 2;
  dst->create(height, width, CV_8UC1);
  for (int y = 0; y < height; ++y) {
    const uint8_t* __restrict row0 = src.ptr<uint8_t>(2 * y);
    const uint8_t* __restrict row1 = src.ptr<uint8_t>(2 * y + 1);
    uint8_t* __restrict out = dst->ptr<uint8_t>(y);
    for (int x = 0; x < width; ++x) {
      const int sum = row0[2 * x] + row0[2 * x + 1] + row1[2 * x] + row1[2 * x + 1];
      out[x] = static_cast<uint8_t>((sum + kRoundHalf) >> kSumShift);
    }
  }
}

void buildPyramid(const cv::Mat& grey, int num_levels, ImagePyramid* out) {
  assert(grey.type() == CV_8UC1);
  assert(num_levels >= 1 && num_levels <= kMaxLevels);
  out->levels.resize(num_levels);
  out->levels[0] = grey;
  for (int level = 1; level < num_levels; ++level) {
    halfSample(out->levels[level - 1], &out->levels[level]);
  }
}

ImagePyramid buildPyramid(const cv::Mat& grey, int num_levels) {
  ImagePyramid pyramid;
  buildPyramid(grey, num_levels, &pyramid);
  return pyramid;
}

}  // namespace rgbdslam
