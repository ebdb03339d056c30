// The wire check runs before liblcm's decoder: counts and lengths that lie about the bytes
// present, or exceed the protocol's limits, are rejected with the field's name, fast and
// without allocating (issue 13: a 110-byte map crashed the tracker, a 118-byte keyframe
// cost 2.1 GB and 1.4 s).
#include "common/wire_check.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <limits>

#include "common/lcm_conversions.h"
#include "common/protocol_limits.h"
#include "sample_messages.h"

namespace rgbdslam {
namespace {

void putBigEndian32(std::vector<uint8_t>& bytes, size_t offset, int32_t value) {
  for (int i = 0; i < 4; ++i) bytes[offset + i] = static_cast<uint8_t>(static_cast<uint32_t>(value) >> (24 - 8 * i));
}

// Runs decodeMessage<T> and expects a quick rejection whose message names 'field'.
template <typename T>
void expectRejected(const std::vector<uint8_t>& bytes, const std::string& field) {
  const auto start = std::chrono::steady_clock::now();
  auto msg = decodeMessage<T>(bytes.data(), bytes.size());
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_FALSE(msg) << field;
  EXPECT_NE(msg.error().find(field), std::string::npos) << msg.error();
  EXPECT_LT(seconds, 0.05) << "rejecting took " << seconds << " s: something was allocated first";
}

TEST(WireCheck, EveryTypeAcceptsItsOwnEncoding) {
  const auto frame = test::encode(toLcm(test::sampleFrame(), FrameEncoding{}));
  EXPECT_TRUE(checkWire<rgbdslam::rgbd_frame_t>(frame.data(), frame.size()));
  const auto keyframe = test::encode(toLcm(test::sampleKeyframe()));
  EXPECT_TRUE(checkWire<rgbdslam::keyframe_t>(keyframe.data(), keyframe.size()));
  const auto map = test::encode(toLcm(test::sampleMapUpdate()));
  EXPECT_TRUE(checkWire<rgbdslam::map_t>(map.data(), map.size()));
  const auto status = test::encode(toLcm(test::sampleStatus()));
  EXPECT_TRUE(checkWire<rgbdslam::status_t>(status.data(), status.size()));
  const auto pose = test::encode(toLcm(test::samplePose(), 7));
  Status s = checkWire<rgbdslam::pose_t>(pose.data(), pose.size());
  EXPECT_TRUE(s) << s.error();
}

// Issue 13, red team: SLAM_MAP with an array count >= 2^28 in 110 bytes; liblcm computed the
// array's byte size in 32-bit int and read past the buffer (SIGSEGV in rgbd-tracker). The
// message then carried a list of acknowledged keyframes (now one number, acked_below).
TEST(WireCheck, MapWithHugeArrayCountIsRejected) {
  MapUpdate update;
  update.map_id = 1;
  update.version = 2;
  update.acked_below = 9;
  update.keyframes = {{0, SE3()}, {1, SE3()}};
  auto bytes = test::encode(toLcm(update));
  // fingerprint, utime, map_id, version, is_snapshot, acked_below
  const size_t num_keyframes = 8 + 8 + 8 + 8 + 1 + 8;
  for (int32_t count : {1 << 28, (1 << 29) + 1, std::numeric_limits<int32_t>::max(), -1}) {
    putBigEndian32(bytes, num_keyframes, count);
    expectRejected<rgbdslam::map_t>(bytes, "num_keyframes");
  }
  update.keyframes.clear();
  update.removed_points = {1, 2, 3};
  bytes = test::encode(toLcm(update));
  putBigEndian32(bytes, bytes.size() - 4 - 3 * 8 - 4, 1 << 28);  // num_removed (then no removed keyframes)
  expectRejected<rgbdslam::map_t>(bytes, "num_removed");
  update.removed_keyframes = {4, 5};
  bytes = test::encode(toLcm(update));
  putBigEndian32(bytes, bytes.size() - 2 * 8 - 4, 1 << 28);  // num_removed_keyframes
  expectRejected<rgbdslam::map_t>(bytes, "num_removed_keyframes");
}

// Counts within the limits but beyond the bytes present: nothing is allocated.
TEST(WireCheck, CountsNotBackedByBytesAreRejectedBeforeAllocation) {
  KeyframeData keyframe;
  keyframe.map_id = 1;
  keyframe.id = 0;
  keyframe.grey = cv::Mat(4, 4, CV_8UC1, cv::Scalar(10));
  auto bytes = test::encode(toLcm(keyframe));
  // The last two int32 are num_measurements and num_new_points, then the byte of new_part
  // and the anchor (an int64 and 7 doubles).
  const size_t tail = 1 + 8 + 7 * 8;
  putBigEndian32(bytes, bytes.size() - tail - 8, limits::kMaxKeyframePoints);
  expectRejected<rgbdslam::keyframe_t>(bytes, "measurements");
  putBigEndian32(bytes, bytes.size() - tail - 8, std::numeric_limits<int32_t>::max());
  expectRejected<rgbdslam::keyframe_t>(bytes, "num_measurements");
  putBigEndian32(bytes, bytes.size() - tail - 8, 0);
  putBigEndian32(bytes, bytes.size() - tail - 4, 100000000);
  expectRejected<rgbdslam::keyframe_t>(bytes, "num_new_points");
}

// A 54-byte status claiming 10^8 counters cost 1.6 GB before it was rejected.
TEST(WireCheck, StatusWithHugeCountsOrBadStringsIsRejected) {
  ComponentStatus status;
  status.component = "c";
  status.state = "s";
  auto bytes = test::encode(toLcm(status));
  const size_t num_counters = 8 + 8 + 4 + 2 + 4 + 2;
  putBigEndian32(bytes, num_counters, 100000000);
  expectRejected<rgbdslam::status_t>(bytes, "num_counters");
  putBigEndian32(bytes, num_counters, 1000);
  expectRejected<rgbdslam::status_t>(bytes, "counter_names");
  bytes = test::encode(toLcm(status));
  putBigEndian32(bytes, 16, 0);  // component's length 0: liblcm would assign -1 bytes
  expectRejected<rgbdslam::status_t>(bytes, "component");
  bytes = test::encode(toLcm(status));
  bytes[16 + 4 + 1] = 'x';  // the component's NUL
  expectRejected<rgbdslam::status_t>(bytes, "NUL");
}

TEST(WireCheck, ImageSizesBeyondTheLimitOrTheBytesAreRejected) {
  auto bytes = test::encode(toLcm(test::sampleFrame(), FrameEncoding{}));
  const size_t colour_size = 8 + 8 + 8 + 4 + 4 + 1;
  putBigEndian32(bytes, colour_size, static_cast<int32_t>(limits::kMaxImageBytes + 1));
  expectRejected<rgbdslam::rgbd_frame_t>(bytes, "colour_size");
  putBigEndian32(bytes, colour_size, static_cast<int32_t>(limits::kMaxImageBytes));
  expectRejected<rgbdslam::rgbd_frame_t>(bytes, "colour");
}

TEST(WireCheck, TruncationTrailingBytesAndAnotherTypeAreNamed) {
  const auto pose = test::encode(toLcm(test::samplePose(), 1));
  auto cut = pose;
  cut.resize(pose.size() - 1);
  expectRejected<rgbdslam::pose_t>(cut, "truncated");
  auto longer = pose;
  longer.push_back(0);
  expectRejected<rgbdslam::pose_t>(longer, "1 bytes beyond");
  expectRejected<rgbdslam::status_t>(pose, "another type");
}

}  // namespace
}  // namespace rgbdslam
