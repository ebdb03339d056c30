#include "rgbdslam/image/codec.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

namespace rgbdslam {
namespace {

cv::Mat randomDepth(int width, int height) {
  cv::Mat depth(height, width, CV_16UC1);
  cv::randu(depth, 0, 30000);
  return depth;
}

TEST(Codec, DepthRoundTripIsExact) {
  const cv::Mat depth = randomDepth(64, 48);
  const auto bytes = compressDepth(depth);
  auto back = decompressDepth(bytes.data(), bytes.size(), 64, 48);
  ASSERT_TRUE(back) << back.error();
  EXPECT_EQ(cv::norm(depth, *back, cv::NORM_INF), 0.0);
}

TEST(Codec, TruncatedOrWrongSizedDepthIsAnError) {
  const cv::Mat depth = randomDepth(64, 48);
  const auto bytes = compressDepth(depth);
  EXPECT_FALSE(decompressDepth(bytes.data(), bytes.size() / 2, 64, 48));
  EXPECT_FALSE(decompressDepth(bytes.data(), bytes.size(), 64, 47));
  EXPECT_FALSE(decompressDepth(bytes.data(), bytes.size(), 64, 49));
  const std::vector<uint8_t> garbage(100, 0xAB);
  EXPECT_FALSE(decompressDepth(garbage.data(), garbage.size(), 64, 48));
}

TEST(Codec, JpegRoundTripIsClose) {
  cv::Mat image(48, 64, CV_8UC3);
  cv::randu(image, 0, 255);
  cv::GaussianBlur(image, image, cv::Size(5, 5), 2.0);
  const auto bytes = encodeJpeg(image, 95);
  auto back = decodeImage(bytes.data(), bytes.size(), 3, 64, 48);
  ASSERT_TRUE(back) << back.error();
  EXPECT_LT(cv::norm(image, *back, cv::NORM_L1) / image.total() / 3, 6.0);  // mean abs error [grey levels]; a wrong decode gives ~60
  EXPECT_FALSE(decodeImage(bytes.data(), bytes.size(), 3, 65, 48));  // size disagrees
  EXPECT_FALSE(decodeImage(bytes.data(), 10, 3, 64, 48));             // truncated
}

TEST(Codec, PngRoundTripIsExact) {
  cv::Mat grey(48, 64, CV_8UC1);
  cv::randu(grey, 0, 255);
  const auto bytes = encodePng(grey);
  auto back = decodeImage(bytes.data(), bytes.size(), 1, 64, 48);
  ASSERT_TRUE(back) << back.error();
  EXPECT_EQ(cv::norm(grey, *back, cv::NORM_INF), 0.0);
}

}  // namespace
}  // namespace rgbdslam
