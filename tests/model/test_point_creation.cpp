#include "rgbdslam/model/point_creation.h"

#include <gtest/gtest.h>

#include <algorithm>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

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

// A keyframe at the origin seeing a wall of random 4x4 px squares 2 m away: corners at
// every level, each with depth.
std::unique_ptr<Keyframe> texturedWallKeyframe() {
  cv::Mat small(120, 160, CV_8UC1);
  cv::RNG rng(7);
  rng.fill(small, cv::RNG::UNIFORM, 0, 256);
  KeyframeData data;
  cv::resize(small, data.grey, cv::Size(640, 480), 0, 0, cv::INTER_NEAREST);
  data.depth_scale = 5000.0;
  data.depth = cv::Mat(480, 640, CV_16UC1, cv::Scalar(10000));  // 2 m
  return makeKeyframe(data, KeyframeBuildOptions{});
}

TEST(PointCreation, NoWeakPassWithoutAWeakFloor) {
  const auto keyframe = texturedWallKeyframe();
  DepthPointOptions options;
  options.max_points_per_level = 5;
  options.weak_until_points = 100000;
  options.weak_noise_ratio = 0.0;
  // Floors equal to min_shi_tomasi: no second pass, so no level gives more than its cut.
  options.weak_min_shi_tomasi = options.min_shi_tomasi;
  const auto strong = createPointsFromDepth(*keyframe, PinholeCamera{}, options, 0);
  ASSERT_GT(strong.size(), 5u);
  std::vector<int> per_level(kMaxLevels, 0);
  for (const NewPoint& p : strong) ++per_level.at(p.point.source_level);
  for (int level = 0; level < kMaxLevels; ++level) EXPECT_LE(per_level[level], 5) << level;
  // A floor just under it: the second pass runs and takes more (its count restarts).
  options.weak_min_shi_tomasi = options.min_shi_tomasi - 0.5;
  EXPECT_GT(createPointsFromDepth(*keyframe, PinholeCamera{}, options, 0).size(), strong.size());
}

}  // namespace
}  // namespace rgbdslam
