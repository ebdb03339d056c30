#include "rgbdslam/image/corners.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <opencv2/imgproc.hpp>

namespace rgbdslam {
namespace {

constexpr int kSquare = 16;  // board cell [px]
constexpr int kGap = 4;      // dark gap between bright squares [px]

// A board of bright squares (kSquare - kGap wide) on a dark background, so every square
// corner is an isolated L-corner (FAST does not fire on the X-junctions of a true
// checkerboard). Returns the image and the positions of the square corner pixels.
cv::Mat squareBoard(int cols, int rows, std::vector<cv::Point2i>* square_corners) {
  cv::Mat image(rows, cols, CV_8UC1, cv::Scalar(40));
  for (int y = kSquare; y + kSquare <= rows - kSquare; y += kSquare) {
    for (int x = kSquare; x + kSquare <= cols - kSquare; x += kSquare) {
      const int side = kSquare - kGap;
      image(cv::Rect(x, y, side, side)).setTo(200);
      square_corners->emplace_back(x, y);
      square_corners->emplace_back(x + side - 1, y);
      square_corners->emplace_back(x, y + side - 1);
      square_corners->emplace_back(x + side - 1, y + side - 1);
    }
  }
  return image;
}

cv::Mat texture(int cols, int rows, double blur_sigma, int seed) {
  cv::Mat image(rows, cols, CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(image, image, cv::Size(0, 0), blur_sigma);
  cv::normalize(image, image, 0, 255, cv::NORM_MINMAX);
  return image;
}

double distanceToNearest(const cv::Point2i& p, const std::vector<cv::Point2i>& set) {
  double best = 1e9;
  for (const cv::Point2i& q : set) best = std::min(best, cv::norm(p - q));
  return best;
}

TEST(Corners, FindsSquareCornersOnABoard) {
  std::vector<cv::Point2i> truth;
  const cv::Mat image = squareBoard(160, 128, &truth);
  LevelCorners corners;
  detectCorners(image, 20, 5, &corners);
  ASSERT_FALSE(corners.maxima.empty());
  // FAST fires near corners only (never along straight edges or inside flat areas) ...
  for (const cv::Point2i& p : corners.all) {
    EXPECT_LE(distanceToNearest(p, truth), 2.0) << p;
  }
  // ... and every square corner has exactly one maximum within 2 px.
  for (const cv::Point2i& q : truth) {
    int near = 0;
    for (const cv::Point2i& p : corners.maxima) near += cv::norm(p - q) <= 2.0;
    EXPECT_EQ(near, 1) << q;
  }
}

TEST(Corners, SortedWithConsistentRowIndex) {
  const cv::Mat image = texture(200, 150, 1.5, 1);
  LevelCorners corners;
  detectCorners(image, 10, 5, &corners);
  ASSERT_GT(corners.all.size(), 100u);
  ASSERT_EQ(corners.row_start.size(), static_cast<size_t>(image.rows + 1));
  EXPECT_EQ(corners.row_start.front(), 0);
  EXPECT_EQ(corners.row_start.back(), static_cast<int>(corners.all.size()));
  for (int y = 0; y < image.rows; ++y) {
    for (int i = corners.row_start[y]; i < corners.row_start[y + 1]; ++i) {
      ASSERT_EQ(corners.all[i].y, y);
      if (i > corners.row_start[y]) {
        ASSERT_LT(corners.all[i - 1].x, corners.all[i].x);
      }
    }
  }
  for (const cv::Point2i& p : corners.all) {
    EXPECT_TRUE(p.x >= 5 && p.y >= 5 && p.x < image.cols - 5 && p.y < image.rows - 5) << p;
  }
}

TEST(Corners, DetectorAgreesWithBruteForceScore) {
  // A corner at threshold t is exactly a pixel whose FAST score is >= t.
  for (int threshold : {5, 12, 30}) {
    const cv::Mat image = texture(120, 90, 1.2, threshold);
    LevelCorners corners;
    detectFastCorners(image, threshold, 3, &corners);
    std::vector<cv::Point2i> expected;
    for (int y = 3; y < image.rows - 3; ++y) {
      for (int x = 3; x < image.cols - 3; ++x) {
        if (fastScore(image, {x, y}) >= threshold) expected.emplace_back(x, y);
      }
    }
    ASSERT_FALSE(expected.empty());
    EXPECT_EQ(corners.all, expected) << "threshold " << threshold;
  }
}

TEST(Corners, FastScoreOfAHandMadeCorner) {
  cv::Mat image(9, 9, CV_8UC1, cv::Scalar(100));
  // Circle pixels clockwise from the top; make 10 contiguous ones (from (3,-1)) brighter.
  const int circle[16][2] = {{0, -3}, {1, -3}, {2, -2}, {3, -1}, {3, 0}, {3, 1}, {2, 2}, {1, 3},
                             {0, 3}, {-1, 3}, {-2, 2}, {-3, 1}, {-3, 0}, {-3, -1}, {-2, -2}, {-1, -3}};
  for (int k = 3; k < 13; ++k) image.at<uint8_t>(4 + circle[k][1], 4 + circle[k][0]) = 130;
  image.at<uint8_t>(4 + circle[7][1], 4 + circle[7][0]) = 160;  // the arc minimum stays 130
  EXPECT_EQ(fastScore(image, {4, 4}), 29);
  // Only 9 contiguous: not a corner at any positive threshold.
  image.at<uint8_t>(4 + circle[12][1], 4 + circle[12][0]) = 100;
  EXPECT_LE(fastScore(image, {4, 4}), 0);
}

TEST(Corners, NonMaximumSuppressionKeepsLocalMaximaOnly) {
  const cv::Mat image = texture(200, 150, 1.5, 2);
  LevelCorners corners;
  detectCorners(image, 8, 5, &corners);
  ASSERT_EQ(corners.scores.size(), corners.all.size());
  ASSERT_FALSE(corners.maxima.empty());
  ASSERT_LT(corners.maxima.size(), corners.all.size());
  std::vector<bool> kept(corners.all.size(), false);
  for (const cv::Point2i& m : corners.maxima) {
    auto it = std::find(corners.all.begin(), corners.all.end(), m);
    ASSERT_NE(it, corners.all.end());
    kept[it - corners.all.begin()] = true;
  }
  for (size_t i = 0; i < corners.all.size(); ++i) {
    EXPECT_EQ(corners.scores[i], fastScore(image, corners.all[i]));
    bool beaten = false;
    for (size_t j = 0; j < corners.all.size(); ++j) {
      const cv::Point2i d = corners.all[j] - corners.all[i];
      if (j == i || std::abs(d.x) > 1 || std::abs(d.y) > 1) continue;
      beaten |= corners.scores[j] > corners.scores[i] ||
                (corners.scores[j] == corners.scores[i] && j < i);
    }
    EXPECT_EQ(kept[i], !beaten) << corners.all[i];
  }
}

TEST(Corners, ReusedBuffersAreReset) {
  LevelCorners corners;
  detectCorners(texture(100, 80, 1.5, 3), 10, 5, &corners);
  ASSERT_FALSE(corners.all.empty());
  const cv::Mat flat(60, 70, CV_8UC1, cv::Scalar(90));
  detectCorners(flat, 10, 5, &corners);
  EXPECT_TRUE(corners.all.empty());
  EXPECT_TRUE(corners.maxima.empty());
  EXPECT_EQ(corners.row_start.size(), 61u);
}

TEST(Corners, PyramidCornersUseTheLevelThresholds) {
  const ImagePyramid pyramid = buildPyramid(texture(320, 240, 2.0, 4));
  CornerOptions options;
  std::vector<LevelCorners> corners;
  detectPyramidCorners(pyramid, options, false, &corners);
  ASSERT_EQ(corners.size(), static_cast<size_t>(kMaxLevels));
  for (int level = 0; level < kMaxLevels; ++level) {
    LevelCorners single;
    detectFastCorners(pyramid.levels[level], options.fast_thresholds[level], options.border,
                      &single);
    EXPECT_EQ(corners[level].all, single.all) << level;
    EXPECT_TRUE(corners[level].maxima.empty());
  }
}

TEST(Corners, ShiTomasiRanksCornersAboveEdgesAndFlats) {
  cv::Mat image(40, 40, CV_8UC1, cv::Scalar(50));
  image(cv::Rect(20, 20, 20, 20)).setTo(150);
  const float corner = shiTomasiScore(image, {20, 20}, 3);
  const float edge = shiTomasiScore(image, {20, 30}, 3);
  const float flat = shiTomasiScore(image, {8, 8}, 3);
    EXPECT_NEAR(edge, 0.0f, 1e-3f);
  EXPECT_NEAR(flat, 0.0f, 1e-3f);
  EXPECT_EQ(shiTomasiScore(image, {2, 20}, 3), 0.0f);  // window leaves the image
  // Exact value: central-difference gradients are 50 on the two pixel lines beside each
  // step of 100; in the 7x7 window at the corner 8 pixels have gx = 50, 8 have gy = 50 and
  // one ((20, 20)) has both, so the averaged tensor is [20000 2500; 2500 20000] / 49 and
  // its smaller eigenvalue (20000 - 2500) / 49.
  EXPECT_NEAR(corner, 17500.0f / 49.0f, 1e-3f);
  cv::Mat rotated;
  cv::rotate(image, rotated, cv::ROTATE_180);
  EXPECT_NEAR(shiTomasiScore(rotated, {19, 19}, 3), corner, 1e-3f);
}

// A ramp (which the noise estimator must ignore) with Gaussian noise of 'sigma' grey levels.
cv::Mat noisyRamp(double sigma, uint64_t seed) {
  cv::Mat ramp(480, 640, CV_32F);
  for (int y = 0; y < ramp.rows; ++y) {
    for (int x = 0; x < ramp.cols; ++x) ramp.at<float>(y, x) = 60.0f + 0.15f * x + 0.1f * y;
  }
  cv::Mat noise(ramp.size(), CV_32F);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, sigma);
  cv::Mat image;
  cv::Mat(ramp + noise).convertTo(image, CV_8U);  // rounds and saturates
  return image;
}

TEST(Corners, NoiseSigmaOfGaussianNoiseOnARamp) {
  EXPECT_LT(imageNoiseSigma(noisyRamp(0.0, 1)), 0.4);  // the ramp's rounding only
  for (const double sigma : {1.5, 3.0, 6.0}) {
    EXPECT_NEAR(imageNoiseSigma(noisyRamp(sigma, 2)), sigma, 0.1 * sigma) << sigma;
  }
  EXPECT_EQ(imageNoiseSigma(cv::Mat(2, 2, CV_8UC1, cv::Scalar(7))), 0.0);
}

// What DepthPointOptions' weak floor (four times noiseShiTomasiScore) rests on: in pure
// noise the Shi-Tomasi score averages about 0.8 times noiseShiTomasiScore(sigma), and no
// window of the ~32000 here reaches three times it.
TEST(Corners, NoiseAloneScoresUnderThreeTimesTheNoiseScore) {
  const double sigma = 3.0;
  const cv::Mat image = noisyRamp(sigma, 3);
  const double noise_score = noiseShiTomasiScore(sigma);
  double sum = 0.0, highest = 0.0;
  int windows = 0;
  for (int y = 8; y < image.rows - 8; y += 3) {
    for (int x = 8; x < image.cols - 8; x += 3) {
      const double score = shiTomasiScore(image, {x, y});
      sum += score;
      highest = std::max(highest, score);
      ++windows;
    }
  }
  EXPECT_GT(windows, 30000);
  EXPECT_GT(sum / windows, 0.7 * noise_score);
  EXPECT_LT(sum / windows, 0.9 * noise_score);
  EXPECT_LT(highest, 3.0 * noise_score) << highest / noise_score << "x";
}

TEST(Corners, BlockMaskCoversEachCornerWithAPixelOfItsLevel) {
  std::vector<LevelCorners> corners(kMaxLevels);
  corners[0].all = {cv::Point2i(10, 10)};  // level 0: pixels 8..12 -> blocks 2..3 (step 4)
  corners[2].all = {cv::Point2i(10, 5)};   // level 2: (41.5, 21.5) +- 5 -> u 36.5..46.5, v 16.5..26.5
  const cv::Mat mask = cornerBlockMask(corners, 4, cv::Size(64, 48));
  ASSERT_EQ(mask.size(), cv::Size(16, 12));
  cv::Mat expected(12, 16, CV_8UC1, cv::Scalar(0));
  expected(cv::Range(2, 4), cv::Range(2, 4)).setTo(255);
  expected(cv::Range(4, 7), cv::Range(9, 12)).setTo(255);
  EXPECT_EQ(cv::countNonZero(mask != expected), 0);
  // A corner at the edge keeps the edge blocks; a size that is not a multiple of the step rounds up.
  corners = std::vector<LevelCorners>(1);
  corners[0].all = {cv::Point2i(0, 0)};
  const cv::Mat edge = cornerBlockMask(corners, 8, cv::Size(20, 10));
  ASSERT_EQ(edge.size(), cv::Size(3, 2));
  EXPECT_EQ(edge.at<uint8_t>(0, 0), 255);
  EXPECT_EQ(cv::countNonZero(edge), 1);
}

TEST(Corners, LossyCornerOptionsLowerEveryThresholdToOneAtLeast) {
  CornerOptions options;
  options.fast_thresholds = {10, 15, 3, 10};
  const CornerOptions lossy = lossyCornerOptions(options);
  EXPECT_EQ(lossy.fast_thresholds, (std::array<int, kMaxLevels>{6, 11, 1, 6}));
  EXPECT_EQ(lossyCornerOptions(options, 9).fast_thresholds, (std::array<int, kMaxLevels>{1, 6, 1, 1}));
  EXPECT_EQ(lossy.border, options.border);
}

}  // namespace
}  // namespace rgbdslam
