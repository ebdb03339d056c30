#include "rgbdslam/image/codec.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include <opencv2/imgcodecs.hpp>
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

// A wall 1-6 m away read by a Kinect-like sensor: sigma = a z^2, stored in millimetres, and
// a band without readings.
cv::Mat noisyWall(int width, int height, double a) {
  cv::Mat depth(height, width, CV_16UC1);
  cv::RNG rng(7);
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const double z = 1.0 + 5.0 * u / width;
      depth.at<uint16_t>(v, u) = v % 16 < 2 ? 0 : static_cast<uint16_t>(std::lround(1000 * (z + rng.gaussian(a * z * z))));
    }
  }
  return depth;
}

TEST(Codec, InverseDepthStaysWithinHalfAStepAndKeepsMissingReadings) {
  const double a = 3.331e-3, step = 0.25 * a;
  const cv::Mat depth = noisyWall(160, 120, a);
  const auto bytes = compressInverseDepth(depth, 1000.0, step);
  auto back = decompressInverseDepth(bytes.data(), bytes.size(), 160, 120, 1000.0);
  ASSERT_TRUE(back) << back.error();
  double worst = 0;
  for (int v = 0; v < 120; ++v) {
    for (int u = 0; u < 160; ++u) {
      const int raw = depth.at<uint16_t>(v, u), out = back->at<uint16_t>(v, u);
      ASSERT_EQ(raw == 0, out == 0) << u << "," << v;
      if (raw == 0) continue;
      // Half a step in inverse depth, and the millimetre of the decoded reading.
      const double z = raw / 1000.0, z_out = out / 1000.0;
      worst = std::max(worst, std::abs(1 / z_out - 1 / z) / (step / 2 + 0.0005 / (z_out * z_out)));
    }
  }
  EXPECT_LE(worst, 1.0 + 1e-9);
  EXPECT_LT(bytes.size(), compressDepth(depth, 6).size() * 3 / 4) << "a quarter smaller than zlib at least";
}

TEST(Codec, AnInverseStepTooFineForTheNearestReadingIsWidened) {
  cv::Mat depth(8, 8, CV_16UC1, cv::Scalar(300));  // 0.3 m
  depth.at<uint16_t>(3, 3) = 4000;
  const auto bytes = compressInverseDepth(depth, 1000.0, 1e-9);
  auto back = decompressInverseDepth(bytes.data(), bytes.size(), 8, 8, 1000.0);
  ASSERT_TRUE(back) << back.error();
  EXPECT_NEAR(back->at<uint16_t>(0, 0), 300, 1);
  EXPECT_NEAR(back->at<uint16_t>(3, 3), 4000, 200) << "a far reading is not clamped to the near one";
}

TEST(Codec, BadInverseDepthStreamsAreErrors) {
  const cv::Mat depth = noisyWall(64, 48, 3.331e-3);
  auto bytes = compressInverseDepth(depth, 1000.0, 1e-3);
  EXPECT_TRUE(decompressInverseDepth(bytes.data(), bytes.size(), 64, 48, 1000.0));
  EXPECT_FALSE(decompressInverseDepth(bytes.data(), bytes.size() - 1, 64, 48, 1000.0)) << "cut short";
  EXPECT_FALSE(decompressInverseDepth(bytes.data(), 3, 64, 48, 1000.0)) << "no step";
  EXPECT_FALSE(decompressInverseDepth(bytes.data(), bytes.size(), 64, 47, 1000.0)) << "another size";
  EXPECT_FALSE(decompressInverseDepth(bytes.data(), bytes.size(), 64, 48, 0.0)) << "no scale";
  auto longer = bytes;
  longer.push_back(0);
  EXPECT_FALSE(decompressInverseDepth(longer.data(), longer.size(), 64, 48, 1000.0)) << "trailing byte";
  for (float step : {0.0f, -1.0f, 11.0f, 1e-45f, std::numeric_limits<float>::quiet_NaN()}) {
    auto spoiled = bytes;
    uint32_t bits;
    std::memcpy(&bits, &step, 4);
    for (int i = 0; i < 4; ++i) spoiled[i] = static_cast<uint8_t>(bits >> (8 * i));
    EXPECT_FALSE(decompressInverseDepth(spoiled.data(), spoiled.size(), 64, 48, 1000.0)) << step;
  }
  const std::vector<uint8_t> garbage(100, 0xAB);
  EXPECT_FALSE(decompressInverseDepth(garbage.data(), garbage.size(), 64, 48, 1000.0));
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

TEST(Codec, OptimalHuffmanTablesKeepThePixelsInFewerBytes) {
  cv::Mat image(480, 640, CV_8UC1);
  cv::randu(image, 0, 255);
  cv::GaussianBlur(image, image, cv::Size(5, 5), 1.5);
  for (int quality : {30, 75}) {
    const auto standard = encodeJpeg(image, quality);
    const auto optimal = encodeJpeg(image, quality, /*optimal_huffman=*/true);
    EXPECT_LT(optimal.size(), standard.size()) << quality;
    auto a = decodeImage(standard.data(), standard.size(), 1, 640, 480);
    auto b = decodeImage(optimal.data(), optimal.size(), 1, 640, 480);
    ASSERT_TRUE(a && b) << quality;
    EXPECT_EQ(cv::norm(*a, *b, cv::NORM_INF), 0.0) << quality;  // the same coefficients
  }
}

TEST(Codec, PngRoundTripIsExact) {
  cv::Mat grey(48, 64, CV_8UC1);
  cv::randu(grey, 0, 255);
  const auto bytes = encodePng(grey);
  auto back = decodeImage(bytes.data(), bytes.size(), 1, 64, 48);
  ASSERT_TRUE(back) << back.error();
  EXPECT_EQ(cv::norm(grey, *back, cv::NORM_INF), 0.0);
}


// The offset of a JPEG's frame header (SOFn) marker, found by the same walk a decoder does.
size_t jpegFrameHeader(const std::vector<uint8_t>& jpeg) {
  size_t at = 2;
  while (at + 4 <= jpeg.size()) {
    const uint8_t marker = jpeg[at + 1];
    if (marker >= 0xC0 && marker <= 0xC3) return at;
    at += 2 + ((jpeg[at + 2] << 8) | jpeg[at + 3]);
  }
  return 0;
}

TEST(Codec, ReadsTheDeclaredSizeWithoutDecoding) {
  cv::Mat image(48, 64, CV_8UC3, cv::Scalar(10, 20, 30));
  for (const auto& bytes : {encodeJpeg(image, 90), encodePng(image)}) {
    const auto size = encodedImageSize(bytes.data(), bytes.size());
    ASSERT_TRUE(size) << size.error();
    EXPECT_EQ(*size, cv::Size(64, 48));
    EXPECT_FALSE(encodedImageSize(bytes.data(), 6));  // cut off before the size
  }
  std::vector<uint8_t> bmp;
  cv::imencode(".bmp", image, bmp);
  const auto refused = decodeImage(bmp.data(), bmp.size(), 3, 64, 48);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().find("neither JPEG nor PNG"), std::string::npos) << refused.error();
}

// A few bytes of JPEG header may declare a 30000x30000 image: decoding it would allocate
// 2.7 GB before the size is compared (an out-of-memory the fuzzer found in an LCM log). The
// header is read first, so it is refused without the allocation.
TEST(Codec, AHeaderDeclaringAHugeImageIsRefusedBeforeDecoding) {
  auto bytes = encodeJpeg(cv::Mat(48, 64, CV_8UC1, cv::Scalar(7)), 90);
  const size_t sof = jpegFrameHeader(bytes);
  ASSERT_GT(sof, 0u);
  for (size_t i : {sof + 5, sof + 7}) {  // height, width: big-endian 16 bits each
    bytes[i] = 30000 >> 8;
    bytes[i + 1] = 30000 & 0xFF;
  }
  const auto size = encodedImageSize(bytes.data(), bytes.size());
  ASSERT_TRUE(size) << size.error();
  EXPECT_EQ(*size, cv::Size(30000, 30000));
  const auto refused = decodeImage(bytes.data(), bytes.size(), 1, 64, 48);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().find("header says 30000x30000, expected 64x48"), std::string::npos) << refused.error();

  auto png = encodePng(cv::Mat(48, 64, CV_8UC1, cv::Scalar(7)));
  png[16] = png[20] = 0x7F;  // width and height 2^31 - ...
  EXPECT_FALSE(encodedImageSize(png.data(), png.size()));
  EXPECT_FALSE(decodeImage(png.data(), png.size(), 1, 64, 48));
}

}  // namespace
}  // namespace rgbdslam
