#include "rgbdslam/model/noise_model.h"

#include <gtest/gtest.h>

namespace rgbdslam {
namespace {

TEST(NoiseModel, SigmasGrowWithLevelAndSquaredDepth) {
  const NoiseModel paper;  // the paper's k and a
  EXPECT_DOUBLE_EQ(paper.sigma2d(0), 0.987);
  EXPECT_DOUBLE_EQ(paper.sigma2d(2), 4 * 0.987);
  EXPECT_DOUBLE_EQ(paper.sigmaDepth(2.0), 4 * 3.331e-3);
  NoiseModel other;
  other.sigma_2d_k = 1.5;
  other.depth_sigma_a = 0.01;
  EXPECT_DOUBLE_EQ(other.sigma2d(3), 12.0);
  EXPECT_DOUBLE_EQ(other.sigmaDepth(3.0), 0.09);
}

TEST(NoiseModel, OneConfigurationPlaceForEveryCopy) {
  NoiseModel tracker_copy, mapper_copy;
  OptionRegistry registry;
  tracker_copy.bind(&registry);
  mapper_copy.bind(&registry);
  ASSERT_TRUE(registry.set("noise.sigma_2d_k=1.25"));
  ASSERT_TRUE(registry.set("noise.depth_sigma_a=0.004"));
  EXPECT_DOUBLE_EQ(tracker_copy.sigma_2d_k, 1.25);
  EXPECT_DOUBLE_EQ(mapper_copy.sigma_2d_k, 1.25);
  EXPECT_DOUBLE_EQ(tracker_copy.depth_sigma_a, 0.004);
  EXPECT_DOUBLE_EQ(mapper_copy.depth_sigma_a, 0.004);
}

}  // namespace
}  // namespace rgbdslam
