#include "rgbdslam/tracking/keyframe_policy.h"

#include <gtest/gtest.h>

#include <cmath>

namespace rgbdslam {
namespace {

class KeyframePolicyTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto keyframe = std::make_unique<Keyframe>();
    keyframe->id = 0;
    map_.addKeyframe(std::move(keyframe));
    // The distance and angle rules alone; the few-points rules have their own tests.
    options_.few_points = 0;
    options_.few_points_no_depth = 0;
    input_.tracking_good = true;
    input_.frames_since_keyframe = options_.min_frames_between_keyframes;
    input_.median_depth_m = 2.0;  // keyframe distance threshold 0.2 m
  }
  bool decide(const SE3& T_w_c) {
    input_.T_w_c = T_w_c;
    return shouldAddKeyframe(map_, input_, options_);
  }
  static SE3 translated(double x) { return SE3(Mat3::Identity(), Vec3(x, 0, 0)); }
  static SE3 rotated(double deg) { return SE3(expSO3(Vec3(0, deg * M_PI / 180.0, 0)), Vec3::Zero()); }

  Map map_;
  KeyframePolicyOptions options_;
  KeyframePolicyInput input_;
};

TEST_F(KeyframePolicyTest, DistanceRelativeToSceneDepth) {
  EXPECT_FALSE(decide(translated(0.15)));
  EXPECT_TRUE(decide(translated(0.25)));
  input_.median_depth_m = 4.0;  // now 0.4 m is needed
  EXPECT_FALSE(decide(translated(0.25)));
}

TEST_F(KeyframePolicyTest, Rotation) {
  EXPECT_FALSE(decide(rotated(10.0)));
  EXPECT_TRUE(decide(rotated(20.0)));
  options_.angle_deg = 25.0;
  EXPECT_FALSE(decide(rotated(20.0)));
}

TEST_F(KeyframePolicyTest, NeedsGoodTrackingAndEnoughFrames) {
  input_.frames_since_keyframe = options_.min_frames_between_keyframes - 1;
  EXPECT_FALSE(decide(translated(1.0)));
  input_.frames_since_keyframe = options_.min_frames_between_keyframes;
  input_.tracking_good = false;
  EXPECT_FALSE(decide(translated(1.0)));
  input_.tracking_good = true;
  EXPECT_TRUE(decide(translated(1.0)));
}

TEST_F(KeyframePolicyTest, AnyCoveringKeyframeSuppresses) {
  auto second = std::make_unique<Keyframe>();
  second->id = 1;
  second->T_w_c = translated(1.0);
  map_.addKeyframe(std::move(second));
  EXPECT_FALSE(decide(translated(0.9)));
  EXPECT_TRUE(decide(translated(0.5)));
}

TEST_F(KeyframePolicyTest, FewPointsFoundWithDepthGiveAKeyframeWhereverTheCameraIs) {
  options_.few_points = 60;
  options_.few_points_min_frames = 3;
  input_.frames_since_keyframe = 3;  // fewer than min_frames_between_keyframes
  input_.points_found = 59;
  input_.points_from_depth = true;
  EXPECT_TRUE(decide(translated(0.0)));  // on top of keyframe 0
  input_.points_found = 60;
  EXPECT_FALSE(decide(translated(0.0)));
  input_.points_found = 20;
  input_.points_from_depth = false;  // mono: a keyframe would bring no points at once
  EXPECT_FALSE(decide(translated(0.0)));
  input_.points_from_depth = true;
  input_.frames_since_keyframe = 2;
  EXPECT_FALSE(decide(translated(0.0)));
  input_.frames_since_keyframe = 3;
  input_.tracking_good = false;
  EXPECT_FALSE(decide(translated(0.0)));
  options_.few_points = 0;  // off
  input_.tracking_good = true;
  EXPECT_FALSE(decide(translated(0.0)));
}

// A plain wall: a keyframe could not bring the missing points, so the few-points rule waits
// for a view with corners; moving on still gives keyframes (their depth holds the pose).
TEST_F(KeyframePolicyTest, FewPointsRuleWaitsWhereTheFrameHasNoCorners) {
  options_.few_points = 60;
  options_.few_points_min_frames = 3;
  input_.frames_since_keyframe = 3;
  input_.points_found = 5;
  input_.points_from_depth = true;
  input_.corners = 59;
  EXPECT_FALSE(decide(translated(0.0)));
  input_.corners = 60;
  EXPECT_TRUE(decide(translated(0.0)));
  input_.corners = 0;
  input_.frames_since_keyframe = options_.min_frames_between_keyframes;
  EXPECT_TRUE(decide(translated(0.3)));  // beyond 0.1 x 2 m from every keyframe
}

TEST_F(KeyframePolicyTest, FewPointsFoundWithoutDepthHaveTheirOwnThresholdAndWait) {
  options_.few_points = 60;
  options_.few_points_min_frames = 3;
  options_.few_points_no_depth = 40;
  options_.few_points_no_depth_min_frames = 5;
  input_.points_from_depth = false;  // mono: the mapper's epipolar search brings the points
  input_.points_found = 39;
  input_.frames_since_keyframe = 4;  // enough with depth, not without
  EXPECT_FALSE(decide(translated(0.0)));
  input_.frames_since_keyframe = 5;
  EXPECT_TRUE(decide(translated(0.0)));
  input_.points_found = 40;  // below the depth threshold, not below the mono one
  EXPECT_FALSE(decide(translated(0.0)));
  input_.points_found = 39;
  input_.tracking_good = false;
  EXPECT_FALSE(decide(translated(0.0)));
  input_.tracking_good = true;
  options_.few_points_no_depth = 0;  // off
  EXPECT_FALSE(decide(translated(0.0)));
}

// Points that thin out to a far plane (a hall's walls beyond the depth range): plenty are
// found, but the pose's sigma grows; a keyframe brings near points from depth before the
// pose is lost, but not for one uncertain frame, not in mono, not without corners, and not
// where points are scarce.
TEST_F(KeyframePolicyTest, AnUncertainPoseForSomeFramesGivesAKeyframeWhereverTheCameraIs) {
  options_.uncertain_pose_sigma_m = 0.015;
  options_.uncertain_pose_frames = 3;
  options_.few_points = 60;  // also the corners a keyframe needs to be worth making
  input_.frames_since_keyframe = 3;  // fewer than min_frames_between_keyframes
  input_.points_found = 150;
  input_.points_from_depth = true;
  input_.uncertain_frames = 3;
  EXPECT_TRUE(decide(translated(0.0)));  // on top of keyframe 0
  input_.uncertain_frames = 2;
  EXPECT_FALSE(decide(translated(0.0)));
  input_.uncertain_frames = 3;
  input_.points_from_depth = false;
  EXPECT_FALSE(decide(translated(0.0)));
  input_.points_from_depth = true;
  input_.corners = 10;  // a plain view: a keyframe brings nothing
  EXPECT_FALSE(decide(translated(0.0)));
  input_.corners = -1;
  input_.tracking_good = false;
  EXPECT_FALSE(decide(translated(0.0)));
  input_.tracking_good = true;
  // Points scarce: the sigma grows because they are few, and the few-points rule decides
  // alone (it waits few_points_min_frames, 3, since the last keyframe).
  input_.points_found = 40;
  input_.frames_since_keyframe = 2;
  EXPECT_FALSE(decide(translated(0.0)));
  input_.frames_since_keyframe = 3;
  EXPECT_TRUE(decide(translated(0.0)));
  input_.points_found = 150;
  options_.uncertain_pose_sigma_m = 0.0;  // off
  EXPECT_FALSE(decide(translated(0.0)));
}

}  // namespace
}  // namespace rgbdslam
