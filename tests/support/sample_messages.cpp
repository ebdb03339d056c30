#include "sample_messages.h"

namespace rgbdslam::test {

RgbdFrame sampleFrame(int width, int height) {
  RgbdFrame frame;
  frame.utime = 1700000000123456;
  frame.seq = 42;
  frame.colour = cv::Mat(height, width, CV_8UC3);
  cv::randu(frame.colour, 0, 255);
  frame.depth = cv::Mat(height, width, CV_16UC1);
  cv::randu(frame.depth, 0, 20000);
  frame.depth_scale = 5000.0;
  frame.camera_name = "tum_fr3";
  return frame;
}

namespace {
SE3 somePose() {
  Vec6 xi;
  xi << 0.5, -1.0, 2.0, 0.1, -0.3, 0.2;
  return SE3::exp(xi);
}
}  // namespace

KeyframeData sampleKeyframe() {
  KeyframeData keyframe;
  keyframe.utime = 99;
  keyframe.map_id = 1234;
  keyframe.id = 3;
  keyframe.T_w_c = somePose();
  keyframe.grey = cv::Mat(48, 64, CV_8UC1);
  cv::randu(keyframe.grey, 0, 255);
  keyframe.depth = sampleFrame().depth;
  keyframe.measurements.push_back({17, Eigen::Vector2d(10.25, 20.5), 1, 1.5});
  keyframe.new_points.push_back({3 * kPointsPerKeyframe + 1, Vec3(1, 2, 3), 3, Eigen::Vector2d(5, 6), 2});
  return keyframe;
}

MapUpdate sampleMapUpdate() {
  MapUpdate update;
  update.map_id = 1234;
  update.version = 8;
  update.is_snapshot = true;
  update.acked_below = 3;
  update.keyframes.push_back({2, somePose()});
  update.points.push_back({5, Vec3(0.5, 0.25, 3), 1, Eigen::Vector2d(100, 200), 0});
  update.moved_points.push_back({6, Vec3(100.0, -2.5, 1.25)});
  update.removed_points = {9, 10};
  update.removed_keyframes = {1};
  return update;
}

ComponentStatus sampleStatus() {
  ComponentStatus status;
  status.utime = 5;
  status.component = "rgbd-tracker";
  status.state = "tracking";
  status.counters = {{"frames", 300}, {"bad_messages", 2}};
  status.timings_ms = {{"track_ms_median", 4.5}};
  return status;
}

PoseEstimate samplePose() {
  PoseEstimate pose;
  pose.utime = 123;
  pose.seq = 7;
  pose.T_w_c = somePose();
  pose.map_T_w_c = SE3::exp((Vec6() << 0.5, -0.25, 0.1, 0.02, 0.0, -0.03).finished()) * somePose();
  pose.part = 42;
  pose.state = TrackingState::kTracking;
  pose.points_tracked = 150;
  pose.quality = 0.5;
  pose.latency_ms = 3.25;
  return pose;
}

MapReceipt sampleReceipt() {
  MapReceipt receipt;
  receipt.utime = 1700000001000000;
  receipt.map_id = 1234;
  receipt.applied_version = 8;
  receipt.newest_version_seen = 9;
  receipt.keyframes_created = 6;
  receipt.keyframes_unacked = 3;
  receipt.keyframes_sendable_from = 2;
  return receipt;
}

namespace {
void putBigEndian(std::vector<uint8_t>& out, uint64_t value, int bytes) {
  for (int i = bytes - 1; i >= 0; --i) out.push_back(static_cast<uint8_t>(value >> (8 * i)));
}
}  // namespace

void appendLogEvent(std::vector<uint8_t>& log, int64_t number, const std::string& channel,
                    const std::vector<uint8_t>& data, int32_t claimed_length) {
  putBigEndian(log, 0xEDA1DA01, 4);
  putBigEndian(log, static_cast<uint64_t>(number), 8);
  putBigEndian(log, 1700000000000000 + static_cast<uint64_t>(number), 8);
  putBigEndian(log, channel.size(), 4);
  const int32_t length = claimed_length >= 0 ? claimed_length : static_cast<int32_t>(data.size());
  putBigEndian(log, static_cast<uint32_t>(length), 4);
  log.insert(log.end(), channel.begin(), channel.end());
  log.insert(log.end(), data.begin(), data.end());
}

}  // namespace rgbdslam::test
