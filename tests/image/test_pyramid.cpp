#include "rgbdslam/image/pyramid.h"

#include <gtest/gtest.h>

namespace rgbdslam {
namespace {

TEST(Pyramid, LevelSizesHalveAndDropOddRows) {
  const cv::Mat grey(481, 643, CV_8UC1, cv::Scalar(7));
  const ImagePyramid pyramid = buildPyramid(grey);
  ASSERT_EQ(pyramid.numLevels(), kMaxLevels);
  EXPECT_EQ(pyramid.levels[0].size(), cv::Size(643, 481));
  EXPECT_EQ(pyramid.levels[1].size(), cv::Size(321, 240));
  EXPECT_EQ(pyramid.levels[2].size(), cv::Size(160, 120));
  EXPECT_EQ(pyramid.levels[3].size(), cv::Size(80, 60));
  for (const cv::Mat& level : pyramid.levels) EXPECT_EQ(level.type(), CV_8UC1);
  EXPECT_EQ(buildPyramid(grey, 2).numLevels(), 2);
}

TEST(Pyramid, LevelIsRounded2x2Average) {
  cv::Mat grey(4, 6, CV_8UC1);
  for (int y = 0; y < grey.rows; ++y) {
    for (int x = 0; x < grey.cols; ++x) grey.at<uint8_t>(y, x) = static_cast<uint8_t>(y * 37 + x * 11 + (x * y) % 5);
  }
  const ImagePyramid pyramid = buildPyramid(grey, 2);
  const cv::Mat& half = pyramid.levels[1];
  ASSERT_EQ(half.size(), cv::Size(3, 2));
  for (int y = 0; y < 2; ++y) {
    for (int x = 0; x < 3; ++x) {
      const int sum = grey.at<uint8_t>(2 * y, 2 * x) + grey.at<uint8_t>(2 * y, 2 * x + 1) +
                      grey.at<uint8_t>(2 * y + 1, 2 * x) + grey.at<uint8_t>(2 * y + 1, 2 * x + 1);
      EXPECT_EQ(half.at<uint8_t>(y, x), (sum + 2) / 4) << x << "," << y;
    }
  }
  // A hand-computed block: 1 + 2 + 3 + 5 = 11 -> 2.75 -> 3 (rounded, not truncated).
  cv::Mat block = (cv::Mat_<uint8_t>(2, 2) << 1, 2, 3, 5);
  EXPECT_EQ(buildPyramid(block, 2).levels[1].at<uint8_t>(0, 0), 3);
}

TEST(Pyramid, ReusedBuffersGiveTheSameResult) {
  cv::Mat a(96, 128, CV_8UC1), b(96, 128, CV_8UC1);
  cv::randu(a, 0, 256);
  cv::randu(b, 0, 256);
  ImagePyramid reused;
  buildPyramid(a, kMaxLevels, &reused);
  const uint8_t* level1_data = reused.levels[1].data;
  buildPyramid(b, kMaxLevels, &reused);
  EXPECT_EQ(reused.levels[1].data, level1_data);  // no reallocation
  const ImagePyramid fresh = buildPyramid(b);
  for (int l = 0; l < kMaxLevels; ++l) {
    EXPECT_EQ(cv::norm(reused.levels[l], fresh.levels[l], cv::NORM_INF), 0.0) << l;
  }
}

TEST(Pyramid, LevelCoordinatesFollowPixelCentres) {
  // The centre of level-1 pixel 0 is between level-0 pixels 0 and 1.
  EXPECT_DOUBLE_EQ(zeroFromLevel(Eigen::Vector2d(0, 0), 1).x(), 0.5);
  EXPECT_DOUBLE_EQ(zeroFromLevel(Eigen::Vector2d(0, 0), 2).x(), 1.5);
  EXPECT_DOUBLE_EQ(levelFromZero(Eigen::Vector2d(1.5, 1.5), 2).y(), 0.0);
  EXPECT_DOUBLE_EQ(levelFromZero(Eigen::Vector2d(319.5, 239.5), 3).x(), 39.5);
  EXPECT_DOUBLE_EQ(levelScale(3), 8.0);
  const Eigen::Vector2d uv(123.25, 77.8);
  for (int level = 0; level < kMaxLevels; ++level) {
    EXPECT_LT((zeroFromLevel(levelFromZero(uv, level), level) - uv).norm(), 1e-12);
    EXPECT_LT((levelFromZero(zeroFromLevel(uv, level), level) - uv).norm(), 1e-12);
  }
}

TEST(Pyramid, CoordinatesMatchTheAveragedContent) {
  // A bright pixel block at level-0 pixels 8..11 (centre 9.5) lands at level-2 pixel 2
  // (centre 2.0 = levelFromZero(9.5)).
  cv::Mat grey(32, 32, CV_8UC1, cv::Scalar(0));
  grey(cv::Rect(8, 8, 4, 4)).setTo(200);
  const ImagePyramid pyramid = buildPyramid(grey, 3);
  cv::Point max_loc;
  cv::minMaxLoc(pyramid.levels[2], nullptr, nullptr, nullptr, &max_loc);
  const Eigen::Vector2d centre = levelFromZero(Eigen::Vector2d(9.5, 9.5), 2);
  EXPECT_EQ(max_loc, cv::Point(static_cast<int>(centre.x()), static_cast<int>(centre.y())));
  EXPECT_DOUBLE_EQ(centre.x(), 2.0);
}

}  // namespace
}  // namespace rgbdslam
