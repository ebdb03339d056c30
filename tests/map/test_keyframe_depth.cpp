#include "rgbdslam/map/keyframe_depth.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "rgbdslam/map/map.h"

namespace rgbdslam {
namespace {

constexpr double kDepthScale = 5000.0;        // raw units per metre (TUM)
constexpr double kMinM = 0.3, kMaxM = 8.0;  // the keyframe build's defaults

// Raw depth with every kind of reading: none (0), nearer than the range, in it, beyond it,
// and the readings at the range's ends and the largest.
cv::Mat randomRawDepth(int rows, int cols, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> units(0, 50000);  // 0-10 m
  constexpr uint16_t kEnds[] = {1, 1499, 1500, 1501, 39999, 40000, 40001, 65535};  // 0.3 m = 1500, 8 m = 40000
  cv::Mat raw(rows, cols, CV_16UC1);
  for (int v = 0; v < rows; ++v) {
    for (int u = 0; u < cols; ++u) {
      const int kind = (u * 7 + v) % 13;
      raw.at<uint16_t>(v, u) = kind == 0 ? 0 : kind == 1 ? kEnds[(u + v) % 8] : static_cast<uint16_t>(units(rng));
    }
  }
  return raw;
}

// The map's metres as the float image held them before KeyframeDepth, written out here
// (not through rawDepthToMetres, which KeyframeDepth and depthToMetres share).
float metresAsBefore(uint16_t units) {
  const double d = units * (1.0 / kDepthScale);
  return units != 0 && d >= kMinM && d <= kMaxM ? static_cast<float>(d) : std::numeric_limits<float>::quiet_NaN();
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

// Bit for bit (NaN equals NaN), against the float image the map kept before; and the
// share of valid readings as point creation counted it over that image.
void expectSameMetres(const KeyframeDepth& depth, const cv::Mat& raw) {
  const cv::Mat got = depth.metres();
  ASSERT_EQ(got.size(), raw.size());
  ASSERT_EQ(got.type(), CV_32FC1);
  int differ = 0, valid = 0;
  for (int v = 0; v < raw.rows; ++v) {
    for (int u = 0; u < raw.cols; ++u) {
      const float want = metresAsBefore(raw.at<uint16_t>(v, u)), a = depth.at(u, v), b = got.at<float>(v, u);
      differ += std::memcmp(&a, &want, sizeof(float)) != 0 || std::memcmp(&b, &want, sizeof(float)) != 0 ? 1 : 0;
      valid += std::isfinite(want) ? 1 : 0;
    }
  }
  EXPECT_EQ(differ, 0);
  EXPECT_EQ(depth.validFraction(), static_cast<double>(valid) / raw.total());
  const cv::Mat shared = depthToMetres(raw, kDepthScale, kMinM, kMaxM);
  EXPECT_EQ(std::memcmp(got.data, shared.data, shared.total() * sizeof(float)), 0);
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
  // Anywhere in a block, in a block's first row, and in the last blocks, cut by the border.
  for (const int step : {2, 4, 8}) {
    const int rows = 483, cols = 645;
    const cv::Mat sparse = randomRawDepth((rows + step - 1) / step, (cols + step - 1) / step, 3);
    for (const cv::Point at : {cv::Point(203, 101), cv::Point(step * 10 + 1, step * 7), cv::Point(cols - 1, 5),
                               cv::Point(9, rows - 1)}) {
      if (at.x % step == 0 && at.y % step == 0) continue;  // a block's own reading
      SCOPED_TRACE("step " + std::to_string(step) + " at " + std::to_string(at.x) + "," + std::to_string(at.y));
      cv::Mat raw = expandedDepth(sparse, step, rows, cols);
      raw.at<uint16_t>(at) = static_cast<uint16_t>(raw.at<uint16_t>(at) + 1);
      const KeyframeDepth depth(raw, kDepthScale, kMinM, kMaxM);
      EXPECT_LT(depth.step(), step);
      expectSameMetres(depth, raw);
    }
  }
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
      if (d) {
        EXPECT_EQ(*d, static_cast<double>(w));
      }
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
