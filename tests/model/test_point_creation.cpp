#include "rgbdslam/model/point_creation.h"

#include <gtest/gtest.h>

#include <opencv2/core.hpp>

namespace rgbdslam {
namespace {

// Flat grey with Gaussian noise of 'sigma' grey levels (0: none).
ImagePyramid noisyGreyPyramid(double sigma) {
  cv::Mat image(480, 640, CV_8UC1, cv::Scalar(100));
  if (sigma > 0.0) {
    cv::Mat noise(image.size(), CV_32F);
    cv::RNG rng(5);
    rng.fill(noise, cv::RNG::NORMAL, 100.0, sigma);
    noise.convertTo(image, CV_8U);
  }
  return buildPyramid(image);
}

TEST(PointCreation, WeakCornersMustStandAboveTheImageNoise) {
  DepthPointOptions options;  // floor 4x the noise's score, at least 2, never above 30
  // Noise of 3 grey levels scores 4.5 at level 0, and a quarter of that per level up.
  const std::vector<double> noisy = weakScoreFloors(noisyGreyPyramid(3.0), options);
  ASSERT_EQ(noisy.size(), static_cast<size_t>(kMaxLevels));
  EXPECT_NEAR(noisy[0], 4.0 * 4.5, 0.1 * 18.0);
  EXPECT_NEAR(noisy[1], 4.0 * 4.5 / 4.0, 0.1 * 4.5);
  for (int level = 2; level < kMaxLevels; ++level) EXPECT_EQ(noisy[level], 2.0) << level;
  // A noisier camera's weak corners must be stronger; a noiseless image keeps the floor.
  EXPECT_EQ(weakScoreFloors(noisyGreyPyramid(8.0), options)[0], options.min_shi_tomasi);
  for (double floor : weakScoreFloors(noisyGreyPyramid(0.0), options)) EXPECT_EQ(floor, 2.0);
  // The ratio off: the fixed floor alone (the rule before the noise estimate).
  options.weak_noise_ratio = 0.0;
  options.weak_min_shi_tomasi = 10.0;
  for (double floor : weakScoreFloors(noisyGreyPyramid(3.0), options)) EXPECT_EQ(floor, 10.0);
}

}  // namespace
}  // namespace rgbdslam
