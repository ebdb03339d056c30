#include "common/lcm_conversions.h"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>

#include "rgbdslam/image/corners.h"
#include "rgbdslam/image/pyramid.h"
#include "rgbdslam/model/noise_model.h"
#include "rgbdslam/synth/scene.h"
#include "sample_messages.h"

namespace rgbdslam {
namespace {

using test::encode;

RgbdFrame makeFrame() { return test::sampleFrame(); }

TEST(LcmConversions, FrameRoundTripIsExactForRawAndZlib) {
  const RgbdFrame frame = makeFrame();
  for (bool zlib : {false, true}) {
    FrameEncoding encoding;
    encoding.zlib_depth = zlib;
    const auto bytes = encode(toLcm(frame, encoding));
    auto msg = decodeMessage<rgbdslam::rgbd_frame_t>(bytes.data(), bytes.size());
    ASSERT_TRUE(msg) << msg.error();
    auto back = fromLcm(*msg);
    ASSERT_TRUE(back) << back.error();
    EXPECT_EQ(back->utime, frame.utime);
    EXPECT_EQ(back->seq, frame.seq);
    EXPECT_EQ(back->camera_name, "tum_fr3");
    EXPECT_EQ(cv::norm(back->colour, frame.colour, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(back->depth, frame.depth, cv::NORM_INF), 0.0);
  }
}

// rgbd-tracker decodes every frame into the buffers of the one before (decodeFrame). The
// second frame must be its own whole: a buffer nothing else holds is reused, one that a
// keyframe still holds is left to it, and arrays liblcm leaves as they were when their count
// is 0 (a frame without colour after one with) are not read as the new frame's.
TEST(LcmConversions, FramesDecodedIntoTheBuffersOfTheOneBefore) {
  const RgbdFrame first = makeFrame();
  RgbdFrame second = makeFrame();
  second.seq = first.seq + 1;
  second.colour = first.colour.clone() + cv::Scalar(7, 7, 7);
  second.depth = first.depth.clone() + 11;
  rgbdslam::rgbd_frame_t msg;
  RgbdFrame frame;
  const auto first_bytes = encode(toLcm(first, FrameEncoding{}));  // raw colour, zlib depth
  FrameEncoding raw;
  raw.zlib_depth = false;
  const auto second_bytes = encode(toLcm(second, raw));
  ASSERT_TRUE(decodeFrame(first_bytes.data(), first_bytes.size(), &msg, &frame));
  const uchar* colour_buffer = frame.colour.data;
  const cv::Mat held_depth = frame.depth;  // as a keyframe made from the frame holds it
  ASSERT_TRUE(decodeFrame(second_bytes.data(), second_bytes.size(), &msg, &frame));
  EXPECT_EQ(frame.seq, second.seq);
  EXPECT_EQ(frame.colour.data, colour_buffer) << "nothing else held the colour: its buffer is reused";
  EXPECT_EQ(cv::norm(frame.colour, second.colour, cv::NORM_INF), 0.0);
  EXPECT_NE(frame.depth.data, held_depth.data) << "the held depth got a buffer of its own";
  EXPECT_EQ(cv::norm(frame.depth, second.depth, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(held_depth, first.depth, cv::NORM_INF), 0.0) << "the held depth is still the first frame's";

  RgbdFrame depth_only = second;
  depth_only.colour.release();
  const auto third_bytes = encode(toLcm(depth_only, raw));
  ASSERT_TRUE(decodeFrame(third_bytes.data(), third_bytes.size(), &msg, &frame));
  EXPECT_TRUE(frame.colour.empty()) << "the frame before's colour is not this frame's";
  EXPECT_EQ(cv::norm(frame.depth, second.depth, cv::NORM_INF), 0.0);

  const auto bad = encode(toLcm(first, FrameEncoding{}));
  EXPECT_FALSE(decodeFrame(bad.data(), bad.size() - 1, &msg, &frame)) << "a truncated frame is an error";
}

TEST(LcmConversions, JpegColourDecodesToTheRightSize) {
  FrameEncoding encoding;
  encoding.jpeg_colour = true;
  auto back = fromLcm(toLcm(makeFrame(), encoding));
  ASSERT_TRUE(back) << back.error();
  EXPECT_EQ(back->colour.size(), cv::Size(64, 48));
}

TEST(LcmConversions, FrameWithLyingSizesIsRejected) {
  rgbdslam::rgbd_frame_t msg = toLcm(makeFrame(), FrameEncoding{});
  msg.width = 65;
  EXPECT_FALSE(fromLcm(msg));
  msg = toLcm(makeFrame(), FrameEncoding{false, 90, false, 1});
  msg.depth.resize(100);
  msg.depth_size = 100;
  EXPECT_FALSE(fromLcm(msg));
  msg = toLcm(makeFrame(), FrameEncoding{});
  msg.depth_scale = 0;
  EXPECT_FALSE(fromLcm(msg));
  msg = toLcm(makeFrame(), FrameEncoding{});
  msg.colour_format = 17;
  EXPECT_FALSE(fromLcm(msg));
  msg.width = -5;
  EXPECT_FALSE(fromLcm(msg));
}

// Review finding: frames shared the keyframes' depth decoder, so a frame could carry an
// inverse-depth stream of a huge declared size in a few kB. A frame's depth is raw or zlib.
TEST(LcmConversions, FrameWithAKeyframeDepthFormatIsRejected) {
  KeyframeData keyframe;
  keyframe.grey = cv::Mat(48, 64, CV_8UC1, cv::Scalar(90));
  keyframe.depth = cv::Mat(48, 64, CV_16UC1, cv::Scalar(5000));
  KeyframeEncoding encoding{true, 80, 1};
  encoding.inverse_depth_step = 1e-3;
  const rgbdslam::keyframe_t kf = toLcm(keyframe, encoding);
  rgbdslam::rgbd_frame_t msg = toLcm(makeFrame(), FrameEncoding{});
  msg.depth_format = kf.depth_format;
  msg.depth = kf.depth;
  msg.depth_size = kf.depth_size;
  auto back = fromLcm(msg);
  ASSERT_FALSE(back);
  EXPECT_NE(back.error().find("not a frame's"), std::string::npos) << back.error();
}

TEST(LcmConversions, TruncatedOversizedAndWrongTypeMessagesAreRejected) {
  const auto bytes = encode(toLcm(makeFrame(), FrameEncoding{}));
  for (size_t cut : {size_t{0}, size_t{4}, size_t{20}, bytes.size() / 2, bytes.size() - 1}) {
    EXPECT_FALSE(decodeMessage<rgbdslam::rgbd_frame_t>(bytes.data(), cut)) << cut;
  }
  std::vector<uint8_t> longer = bytes;
  longer.resize(bytes.size() + 10, 0);
  auto oversized = decodeMessage<rgbdslam::rgbd_frame_t>(longer.data(), longer.size());
  ASSERT_FALSE(oversized);
  EXPECT_NE(oversized.error().find("10 bytes beyond"), std::string::npos);
  EXPECT_FALSE(decodeMessage<rgbdslam::pose_t>(bytes.data(), bytes.size()));
}

TEST(LcmConversions, NegativeArraySizeIsRejectedWithoutThrowing) {
  rgbdslam::status_t status;
  status.component = "x";
  status.state = "y";
  status.num_counters = 0;
  status.num_timings = 0;
  auto bytes = encode(status);
  // Layout: hash(8) utime(8) component(4+2) state(4+2) num_counters(4): make it -1.
  const size_t offset = 8 + 8 + 6 + 6;
  const uint8_t minus_one[4] = {0xff, 0xff, 0xff, 0xff};
  std::memcpy(bytes.data() + offset, minus_one, 4);
  EXPECT_FALSE(decodeMessage<rgbdslam::status_t>(bytes.data(), bytes.size()));
}

TEST(LcmConversions, PoseRoundTrip) {
  PoseEstimate pose = test::samplePose();
  pose.state = TrackingState::kDodgy;
  auto back = fromLcm(toLcm(pose, 1));
  ASSERT_TRUE(back) << back.error();
  EXPECT_EQ(back->pose.state, TrackingState::kDodgy);
  EXPECT_EQ(back->pose.points_tracked, 150);
  EXPECT_FLOAT_EQ(back->pose.latency_ms, 3.25);
  EXPECT_LT((back->pose.T_w_c.inverse() * pose.T_w_c).log().norm(), 1e-12);
  EXPECT_LT((back->pose.map_T_w_c.inverse() * pose.map_T_w_c).log().norm(), 1e-12);
  EXPECT_GT((back->pose.map_T_w_c.inverse() * back->pose.T_w_c).log().norm(), 0.1);  // not the published one
  EXPECT_EQ(back->pose.part, 42);
}

TEST(LcmConversions, PoseWithBadQuaternionOrStateIsRejected) {
  rgbdslam::pose_t msg = toLcm(PoseEstimate{}, 1);
  msg.orientation[0] = 2.0;
  EXPECT_FALSE(fromLcm(msg));
  msg = toLcm(PoseEstimate{}, 1);
  msg.position[1] = std::nan("");
  EXPECT_FALSE(fromLcm(msg));
  msg = toLcm(PoseEstimate{}, 1);
  msg.state = 9;
  EXPECT_FALSE(fromLcm(msg));
  // The map pose is checked as the published one is, and the part's id.
  msg = toLcm(PoseEstimate{}, 1);
  msg.map_orientation[2] = 0.5;
  auto bad = fromLcm(msg);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().find("map pose: orientation is not a unit quaternion"), std::string::npos) << bad.error();
  msg = toLcm(PoseEstimate{}, 1);
  msg.map_position[0] = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(fromLcm(msg));
  msg = toLcm(PoseEstimate{}, 1);
  msg.map_position[2] = 1e9;  // beyond the world bound
  EXPECT_FALSE(fromLcm(msg));
  msg = toLcm(PoseEstimate{}, 1);
  msg.part = -3;
  bad = fromLcm(msg);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().find("part has a negative id"), std::string::npos) << bad.error();
}

TEST(LcmConversions, KeyframeRoundTrip) {
  const KeyframeData keyframe = test::sampleKeyframe();
  const auto bytes = encode(toLcm(keyframe));
  auto msg = decodeMessage<rgbdslam::keyframe_t>(bytes.data(), bytes.size());
  ASSERT_TRUE(msg) << msg.error();
  auto back = fromLcm(*msg);
  ASSERT_TRUE(back) << back.error();
  EXPECT_EQ(back->id, 3);
  EXPECT_EQ(back->map_id, 1234);
  EXPECT_EQ(cv::norm(back->grey, keyframe.grey, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(back->depth, keyframe.depth, cv::NORM_INF), 0.0);
  ASSERT_EQ(back->measurements.size(), 1u);
  EXPECT_EQ(back->measurements[0].point_id, 17);
  EXPECT_DOUBLE_EQ(back->measurements[0].uv.x(), 10.25);
  EXPECT_EQ(back->measurements[0].level, 1);
  ASSERT_EQ(back->new_points.size(), 1u);
  EXPECT_EQ(back->new_points[0].id, 3 * kPointsPerKeyframe + 1);
  EXPECT_EQ(back->new_points[0].p_w, Vec3(1, 2, 3));
  EXPECT_FALSE(back->new_part);
  KeyframeData starting = keyframe;  // the first keyframe of a new part of the map
  starting.new_part = true;
  auto part = fromLcm(*decodeMessage<rgbdslam::keyframe_t>(encode(toLcm(starting)).data(), encode(toLcm(starting)).size()));
  ASSERT_TRUE(part) << part.error();
  EXPECT_TRUE(part->new_part);
}

// The anchor keyframe (mapper.h, "Anchor") and its pose come through; an anchor that is not an
// older keyframe, or a pose that is not one, is refused with the field named.
TEST(LcmConversions, KeyframeAnchorRoundTripAndHostileAnchors) {
  KeyframeData keyframe = test::sampleKeyframe();
  EXPECT_EQ(fromLcm(toLcm(keyframe))->anchor, -1);
  keyframe.anchor = 2;
  keyframe.T_w_anchor = SE3(Mat3(Eigen::AngleAxisd(0.3, Vec3::UnitZ()).toRotationMatrix()), Vec3(4, -5, 6));
  const auto bytes = encode(toLcm(keyframe));
  auto back = fromLcm(*decodeMessage<rgbdslam::keyframe_t>(bytes.data(), bytes.size()));
  ASSERT_TRUE(back) << back.error();
  EXPECT_EQ(back->anchor, 2);
  EXPECT_LT((back->T_w_anchor.inverse() * keyframe.T_w_anchor).log().norm(), 1e-12);
  rgbdslam::keyframe_t msg = toLcm(keyframe);
  for (int64_t id : {int64_t{3}, int64_t{4}, int64_t{-2}, std::numeric_limits<int64_t>::min()}) {
    msg.anchor_keyframe_id = id;
    auto bad = fromLcm(msg);
    ASSERT_FALSE(bad) << id;
    EXPECT_NE(bad.error().find("anchor"), std::string::npos) << bad.error();
  }
  msg = toLcm(keyframe);
  msg.anchor_position[0] = std::nan("");
  EXPECT_FALSE(fromLcm(msg));
  msg = toLcm(keyframe);
  msg.anchor_orientation[0] = 2.0;
  EXPECT_FALSE(fromLcm(msg));
}

// A keyframe's part is named by the keyframe that started it: never a later one, never < 0.
TEST(LcmConversions, MapWithAKeyframeInALaterPartIsRejected) {
  MapUpdate update = test::sampleMapUpdate();
  update.keyframes[0].part = update.keyframes[0].id;  // it started its part: fine
  auto back = fromLcm(toLcm(update));
  ASSERT_TRUE(back) << back.error();
  EXPECT_EQ(back->keyframes[0].part, update.keyframes[0].id);
  for (const KeyframeId part : {update.keyframes[0].id + 1, KeyframeId{-1}}) {
    update.keyframes[0].part = part;
    const auto refused = fromLcm(toLcm(update));
    ASSERT_FALSE(refused) << "part " << part;
    EXPECT_NE(refused.error().find("part"), std::string::npos) << refused.error();
  }
}

TEST(LcmConversions, MapRoundTrip) {
  const MapUpdate update = test::sampleMapUpdate();
  auto back = fromLcm(toLcm(update));
  ASSERT_TRUE(back) << back.error();
  EXPECT_EQ(back->version, 8);
  EXPECT_TRUE(back->is_snapshot);
  EXPECT_EQ(back->acked_below, update.acked_below);
  EXPECT_EQ(back->removed_points, update.removed_points);
  EXPECT_EQ(back->removed_keyframes, update.removed_keyframes);
  ASSERT_EQ(back->points.size(), 1u);
  EXPECT_EQ(back->points[0].uv, Eigen::Vector2d(100, 200));
  ASSERT_EQ(back->moved_points.size(), 1u);
  EXPECT_EQ(back->moved_points[0].id, 6);
  EXPECT_LT((back->moved_points[0].p_w - Vec3(100.0, -2.5, 1.25)).norm(), 1e-5);  // float
  EXPECT_LT((back->keyframes[0].T_w_c.inverse() * update.keyframes[0].T_w_c).log().norm(), 1e-12);
}

TEST(LcmConversions, CompactKeyframeEncodingKeepsHalfTheDepthPixels) {
  KeyframeData keyframe;
  keyframe.id = 1;
  keyframe.grey = cv::Mat(48, 64, CV_8UC1);
  cv::randu(keyframe.grey, 0, 255);
  keyframe.depth = cv::Mat(48, 64, CV_16UC1);
  cv::randu(keyframe.depth, 1000, 20000);
  const auto bytes = encode(toLcm(keyframe, KeyframeEncoding{true, 80, 2}));
  auto msg = decodeMessage<rgbdslam::keyframe_t>(bytes.data(), bytes.size());
  ASSERT_TRUE(msg) << msg.error();
  EXPECT_EQ(int{msg->grey_format}, int{rgbdslam::keyframe_t::GREY_JPEG});
  EXPECT_EQ(int{msg->depth_format}, int{rgbdslam::keyframe_t::DEPTH_ZLIB_U16_HALF});
  auto back = fromLcm(*msg);
  ASSERT_TRUE(back) << back.error();
  ASSERT_EQ(back->depth.size(), keyframe.depth.size());
  for (int v = 0; v < 48; ++v) {
    for (int u = 0; u < 64; ++u) {  // each pixel takes the value of its 2x2 block's centre
      ASSERT_EQ(back->depth.at<uint16_t>(v, u), keyframe.depth.at<uint16_t>(v - v % 2 + 1, u - u % 2 + 1));
    }
  }
  EXPECT_EQ(back->grey.size(), keyframe.grey.size());
}

TEST(LcmConversions, KeyframeDepthAsInverseDepthAtEveryFourthPixel) {
  KeyframeData keyframe;
  keyframe.id = 1;
  keyframe.grey = cv::Mat(48, 64, CV_8UC1, cv::Scalar(90));
  keyframe.depth = cv::Mat(48, 64, CV_16UC1);
  cv::randu(keyframe.depth, 2500, 20000);  // 0.5-4 m at 5000 units per metre
  keyframe.depth.at<uint16_t>(2, 2) = 0;
  keyframe.depth_scale = 5000;
  KeyframeEncoding encoding{true, 80, 4};
  encoding.inverse_depth_step = 1e-3;  // [1/m]
  const auto bytes = encode(toLcm(keyframe, encoding));
  auto msg = decodeMessage<rgbdslam::keyframe_t>(bytes.data(), bytes.size());
  ASSERT_TRUE(msg) << msg.error();
  EXPECT_EQ(int{msg->depth_format}, int{rgbdslam::keyframe_t::DEPTH_INVERSE_ZSTD_QUARTER});
  auto back = fromLcm(*msg);
  ASSERT_TRUE(back) << back.error();
  ASSERT_EQ(back->depth.size(), keyframe.depth.size());
  for (int v = 0; v < 48; ++v) {
    for (int u = 0; u < 64; ++u) {  // each pixel takes its 4x4 block's centre, within half a step
      const double raw = keyframe.depth.at<uint16_t>(v - v % 4 + 2, u - u % 4 + 2), out = back->depth.at<uint16_t>(v, u);
      ASSERT_EQ(raw == 0, out == 0);
      if (raw > 0) {
        ASSERT_LE(std::abs(5000 / out - 5000 / raw), 0.5e-3 + 0.5 * 5000 / (out * out)) << u << "," << v;
      }
    }
  }
}

// Depth only near corners (the link budget's second rung): wherever the mapper can read
// depth, at a corner it detects in the decoded JPEG and up to a pixel of the corner's level
// away, the reading is the one the whole depth gives; and it costs far fewer bytes.
TEST(LcmConversions, KeyframeDepthNearCornersKeepsWhatTheMapperReads) {
  const SyntheticScene scene(*parseSyntheticSpec("corridor,frames=60"));
  const RgbdFrame frame = scene.render(40);  // the corridor's plain walls
  KeyframeData keyframe;
  keyframe.id = 1;
  keyframe.grey = frame.grey();
  keyframe.depth = frame.depth;
  keyframe.depth_scale = frame.depth_scale;
  KeyframeEncoding whole{true, 45, 4};
  whole.inverse_depth_step = 0.25 * NoiseModel{}.depth_sigma_a;
  KeyframeEncoding near = whole;
  near.depth_near_corners = true;
  const rgbdslam::keyframe_t whole_msg = toLcm(keyframe, whole), near_msg = toLcm(keyframe, near);
  EXPECT_EQ(near_msg.grey, whole_msg.grey);
  EXPECT_LT(near_msg.depth.size(), whole_msg.depth.size() * 7 / 10);  // 4.1 of 6.6 kB
  auto a = fromLcm(whole_msg);
  auto b = fromLcm(near_msg);
  ASSERT_TRUE(a && b);
  EXPECT_LT(cv::countNonZero(b->depth), cv::countNonZero(a->depth) * 7 / 10);
  std::vector<LevelCorners> corners;
  ASSERT_TRUE(b->grey_lossy);  // the mapper detects its corners below the thresholds
  detectPyramidCorners(buildPyramid(b->grey), lossyCornerOptions(CornerOptions{}), false, &corners);
  long reads = 0, same = 0;
  for (int level = 0; level < static_cast<int>(corners.size()); ++level) {
    const int s = 1 << level;
    for (const cv::Point2i& c : corners[level].all) {
      for (int dv : {-s, 0, s}) {
        for (int du : {-s, 0, s}) {
          const int u = std::clamp((c.x * s) + s / 2 + du, 0, b->depth.cols - 1);
          const int v = std::clamp((c.y * s) + s / 2 + dv, 0, b->depth.rows - 1);
          if (a->depth.at<uint16_t>(v, u) == 0) continue;
          ++reads;
          same += a->depth.at<uint16_t>(v, u) == b->depth.at<uint16_t>(v, u) ? 1 : 0;
        }
      }
    }
  }
  ASSERT_GT(reads, 1000);
  EXPECT_GE(same, reads * 99 / 100) << same << " of " << reads;  // 18854 of 18982
}

TEST(LcmConversions, StatusRoundTrip) {
  ComponentStatus status{5, "rgbd-tracker", "tracking", {{"frames", 10}, {"bad_messages", 1}}, {{"track_ms", 3.5}}};
  auto back = fromLcm(toLcm(status));
  ASSERT_TRUE(back) << back.error();
  EXPECT_EQ(back->component, "rgbd-tracker");
  EXPECT_EQ(back->counters, status.counters);
  EXPECT_EQ(back->timings_ms, status.timings_ms);
}

}  // namespace
}  // namespace rgbdslam
