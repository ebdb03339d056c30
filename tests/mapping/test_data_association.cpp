#include "rgbdslam/mapping/data_association.h"

#include <gtest/gtest.h>

#include <opencv2/core.hpp>

namespace rgbdslam {
namespace {

// An 8x8 template of a vertical step of 'contrast' grey levels (zero-mean energy
// 64 * (contrast / 2)^2), plus a flat image patch to match it against.
Patch stepPatch(int contrast) {
  cv::Mat image(32, 32, CV_8UC1, cv::Scalar(100));
  image(cv::Rect(16, 0, 16, 32)).setTo(cv::Scalar(100 + contrast));
  Patch patch;
  EXPECT_TRUE(extractPatch(image, cv::Point2i(16, 16), &patch));
  return patch;
}

TEST(DataAssociation, FlatCapRejectsWeakTemplatesOnTextureless) {
  const int max_zmssd = 400 * 64;
  // A weak template (step of 10: energy 1600): the absolute threshold alone would accept a
  // flat patch, whose ZMSSD equals the energy; the cap at 0.7 E does not.
  const Patch weak = stepPatch(10);
  const double energy = weak.sum_sq - static_cast<double>(weak.sum) * weak.sum / kPatchArea;
  EXPECT_NEAR(energy, 1600.0, 1.0);
  cv::Mat flat(32, 32, CV_8UC1, cv::Scalar(120));
  const int flat_zmssd = zmssdAt(weak, flat, cv::Point2i(16, 16));
  EXPECT_LT(flat_zmssd, flatCappedAcceptance(weak, max_zmssd, 0.0));  // off: accepted
  EXPECT_GE(flat_zmssd, flatCappedAcceptance(weak, max_zmssd, 0.7));  // on: rejected
  EXPECT_EQ(flatCappedAcceptance(weak, max_zmssd, 0.7), static_cast<int>(0.7 * energy));
  // A strong template keeps the absolute threshold (the cap is above it).
  const Patch strong = stepPatch(120);
  EXPECT_EQ(flatCappedAcceptance(strong, max_zmssd, 0.7), max_zmssd);
}

}  // namespace
}  // namespace rgbdslam
