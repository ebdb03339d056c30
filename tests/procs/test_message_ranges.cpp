// Every field of a decoded message is held to a range by fromLcm (protocol_limits.h), with an
// error naming the field (issue 13: a pyramid level of 4 overflowed the mapper's pyramid, a
// keyframe at 1e155 m aborted the mapper inside Ceres).
#include <gtest/gtest.h>

#include <cmath>

#include "common/lcm_conversions.h"
#include "common/protocol_limits.h"
#include "sample_messages.h"

namespace rgbdslam {
namespace {

template <typename T>
void expectRejected(const T& msg, const std::string& words) {
  auto converted = fromLcm(msg);
  ASSERT_FALSE(converted) << "accepted; expected an error with '" << words << "'";
  EXPECT_NE(converted.error().find(words), std::string::npos) << converted.error();
}

TEST(MessageRanges, SamplesPassEveryCheck) {
  EXPECT_TRUE(fromLcm(toLcm(test::sampleKeyframe())));
  EXPECT_TRUE(fromLcm(toLcm(test::sampleMapUpdate())));
  EXPECT_TRUE(fromLcm(toLcm(test::sampleStatus())));
  EXPECT_TRUE(fromLcm(toLcm(test::samplePose(), 5)));
  EXPECT_TRUE(fromLcm(toLcm(test::sampleFrame(), FrameEncoding{})));
}

TEST(MessageRanges, KeyframeLevelsMustIndexThePyramid) {
  rgbdslam::keyframe_t msg = toLcm(test::sampleKeyframe());
  msg.measurements[0].level = limits::kMaxLevels;  // 4: past levels 0..3
  expectRejected(msg, "pyramid level 4");
  msg = toLcm(test::sampleKeyframe());
  msg.new_points[0].level = 127;
  expectRejected(msg, "pyramid level 127");
  msg = toLcm(test::sampleKeyframe());
  msg.measurements[0].level = -1;
  expectRejected(msg, "pyramid level -1");
}

TEST(MessageRanges, KeyframePositionsMustLieInTheWorld) {
  rgbdslam::keyframe_t msg = toLcm(test::sampleKeyframe());
  msg.position[0] = 1e155;  // finite, but aborted Ceres in the mapper
  expectRejected(msg, "world bound");
  msg = toLcm(test::sampleKeyframe());
  msg.new_points[0].position[2] = 2e4f;
  expectRejected(msg, "world bound");
  msg = toLcm(test::sampleKeyframe());
  msg.new_points[0].position[1] = std::nanf("");
  expectRejected(msg, "not finite");
}

TEST(MessageRanges, KeyframePixelsDepthsAndIdsAreChecked) {
  rgbdslam::keyframe_t msg = toLcm(test::sampleKeyframe());
  msg.measurements[0].u = 64.0f;  // the image is 64 wide: columns up to 63.5
  expectRejected(msg, "outside the 64x48 image");
  msg = toLcm(test::sampleKeyframe());
  msg.new_points[0].v = -3.0f;
  expectRejected(msg, "outside the 64x48 image");
  msg = toLcm(test::sampleKeyframe());
  msg.measurements[0].depth = 1e6f;
  expectRejected(msg, "depth");
  msg = toLcm(test::sampleKeyframe());
  msg.measurements[0].point_id = -5;
  expectRejected(msg, "negative id");
  msg = toLcm(test::sampleKeyframe());
  msg.new_points[0].source_keyframe = 2;
  expectRejected(msg, "as its source");
  msg = toLcm(test::sampleKeyframe());
  msg.depth_scale = std::numeric_limits<float>::infinity();
  expectRejected(msg, "depth_scale");
  msg = toLcm(test::sampleKeyframe());
  msg.orientation[0] = 0.5;
  expectRejected(msg, "unit quaternion");
}

TEST(MessageRanges, CountsMustMatchTheArrays) {
  rgbdslam::keyframe_t keyframe = toLcm(test::sampleKeyframe());
  keyframe.num_measurements = 5;
  expectRejected(keyframe, "num_measurements is 5 but the array holds 1");
  rgbdslam::status_t status = toLcm(test::sampleStatus());
  status.num_counters = 1000;  // indexed the names past their end before
  expectRejected(status, "num_counters");
  rgbdslam::map_t map = toLcm(test::sampleMapUpdate());
  map.num_removed = -1;
  expectRejected(map, "num_removed");
  map = toLcm(test::sampleMapUpdate());
  map.num_removed_keyframes = 2;
  expectRejected(map, "num_removed_keyframes");
}

TEST(MessageRanges, MapContentsAreChecked) {
  rgbdslam::map_t msg = toLcm(test::sampleMapUpdate());
  msg.points[0].level = 4;
  expectRejected(msg, "pyramid level 4");
  msg = toLcm(test::sampleMapUpdate());
  msg.keyframes[0].position[1] = -1e155;
  expectRejected(msg, "world bound");
  msg = toLcm(test::sampleMapUpdate());
  msg.moved[0].position[0] = 3e30f;
  expectRejected(msg, "world bound");
  msg = toLcm(test::sampleMapUpdate());
  msg.acked_below = -7;
  expectRejected(msg, "negative id -7");
  msg = toLcm(test::sampleMapUpdate());
  msg.removed_points[0] = -1;
  expectRejected(msg, "negative id");
  msg = toLcm(test::sampleMapUpdate());
  msg.removed_keyframes[0] = -3;
  expectRejected(msg, "removed keyframe");
}

TEST(MessageRanges, PoseCarriesItsMapAndIsChecked) {
  auto back = fromLcm(toLcm(test::samplePose(), 4242));
  ASSERT_TRUE(back) << back.error();
  EXPECT_EQ(back->map_id, 4242);
  EXPECT_EQ(back->pose.seq, 7);
  rgbdslam::pose_t msg = toLcm(test::samplePose(), 1);
  msg.position[2] = 1e200;
  expectRejected(msg, "world bound");
  msg = toLcm(test::samplePose(), -3);
  expectRejected(msg, "negative id");
  msg = toLcm(test::samplePose(), 1);
  msg.quality = 2.0f;
  expectRejected(msg, "quality");
  msg = toLcm(test::samplePose(), 1);
  msg.latency_ms = std::nanf("");
  expectRejected(msg, "latency");
}

TEST(MessageRanges, FrameDepthScaleAndCountsAreChecked) {
  rgbdslam::rgbd_frame_t msg = toLcm(test::sampleFrame(), FrameEncoding{});
  msg.depth_scale = 1e30f;
  expectRejected(msg, "depth_scale");
  msg = toLcm(test::sampleFrame(), FrameEncoding{});
  msg.colour_size = 3;
  expectRejected(msg, "colour_size");
}

}  // namespace
}  // namespace rgbdslam
