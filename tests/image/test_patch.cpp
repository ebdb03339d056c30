#include "rgbdslam/image/patch.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace rgbdslam {
namespace {

cv::Mat texture(int cols, int rows, double blur_sigma, int seed) {
  cv::Mat image(rows, cols, CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(image, image, cv::Size(0, 0), blur_sigma);
  cv::normalize(image, image, 10, 245, cv::NORM_MINMAX);
  return image;
}

// A smooth analytic texture sampled at pixel centres shifted by -shift: the content moves
// by +shift, so a feature at x in shift = 0 appears at x + shift.
cv::Mat smoothTexture(int cols, int rows, const Eigen::Vector2d& shift) {
  cv::Mat image(rows, cols, CV_8UC1);
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < cols; ++x) {
      const double u = x - shift.x(), v = y - shift.y();
      const double value = 128 + 45 * std::sin(0.21 * u + 0.13 * v) +
                           40 * std::sin(-0.11 * u + 0.23 * v + 1.0) +
                           30 * std::cos(0.17 * u - 0.19 * v + 2.0);
      image.at<uint8_t>(y, x) = cv::saturate_cast<uint8_t>(value);
    }
  }
  return image;
}

// 'image' with its content moved by +shift [px], by bilinear interpolation (in double,
// rounded once); pixels whose source falls outside are clamped to the edge.
cv::Mat bilinearShift(const cv::Mat& image, const Eigen::Vector2d& shift) {
  cv::Mat shifted(image.size(), CV_8UC1);
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      const double u = std::clamp(x - shift.x(), 0.0, image.cols - 1.001);
      const double v = std::clamp(y - shift.y(), 0.0, image.rows - 1.001);
      const int x0 = static_cast<int>(u), y0 = static_cast<int>(v);
      const double fx = u - x0, fy = v - y0;
      const double value =
          (1 - fy) * ((1 - fx) * image.at<uint8_t>(y0, x0) + fx * image.at<uint8_t>(y0, x0 + 1)) +
          fy * ((1 - fx) * image.at<uint8_t>(y0 + 1, x0) + fx * image.at<uint8_t>(y0 + 1, x0 + 1));
      shifted.at<uint8_t>(y, x) = cv::saturate_cast<uint8_t>(value);
    }
  }
  return shifted;
}

std::vector<uint8_t> imagePatch(const cv::Mat& image, cv::Point2i centre) {
  std::vector<uint8_t> values;
  for (int r = 0; r < kPatchSize; ++r) {
    for (int c = 0; c < kPatchSize; ++c) {
      values.push_back(image.at<uint8_t>(centre.y - kPatchCentre + r, centre.x - kPatchCentre + c));
    }
  }
  return values;
}

std::vector<uint8_t> pixelsOf(const Patch& patch) {
  return std::vector<uint8_t>(patch.pixels.begin(), patch.pixels.end());
}

TEST(Patch, SearchLevelFollowsTheAreaMagnification) {
  const Eigen::Matrix2d I = Eigen::Matrix2d::Identity();
  EXPECT_EQ(chooseSearchLevel(I, 0, kMaxLevels), 0);
  EXPECT_EQ(chooseSearchLevel(1.6 * I, 0, kMaxLevels), 0);  // det 2.56 <= 3
  EXPECT_EQ(chooseSearchLevel(2.0 * I, 0, kMaxLevels), 1);  // 2x zoom: one level up
  EXPECT_EQ(chooseSearchLevel(4.0 * I, 0, kMaxLevels), 2);
  EXPECT_EQ(chooseSearchLevel(100.0 * I, 0, kMaxLevels), kMaxLevels - 1);
  EXPECT_EQ(chooseSearchLevel(100.0 * I, 0, 2), 1);
  EXPECT_EQ(chooseSearchLevel(I, 1, kMaxLevels), 1);        // same scale as the source
  EXPECT_EQ(chooseSearchLevel(0.5 * I, 2, kMaxLevels), 1);
  Eigen::Matrix2d mirror = I;
  mirror(0, 0) = -1;
  EXPECT_EQ(chooseSearchLevel(mirror, 0, kMaxLevels), -1);
  EXPECT_EQ(chooseSearchLevel(Eigen::Matrix2d::Zero(), 0, kMaxLevels), -1);
}

TEST(Patch, IdentityWarpReproducesTheImagePatch) {
  const ImagePyramid pyramid = buildPyramid(texture(160, 120, 1.0, 1));
  Patch patch;
  ASSERT_TRUE(warpPatch(pyramid.levels[0], 0, Eigen::Vector2d(37, 52), Eigen::Matrix2d::Identity(), 0, &patch));
  EXPECT_EQ(pixelsOf(patch), imagePatch(pyramid.levels[0], {37, 52}));
  Patch extracted;
  ASSERT_TRUE(extractPatch(pyramid.levels[0], {37, 52}, &extracted));
  EXPECT_EQ(pixelsOf(extracted), pixelsOf(patch));
  EXPECT_EQ(extracted.padded, patch.padded);
  int sum = 0, sum_sq = 0;
  for (uint8_t v : patch.pixels) sum += v, sum_sq += v * v;
  EXPECT_EQ(patch.sum, sum);
  EXPECT_EQ(patch.sum_sq, sum_sq);
  // At source level 1 the centre of level-1 pixel (20, 30) is level-0 (40.5, 60.5).
  ASSERT_TRUE(warpPatch(pyramid.levels[1], 1, Eigen::Vector2d(40.5, 60.5), Eigen::Matrix2d::Identity(), 1, &patch));
  EXPECT_EQ(pixelsOf(patch), imagePatch(pyramid.levels[1], {20, 30}));
}

TEST(Patch, ZoomedWarpSearchedOneLevelUpMatchesTheSource) {
  // The point looks twice as large now: search at level 1, where one pixel spans what a
  // source pixel spanned, so the template is the unwarped source patch.
  const cv::Mat image = texture(160, 120, 1.0, 2);
  const Eigen::Matrix2d A = 2.0 * Eigen::Matrix2d::Identity();
  const int level = chooseSearchLevel(A, 0, kMaxLevels);
  ASSERT_EQ(level, 1);
  Patch patch;
  ASSERT_TRUE(warpPatch(image, 0, Eigen::Vector2d(60, 70), A, level, &patch));
  EXPECT_EQ(pixelsOf(patch), imagePatch(image, {60, 70}));
}

TEST(Patch, RotatedWarpSamplesThroughTheInverse) {
  const cv::Mat image = texture(100, 100, 1.0, 3);
  Eigen::Matrix2d A;  // 90 degrees: +x in the source becomes +y now
  A << 0, -1, 1, 0;
  Patch patch;
  ASSERT_TRUE(warpPatch(image, 0, Eigen::Vector2d(50, 40), A, 0, &patch));
  const Eigen::Matrix2d A_inv = A.inverse();
  for (int r = 0; r < kPatchSize; ++r) {
    for (int c = 0; c < kPatchSize; ++c) {
      const Eigen::Vector2d src = Eigen::Vector2d(50, 40) + A_inv * Eigen::Vector2d(c - 4, r - 4);
      EXPECT_EQ(patch.pixels[r * kPatchSize + c],
                image.at<uint8_t>(static_cast<int>(std::lround(src.y())), static_cast<int>(std::lround(src.x()))));
    }
  }
}

TEST(Patch, WarpLeavingTheSourceFails) {
  const cv::Mat image = texture(64, 48, 1.0, 4);
  Patch patch;
  const Eigen::Matrix2d I = Eigen::Matrix2d::Identity();
  EXPECT_TRUE(warpPatch(image, 0, Eigen::Vector2d(5, 5), I, 0, &patch));  // margin 5..+4
  EXPECT_FALSE(warpPatch(image, 0, Eigen::Vector2d(4, 20), I, 0, &patch));
  EXPECT_FALSE(warpPatch(image, 0, Eigen::Vector2d(60, 20), I, 0, &patch));
  EXPECT_FALSE(warpPatch(image, 0, Eigen::Vector2d(30, 20), 0.2 * I, 0, &patch));  // 5x wider
  EXPECT_FALSE(warpPatch(image, 0, Eigen::Vector2d(30, 20), Eigen::Matrix2d::Zero(), 0, &patch));
  EXPECT_FALSE(extractPatch(image, {4, 20}, &patch));
}

TEST(Patch, ZmssdIsZeroMeanSsd) {
  const cv::Mat image = texture(80, 60, 1.0, 5);
  Patch patch;
  ASSERT_TRUE(extractPatch(image, {30, 30}, &patch));
  EXPECT_EQ(zmssdAt(patch, image, {30, 30}), 0);
  const cv::Point2i other(45, 20);
  double mean_t = 0, mean_i = 0;
  for (int i = 0; i < kPatchArea; ++i) mean_t += patch.pixels[i] / 64.0;
  const std::vector<uint8_t> values = imagePatch(image, other);
  for (uint8_t v : values) mean_i += v / 64.0;
  double expected = 0;
  for (int i = 0; i < kPatchArea; ++i) {
    const double d = (patch.pixels[i] - mean_t) - (values[i] - mean_i);
    expected += d * d;
  }
  EXPECT_NEAR(zmssdAt(patch, image, other), expected, 1.0);  // integer floor
  EXPECT_GT(expected, 1000.0);
}

TEST(Patch, ZmssdIgnoresABrightnessOffset) {
  const cv::Mat image = texture(80, 60, 1.0, 6);  // values 10..245
  Patch patch;
  ASSERT_TRUE(extractPatch(image, {30, 30}, &patch));
  const cv::Mat brighter = image + 9;
  const cv::Mat darker = image - 7;
  for (const cv::Point2i p : {cv::Point2i(30, 30), cv::Point2i(40, 25), cv::Point2i(12, 40)}) {
    EXPECT_EQ(zmssdAt(patch, brighter, p), zmssdAt(patch, image, p)) << p;
    EXPECT_EQ(zmssdAt(patch, darker, p), zmssdAt(patch, image, p)) << p;
  }
}

// At integer centres the sub-pixel ZMSSD is the integer one (up to rounding); on an image
// whose content moved by a fraction of a pixel it finds the template where the content went;
// it grows with the offset, and -1 outside the image.
TEST(Patch, SubpixelZmssdSamplesBilinearly) {
  const cv::Mat image = smoothTexture(80, 60, Eigen::Vector2d::Zero());
  Patch patch;
  ASSERT_TRUE(extractPatch(image, {30, 30}, &patch));
  for (const cv::Point2i p : {cv::Point2i(30, 30), cv::Point2i(40, 25), cv::Point2i(12, 40)}) {
    EXPECT_NEAR(zmssdAtSubpixel(patch, image, Eigen::Vector2d(p.x, p.y)), zmssdAt(patch, image, p), 1.0) << p;
  }
  const Eigen::Vector2d shift(0.4, -0.3);
  const cv::Mat moved = bilinearShift(image, shift);
  const Eigen::Vector2d there = Eigen::Vector2d(30, 30) + shift;
  const int at_the_content = zmssdAtSubpixel(patch, moved, there);
  EXPECT_LT(at_the_content, zmssdAt(patch, moved, {30, 30}));
  EXPECT_LT(at_the_content, 64 * 2);  // the two roundings: under a grey level per pixel
  int previous = at_the_content;
  for (double offset : {0.5, 1.0, 2.0}) {
    const int score = zmssdAtSubpixel(patch, moved, there + Eigen::Vector2d(offset, 0.0));
    EXPECT_GT(score, previous) << offset;
    previous = score;
  }
  EXPECT_EQ(zmssdAtSubpixel(patch, image, Eigen::Vector2d(3.5, 30)), -1);
  EXPECT_EQ(zmssdAtSubpixel(patch, image, Eigen::Vector2d(30, 56.0)), -1);
  EXPECT_GE(zmssdAtSubpixel(patch, image, Eigen::Vector2d(4.0, 30)), 0);
}

TEST(Patch, SearchFindsShiftedPatchesAmongCorners) {
  const cv::Mat image = texture(320, 240, 1.3, 7);
  const cv::Point2i offset(3, -2);
  cv::Mat shifted;
  const cv::Mat M = (cv::Mat_<double>(2, 3) << 1, 0, offset.x, 0, 1, offset.y);
  cv::warpAffine(image, shifted, M, image.size(), cv::INTER_NEAREST, cv::BORDER_REFLECT);
  LevelCorners original, current;
  detectCorners(image, 12, 5, &original);
  detectFastCorners(shifted, 12, 5, &current);
  int tried = 0, found = 0;
  for (const cv::Point2i& p : original.maxima) {
    if (p.x < 20 || p.y < 20 || p.x >= image.cols - 20 || p.y >= image.rows - 20) continue;
    Patch patch;
    ASSERT_TRUE(extractPatch(image, p, &patch));
    int score = -1;
    const auto match = searchPatch(patch, shifted, current, Eigen::Vector2d(p.x, p.y), 10, 5000, &score);
    ++tried;
    if (match && *match == p + offset) {
      ++found;
      EXPECT_EQ(score, 0);
    }
  }
  ASSERT_GT(tried, 50);
  EXPECT_EQ(found, tried);
}

TEST(Patch, SearchRespectsRadiusAndThreshold) {
  const cv::Mat image = texture(200, 150, 1.3, 8);
  LevelCorners corners;
  detectFastCorners(image, 12, 5, &corners);
  ASSERT_GT(corners.all.size(), 10u);
  const cv::Point2i target = corners.all[corners.all.size() / 2];
  Patch patch;
  ASSERT_TRUE(extractPatch(image, target, &patch));
  const Eigen::Vector2d predicted(target.x + 6.0, target.y + 6.0);  // 8.5 px away
  EXPECT_EQ(searchPatch(patch, image, corners, predicted, 9, 1000), target);
  int score = 0;
  EXPECT_NE(searchPatch(patch, image, corners, predicted, 8, 1000, &score), target);
  // Nothing at all passes a threshold of 0 (ZMSSD >= 0 is never < 0).
  EXPECT_FALSE(searchPatch(patch, image, corners, Eigen::Vector2d(target.x, target.y), 5, 0, &score));
  EXPECT_EQ(score, INT_MAX);
  // bestMatchAmong checks exactly the given positions.
  const std::vector<cv::Point2i> candidates{{20, 20}, target, {target.x + 1, target.y}, {1, 1}};
  EXPECT_EQ(bestMatchAmong(patch, image, candidates, 1000, &score), target);
  EXPECT_EQ(score, 0);
  EXPECT_FALSE(bestMatchAmong(patch, image, {{20, 20}, {1, 1}}, 1, &score));
}

// A bilinear "saddle" texture a + b x + c y + d x y around (x0, y0): bilinear interpolation
// reproduces it exactly, so a sub-pixel shift of it is recovered up to quantisation.
cv::Mat saddle(int cols, int rows, const Eigen::Vector2d& centre) {
  cv::Mat image(rows, cols, CV_8UC1);
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < cols; ++x) {
      const double u = x - centre.x(), v = y - centre.y();
      image.at<uint8_t>(y, x) = cv::saturate_cast<uint8_t>(128 + 2.0 * u - 1.5 * v + 2.5 * u * v);
    }
  }
  return image;
}

TEST(Patch, RefinementRecoversASubpixelShiftExactly) {
  for (const Eigen::Vector2d& shift : {Eigen::Vector2d(0.3, -0.4), Eigen::Vector2d(-0.45, 0.2),
                                       Eigen::Vector2d(0.0, 0.5)}) {
    const cv::Mat before = saddle(40, 40, Eigen::Vector2d(20, 20));
    const cv::Mat after = saddle(40, 40, Eigen::Vector2d(20, 20) + shift);
    Patch patch;
    ASSERT_TRUE(extractPatch(before, {20, 20}, &patch));
    // From the integer position and from one pixel further along x (within max_shift).
    const Eigen::Vector2d second(shift.x() >= 0 ? 21 : 19, 20);
    for (const Eigen::Vector2d& start : {Eigen::Vector2d(20, 20), second}) {
      Eigen::Vector2d position = start;
      ASSERT_TRUE(refineSubpixel(patch, after, &position)) << shift.transpose();
      EXPECT_LT((position - Eigen::Vector2d(20, 20) - shift).norm(), 0.02)
          << "shift " << shift.transpose() << " from " << start.transpose() << " got "
          << position.transpose();
    }
  }
}

// Refines every FAST maximum of 'before' (away from the border) in 'after' from its integer
// position and returns the errors against the true position + shift [px] and their mean.
std::vector<double> refinementErrors(const cv::Mat& before, const cv::Mat& after,
                                     const Eigen::Vector2d& shift, Eigen::Vector2d* mean) {
  LevelCorners corners;
  detectCorners(before, 10, 12, &corners);
  std::vector<double> errors;
  *mean = Eigen::Vector2d::Zero();
  for (const cv::Point2i& p : corners.maxima) {
    Patch patch;
    EXPECT_TRUE(extractPatch(before, p, &patch));
    Eigen::Vector2d position(p.x, p.y);
    if (!refineSubpixel(patch, after, &position)) {
      ADD_FAILURE() << "no convergence at " << p;
      continue;
    }
    const Eigen::Vector2d error = position - Eigen::Vector2d(p.x, p.y) - shift;
    errors.push_back(error.norm());
    *mean += error;
  }
  if (!errors.empty()) *mean /= static_cast<double>(errors.size());
  std::sort(errors.begin(), errors.end());
  return errors;
}

TEST(Patch, RefinementOnTextureIsUnbiased) {
  // A random texture moved by (0.3, -0.4) px by bilinear interpolation. Per point, the 8x8
  // window's least-squares optimum itself scatters by ~0.05 px (the interpolation blurs the
  // moved image, and the blur's effect does not cancel inside a small window), so single
  // points are checked loosely; the mean over many corners must be exact: any sign or
  // half-pixel convention error would show there.
  const Eigen::Vector2d shift(0.3, -0.4);
  const cv::Mat before = texture(300, 200, 1.5, 10);
  Eigen::Vector2d mean;
  const std::vector<double> errors = refinementErrors(before, bilinearShift(before, shift), shift, &mean);
  ASSERT_GT(errors.size(), 500u);
  EXPECT_LT(mean.norm(), 0.01);
  EXPECT_LT(errors[errors.size() / 2], 0.06);       // median
  EXPECT_LT(errors[errors.size() * 9 / 10], 0.12);  // 90th percentile
  EXPECT_LT(errors.back(), 0.35);
}

TEST(Patch, RefinementOnAContinuousTextureIsAccurateToATenth) {
  // Sampling an analytic texture at shifted pixel centres: bilinear interpolation misfits
  // the curved texture, which moves the optimum of an 8x8 window by up to about 0.1 px (the
  // exact least-squares minimum, not a solver error).
  const Eigen::Vector2d shift(0.3, -0.4);
  Eigen::Vector2d mean;
  const std::vector<double> errors = refinementErrors(
      smoothTexture(200, 150, Eigen::Vector2d::Zero()), smoothTexture(200, 150, shift), shift, &mean);
  ASSERT_GT(errors.size(), 20u);
  EXPECT_LT(errors[errors.size() / 2], 0.06);
  EXPECT_LT(errors.back(), 0.15);
}

TEST(Patch, RefinementCompensatesBrightnessBias) {
  const Eigen::Vector2d shift(-0.25, 0.35);
  const cv::Mat before = smoothTexture(100, 80, Eigen::Vector2d::Zero());
  const cv::Mat after = smoothTexture(100, 80, shift) - 15;
  Patch patch;
  ASSERT_TRUE(extractPatch(before, {50, 40}, &patch));
  Eigen::Vector2d position(50, 40);
  ASSERT_TRUE(refineSubpixel(patch, after, &position));
  EXPECT_LT((position - Eigen::Vector2d(50, 40) - shift).norm(), 0.05);
}

TEST(Patch, RefinementFailsWithoutTextureOrMatch) {
  const cv::Mat flat(60, 60, CV_8UC1, cv::Scalar(100));
  Patch patch;
  ASSERT_TRUE(extractPatch(flat, {30, 30}, &patch));
  Eigen::Vector2d position(30, 30);
  EXPECT_FALSE(refineSubpixel(patch, flat, &position));
  // A patch that is not there diverges (or fails to converge) instead of wandering off.
  const cv::Mat image = texture(100, 100, 1.3, 9);
  ASSERT_TRUE(extractPatch(image, {30, 30}, &patch));
  int failures = 0;
  for (int y = 20; y < 80; y += 10) {
    for (int x = 50; x < 80; x += 10) {
      Eigen::Vector2d wrong(x, y);
      const bool ok = refineSubpixel(patch, image, &wrong);
      failures += !ok;
      if (!ok) {
        EXPECT_EQ(wrong, Eigen::Vector2d(x, y));  // unchanged on failure
      }
      EXPECT_LE((wrong - Eigen::Vector2d(x, y)).norm(), SubpixelOptions{}.max_shift);
    }
  }
  EXPECT_GT(failures, 0);
  // Too close to the edge to sample the patch.
  Eigen::Vector2d edge(3.5, 50);
  EXPECT_FALSE(refineSubpixel(patch, image, &edge));
}

}  // namespace
}  // namespace rgbdslam
