#include "rgbdslam/map/keyframe_depth.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <tuple>

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

// Depth kept at a step: every pixel valid exactly where its own block's reading is, that
// reading at the block's centre pixel, and elsewhere a value within the readings of the
// blocks around it (their interpolation, or its own); metres() each block's own reading.
void expectReadsBetweenReadings(const KeyframeDepth& depth, const cv::Mat& sparse, int step) {
  const cv::Mat got = depth.metres();
  ASSERT_EQ(got.size(), cv::Size(depth.cols(), depth.rows()));
  int wrong_validity = 0, wrong_centre = 0, outside = 0, differ = 0, valid = 0;
  for (int v = 0; v < depth.rows(); ++v) {
    for (int u = 0; u < depth.cols(); ++u) {
      const int i = u / step, j = v / step;
      const float own = metresAsBefore(sparse.at<uint16_t>(j, i)), a = depth.at(u, v), b = got.at<float>(v, u);
      differ += std::memcmp(&own, &b, sizeof(float)) != 0 ? 1 : 0;
      wrong_validity += std::isfinite(a) != std::isfinite(own) ? 1 : 0;
      if (!std::isfinite(own)) continue;
      ++valid;
      if (u == i * step + step / 2 && v == j * step + step / 2) wrong_centre += a != own ? 1 : 0;
      float lo = own, hi = own;
      for (int jj = std::max(j - 1, 0); jj <= std::min(j + 1, sparse.rows - 1); ++jj) {
        for (int ii = std::max(i - 1, 0); ii <= std::min(i + 1, sparse.cols - 1); ++ii) {
          const float r = metresAsBefore(sparse.at<uint16_t>(jj, ii));
          if (std::isfinite(r)) lo = std::min(lo, r), hi = std::max(hi, r);
        }
      }
      outside += a < lo || a > hi ? 1 : 0;
    }
  }
  EXPECT_EQ(differ, 0);
  EXPECT_EQ(depth.validFraction(), static_cast<double>(valid) / (static_cast<double>(depth.cols()) * depth.rows()));
  EXPECT_EQ(wrong_validity, 0);
  EXPECT_EQ(wrong_centre, 0);
  EXPECT_EQ(outside, 0);
}

// Inverse depth affine in the pixel coordinates: a plane [1/m].
double planeInverseDepth(int u, int v) { return 0.4 + 0.002 * u + 0.0005 * v; }

// A plane's depth read at every step-th pixel and row, at each block's centre, as the link
// sends it (subsampleDepth, procs/common/lcm_conversions.cpp), and decoded by repetition.
cv::Mat planeReadings(int step, int rows, int cols) {
  cv::Mat sparse((rows + step - 1) / step, (cols + step - 1) / step, CV_16UC1);
  for (int j = 0; j < sparse.rows; ++j) {
    for (int i = 0; i < sparse.cols; ++i) {
      const int u = std::min(i * step + step / 2, cols - 1), v = std::min(j * step + step / 2, rows - 1);
      sparse.at<uint16_t>(j, i) = static_cast<uint16_t>(std::lround(kDepthScale / planeInverseDepth(u, v)));
    }
  }
  return sparse;
}
cv::Mat planeAtStep(int step, int rows, int cols) {
  return expandedDepth(planeReadings(step, rows, cols), step, rows, cols);
}

TEST(KeyframeDepth, APlaneBetweenReadingsIsInterpolated) {
  // A wall seen at a grazing angle: 0.5-2.5 m across the image, its depth changing up to 4 %
  // over a block of 8 at the far end. The block's own reading is up to half a block's change
  // off; the interpolation in inverse depth is exact on a plane but for the readings' rounding.
  for (const int step : {2, 4, 8}) {
    SCOPED_TRACE("step " + std::to_string(step));
    const KeyframeDepth depth(planeAtStep(step, 480, 640), kDepthScale, kMinM, kMaxM);
    ASSERT_EQ(depth.step(), step);
    double worst = 0.0, worst_own = 0.0;
    int checked = 0;
    // Inside the readings' lattice (beyond the outermost centres along an axis a pixel reads
    // its own block's readings along that axis).
    for (int v = step / 2; v <= 480 - step + step / 2; ++v) {
      for (int u = step / 2; u <= 640 - step + step / 2; ++u) {
        const double truth = 1.0 / planeInverseDepth(u, v);
        const float got = depth.at(u, v);
        ASSERT_TRUE(std::isfinite(got)) << u << "," << v;
        const int uc = u / step * step + step / 2, vc = v / step * step + step / 2;
        worst = std::max(worst, std::abs(got - truth));
        worst_own = std::max(worst_own, std::abs(1.0 / planeInverseDepth(uc, vc) - truth));
        ++checked;
      }
    }
    EXPECT_GT(checked, 200000);
    EXPECT_LT(worst, 0.5 / kDepthScale + 1e-6);  // the readings' rounding: half a unit, 0.1 mm [m]
    EXPECT_GT(worst_own, 10 * worst);
  }
  // An image whose size is no multiple of the step: the last reading was taken at the border
  // pixel itself (subsampleDepth clips the centre), and the pixels before it interpolate
  // towards it there.
  for (const auto& [step, rows, cols] : {std::tuple{4, 482, 645}, std::tuple{8, 483, 642}}) {
    SCOPED_TRACE("step " + std::to_string(step) + ", " + std::to_string(cols) + "x" + std::to_string(rows));
    const KeyframeDepth depth(planeAtStep(step, rows, cols), kDepthScale, kMinM, kMaxM);
    ASSERT_EQ(depth.step(), step);
    double worst = 0.0;
    int invalid = 0;
    for (int v = step / 2; v < rows; ++v) {
      for (int u = step / 2; u < cols; ++u) {
        const float got = depth.at(u, v);
        invalid += std::isfinite(got) ? 0 : 1;
        if (std::isfinite(got)) worst = std::max(worst, std::abs(got - 1.0 / planeInverseDepth(u, v)));
      }
    }
    EXPECT_EQ(invalid, 0);
    EXPECT_LT(worst, 0.5 / kDepthScale + 1e-6);
  }
}

TEST(KeyframeDepth, ReadingsFartherApartThanTheSpanAreNotInterpolated) {
  // Two columns of readings 7 % and 9 % apart (kInterpolateSpan: 8 %): the pixels between the
  // first pair read between them, those between the second each its own block's reading.
  const int step = 4;
  cv::Mat sparse(30, 40, CV_16UC1, cv::Scalar(10000));  // 2 m
  sparse.col(11).setTo(10700);                          // 2.14 m
  sparse.col(31).setTo(10900);                          // 2.18 m
  const KeyframeDepth depth(expandedDepth(sparse, step, 120, 160), kDepthScale, kMinM, kMaxM);
  for (int v = 20; v < 100; ++v) {
    const float near = depth.at(10 * step + step / 2 + 1, v), far = depth.at(30 * step + step / 2 + 1, v);
    EXPECT_GT(near, metresAsBefore(10000));
    EXPECT_LT(near, metresAsBefore(10700));
    EXPECT_EQ(far, metresAsBefore(10000));
    EXPECT_EQ(depth.at(30 * step + step / 2 + 3, v), metresAsBefore(10900));  // the pixel's own block is the farther
  }
}

TEST(KeyframeDepth, AnEdgeOrAMissingReadingIsNotBlended) {
  // An object 2.0 m away before a wall at 2.4 m (20 %), the edge inside a block's lattice
  // cell; and a missing reading on a slope (0.02 m a block): every pixel around them reads its
  // own block's reading, nothing between.
  const int step = 4;
  cv::Mat sparse(120, 160, CV_16UC1);
  for (int j = 0; j < 120; ++j) {
    for (int i = 0; i < 160; ++i) {
      sparse.at<uint16_t>(j, i) = static_cast<uint16_t>(i < 80 ? 2.0 * kDepthScale : (2.4 + 0.02 * (i - 80)) * kDepthScale);
    }
  }
  sparse.at<uint16_t>(60, 120) = 0;
  const KeyframeDepth depth(expandedDepth(sparse, step, 480, 640), kDepthScale, kMinM, kMaxM);
  // The pixels between the readings of columns 79 and 80 (centres 318 and 322).
  for (int v = 0; v < 480; ++v) {
    for (int u = 319; u < 322; ++u) {
      ASSERT_EQ(depth.at(u, v), metresAsBefore(sparse.at<uint16_t>(v / step, u / step))) << u << "," << v;
    }
  }
  // The pixels whose four readings include the missing one (centre 482, 242).
  for (int v = 239; v < 246; ++v) {
    for (int u = 479; u < 486; ++u) {
      const float own = metresAsBefore(sparse.at<uint16_t>(v / step, u / step)), got = depth.at(u, v);
      if (std::isnan(own)) {
        EXPECT_TRUE(std::isnan(got)) << u << "," << v;
      } else {
        EXPECT_EQ(got, own) << u << "," << v;
      }
    }
  }
  expectReadsBetweenReadings(depth, sparse, step);
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
      expectReadsBetweenReadings(depth, sparse, step);
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
  planeAtStep(4, 480, 640).rowRange(240, 480).copyTo(data.depth.rowRange(240, 480));  // a slope below
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
      if (d && v >= 248 && v < 476 && u >= 2 && u < 638) {  // the slope, its interpolation at the nearest pixel
        EXPECT_NEAR(*d, 1.0 / planeInverseDepth(u, v), 0.5 / kDepthScale + 1e-6) << u << "," << v;
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
