#include "rgbdslam/tracking/feature_relocaliser.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "rgbdslam/synth/scene.h"

namespace rgbdslam {
namespace {

const SyntheticScene& relocRoom() {
  static const SyntheticScene scene(*parseSyntheticSpec("room,frames=400"));
  return scene;
}

Features3d featuresOf(const SyntheticScene& scene, size_t i) {
  const RgbdFrame frame = scene.render(i);
  cv::Mat grey;
  cv::cvtColor(frame.colour, grey, cv::COLOR_BGR2GRAY);
  return extractFeatures3d(grey, frame.depthMetres(), scene.camera(), FeatureRelocaliserOptions{});
}

// After the room's 2 s gap (frames 100-159 dropped) the camera is 30+ degrees and 0.3 m from
// the last keyframe's view: the features still give its pose from that keyframe.
TEST(FeatureRelocaliser, FindsThePoseAfterATwoSecondGap) {
  const SyntheticScene& room = relocRoom();
  const size_t keyframe = 90, frame = 160;
  const Features3d kf = featuresOf(room, keyframe), current = featuresOf(room, frame);
  ASSERT_GT(kf.size(), 200u);
  ASSERT_GT(current.size(), 200u);
  const SE3 T_w_k = room.groundTruthPose(keyframe);
  const std::optional<FeaturePose> pose =
      poseFromFeatures(current, kf, T_w_k, room.camera(), PoseOptimizerOptions{}, FeatureRelocaliserOptions{});
  ASSERT_TRUE(pose.has_value());
  const SE3 truth = room.groundTruthPose(frame);
  const SE3 error = truth.inverse() * pose->T_w_c;
  const double moved = (truth.translation() - T_w_k.translation()).norm();
  EXPECT_GT(moved, 0.2);  // the case PTAM's keyframe views do not reach
  EXPECT_LT(error.translation().norm(), 0.03);
  EXPECT_LT(error.log().tail<3>().norm() * 180.0 / M_PI, 1.0);
  EXPECT_GE(pose->inliers, FeatureRelocaliserOptions{}.min_inliers);
}

// Another world's view shares no 3-D structure with the keyframe: no pose, not a wrong one.
TEST(FeatureRelocaliser, GivesNoPoseForAnotherPlace) {
  const SyntheticScene corridor(*parseSyntheticSpec("corridor,frames=300"));
  const Features3d kf = featuresOf(relocRoom(), 90), elsewhere = featuresOf(corridor, 150);
  EXPECT_FALSE(poseFromFeatures(elsewhere, kf, relocRoom().groundTruthPose(90), relocRoom().camera(),
                                PoseOptimizerOptions{}, FeatureRelocaliserOptions{}).has_value());
}

TEST(FeatureRelocaliser, NeedsDepth) {
  const RgbdFrame frame = relocRoom().render(0);
  cv::Mat grey;
  cv::cvtColor(frame.colour, grey, cv::COLOR_BGR2GRAY);
  const cv::Mat no_depth(grey.size(), CV_32FC1, cv::Scalar(NAN));
  EXPECT_EQ(extractFeatures3d(grey, no_depth, relocRoom().camera(), FeatureRelocaliserOptions{}).size(), 0u);
  EXPECT_EQ(extractFeatures3d(grey, cv::Mat(), relocRoom().camera(), FeatureRelocaliserOptions{}).size(), 0u);
}

}  // namespace
}  // namespace rgbdslam
