#include "rgbdslam/map/keyframe_depth.h"

#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "rgbdslam/map/map.h"

namespace rgbdslam {
namespace {

constexpr double kDepthScale = 5000.0;        // raw units per metre (TUM)
constexpr double kMinM = 0.3, kMaxM = 8.0;  // the keyframe build's defaults

// Raw depth with every kind of reading: none (0), nearer than the range, in it, beyond it.
cv::Mat randomRawDepth(int rows, int cols, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> units(0, 50000);  // 0-10 m
  cv::Mat raw(rows, cols, CV_16UC1);
  for (int v = 0; v < rows; ++v) {
    for (int u = 0; u < cols; ++u) raw.at<uint16_t>(v, u) = (u * 7 + v) % 13 == 0 ? 0 : static_cast<uint16_t>(units(rng));
  }
  return raw;
}

// 'sparse' repeated over step x step blocks, cut to rows x cols, as the link's subsampled
// depth formats are decoded (procs/common/lcm_conversions.cpp).
cv::Mat expandedDepth(const cv::Mat& sparse, int step, int rows, int cols) {
  cv::Mat out(rows, cols, CV_16UC1);
  for (int v = 0; v < rows; ++v) {
    for (int u = 0; u < cols; ++u) out.at<uint16_t>(v, u) = sparse.at<uint16_t>(v / step, u / step);
  }
  return out;
}

// Bit for bit (NaN equals NaN), against the float image the map kept before.
void expectSameMetres(const KeyframeDepth& depth, const cv::Mat& raw) {
  const cv::Mat want = depthToMetres(raw, kDepthScale, kMinM, kMaxM);
  const cv::Mat got = depth.metres();
  ASSERT_EQ(got.size(), want.size());
  ASSERT_EQ(got.type(), CV_32FC1);
  EXPECT_EQ(std::memcmp(got.data, want.data, want.total() * sizeof(float)), 0);
  int differ = 0;
  for (int v = 0; v < raw.rows; ++v) {
    for (int u = 0; u < raw.cols; ++u) {
      const float a = depth.at(u, v), b = want.at<float>(v, u);
      differ += std::memcmp(&a, &b, sizeof(float)) != 0 ? 1 : 0;
    }
  }
  EXPECT_EQ(differ, 0);
}

TEST(KeyframeDepth, ASensorsDepthIsKeptAtEveryPixelAndReadsAsBefore) {
  const cv::Mat raw = randomRawDepth(480, 640, 1);
  const KeyframeDepth depth(raw, kDepthScale, kMinM, kMaxM);
  EXPECT_EQ(depth.step(), 1);
  EXPECT_EQ(depth.cols(), 640);
  EXPECT_EQ(depth.rows(), 480);
  EXPECT_EQ(depth.bytes(), 640u * 480u * 2u);  // half of the float image
  expectSameMetres(depth, raw);
}

TEST(KeyframeDepth, DepthDecodedFromEveryStepthPixelIsKeptAtThatStep) {
  for (const int step : {2, 4, 8}) {
    for (const auto& [rows, cols] : {std::pair{480, 640}, std::pair{483, 645}}) {  // whole and clipped blocks
      SCOPED_TRACE("step " + std::to_string(step) + ", " + std::to_string(cols) + "x" + std::to_string(rows));
      const cv::Mat sparse = randomRawDepth((rows + step - 1) / step, (cols + step - 1) / step, 2 + step);
      const cv::Mat raw = expandedDepth(sparse, step, rows, cols);
      const KeyframeDepth depth(raw, kDepthScale, kMinM, kMaxM);
      EXPECT_EQ(depth.step(), step);
      EXPECT_EQ(depth.bytes(), sparse.total() * 2u);
      expectSameMetres(depth, raw);
    }
  }
}

TEST(KeyframeDepth, OneReadingOffItsBlockKeepsEveryPixel) {
  const cv::Mat sparse = randomRawDepth(120, 160, 3);
  cv::Mat raw = expandedDepth(sparse, 4, 480, 640);
  raw.at<uint16_t>(101, 203) = static_cast<uint16_t>(raw.at<uint16_t>(101, 203) + 1);
  const KeyframeDepth depth(raw, kDepthScale, kMinM, kMaxM);
  EXPECT_EQ(depth.step(), 1);
  expectSameMetres(depth, raw);
  // A block of 2 that holds, inside blocks of 4 that do not: kept at 2.
  const cv::Mat fine = expandedDepth(randomRawDepth(240, 320, 4), 2, 480, 640);
  EXPECT_EQ(KeyframeDepth(fine, kDepthScale, kMinM, kMaxM).step(), 2);
}

TEST(KeyframeDepth, AKeyframeReadsItsDepthThroughIt) {
  KeyframeData data;
  data.id = 3;
  data.grey = cv::Mat(480, 640, CV_8UC1, cv::Scalar(128));
  data.depth = expandedDepth(randomRawDepth(120, 160, 5), 4, 480, 640);
  data.depth_scale = kDepthScale;
  KeyframeBuildOptions options;
  options.min_depth_m = kMinM, options.max_depth_m = kMaxM;
  const auto keyframe = makeKeyframe(data, options);
  EXPECT_EQ(keyframe->depth.step(), 4);
  const cv::Mat want = depthToMetres(data.depth, kDepthScale, kMinM, kMaxM);
  int checked = 0;
  for (int v = 0; v < 480; v += 7) {
    for (int u = 0; u < 640; u += 5) {
      const std::optional<double> d = keyframe->depthAt(Eigen::Vector2d(u + 0.3, v - 0.2));
      const float w = want.at<float>(v, u);
      ASSERT_EQ(d.has_value(), std::isfinite(w)) << u << "," << v;
      if (d) EXPECT_EQ(*d, static_cast<double>(w));
      ++checked;
    }
  }
  EXPECT_GT(checked, 8000);
  EXPECT_FALSE(keyframe->depthAt(Eigen::Vector2d(640.2, 10)).has_value());
  keyframe->releaseMappingData();
  EXPECT_TRUE(keyframe->depth.empty());
  EXPECT_TRUE(KeyframeDepth(cv::Mat(), kDepthScale, kMinM, kMaxM).metres().empty());
}

}  // namespace
}  // namespace rgbdslam
