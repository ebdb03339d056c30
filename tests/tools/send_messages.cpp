// send-messages (test tool): publishes test traffic on one channel.
//   --poses N [--rate HZ] [--map-id ID]  N valid pose_t messages (seq 0..N-1, a moving pose)
//   --bad truncated|oversized|wrongtype|garbage [--type pose|frame|keyframe|map]
//         one malformed message of that kind, made from a valid message of --type
//   --bad keyframe-foreign-map   a valid keyframe (id 3) of map 424242
//   --bad map-stale --map-id ID  a valid map snapshot of map ID with version 1 (the past)
//   --bad map-foreign-map        a valid map snapshot of map 424242, version 10^9
//   --bad frame-wrong-size       a valid 320x240 frame (the cameras are 640x480)
//   Hostile input (issue 13), each a small message that crashed or stalled a process before:
//   --bad map-huge-count         a ~110-byte map claiming 2^28 keyframe poses
//   --bad keyframe-huge-counts   a small keyframe claiming 10^8 measurements
//   --bad status-huge-counts     a 54-byte status claiming 10^8 counters
//   --bad keyframe-level-4       keyframe 0 of map --map-id whose points claim pyramid level 4
//   --bad keyframe-far           keyframe 0 of map --map-id at x = 1e155 m
// Used by the integration tests to drive pose-logger and the SLAM processes.
#include <chrono>
#include <cmath>
#include <iostream>
#include <thread>

#include "common/cli.h"
#include "common/lcm_conversions.h"
#include "common/process.h"

using namespace rgbdslam;

namespace {

std::vector<uint8_t> encodePose(int64_t seq, int64_t map_id) {
  PoseEstimate pose;
  pose.utime = 1700000000000000 + seq * 33333;
  pose.seq = seq;
  Vec6 xi;
  xi << 0.01 * seq, 0.002 * seq, -0.001 * seq, 0.001 * seq, 0.002 * seq, 0.0;
  pose.T_w_c = SE3::exp(xi);
  // The map pose 1 m along x from the published one (a correction not yet taken in), part 5.
  pose.map_T_w_c = SE3(pose.T_w_c.rotation(), pose.T_w_c.translation() + Vec3(1.0, 0.0, 0.0));
  pose.part = 5;
  pose.state = TrackingState::kTracking;
  pose.points_tracked = 100;
  pose.quality = 0.9;
  pose.latency_ms = 2.5;
  const rgbdslam::pose_t msg = toLcm(pose, map_id);
  std::vector<uint8_t> bytes(msg.getEncodedSize());
  msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

template <typename T>
std::vector<uint8_t> encode(const T& msg) {
  std::vector<uint8_t> bytes(msg.getEncodedSize());
  msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

RgbdFrame smallFrame(int width, int height) {
  RgbdFrame frame;
  frame.colour = cv::Mat(height, width, CV_8UC3, cv::Scalar(90, 120, 150));
  frame.depth = cv::Mat(height, width, CV_16UC1, cv::Scalar(5000));
  frame.depth_scale = 5000.0;
  frame.camera_name = "test";
  return frame;
}

std::vector<uint8_t> keyframeBytes(int64_t map_id) {
  KeyframeData keyframe;
  keyframe.map_id = map_id;
  keyframe.id = 3;
  keyframe.grey = cv::Mat(480, 640, CV_8UC1, cv::Scalar(100));
  return encode(toLcm(keyframe));
}

std::vector<uint8_t> mapBytes(int64_t map_id, int64_t version) {
  MapUpdate update;
  update.map_id = map_id;
  update.version = version;
  update.is_snapshot = true;
  return encode(toLcm(update));
}

void putBigEndian32(std::vector<uint8_t>& bytes, size_t offset, uint32_t value) {
  for (int i = 0; i < 4; ++i) bytes[offset + i] = static_cast<uint8_t>(value >> (24 - 8 * i));
}

// Keyframe 0 of 'map_id' with one measurement and one new point, then 'spoil'. Camera-sized
// (640x480, the synthetic camera's), textured and with depth 2 m everywhere, so that the
// mapper would take it in if it did not check the spoilt field: a smaller keyframe is
// refused for its size before any field is looked at.
std::vector<uint8_t> spoiledKeyframe(int64_t map_id, void (*spoil)(rgbdslam::keyframe_t&)) {
  KeyframeData keyframe;
  keyframe.map_id = map_id;
  keyframe.id = 0;
  keyframe.grey = cv::Mat(480, 640, CV_8UC1);
  cv::RNG rng(13);
  rng.fill(keyframe.grey, cv::RNG::UNIFORM, 0, 256);
  keyframe.depth = cv::Mat(480, 640, CV_16UC1, cv::Scalar(10000));
  keyframe.depth_scale = 5000.0;
  keyframe.measurements.push_back({5, Eigen::Vector2d(10, 10), 0, 1.5});
  keyframe.new_points.push_back({1, Vec3(0, 0, 2), 0, Eigen::Vector2d(20, 20), 0});
  rgbdslam::keyframe_t msg = toLcm(keyframe);
  spoil(msg);
  return encode(msg);
}

// Small messages whose counts or fields crashed or stalled a process before issue 13.
std::vector<uint8_t> hostileMessage(const std::string& kind, int64_t map_id) {
  if (kind == "map-huge-count") {
    MapUpdate update;
    update.map_id = map_id, update.version = 2, update.acked_below = 8;
    update.keyframes.resize(1);
    auto bytes = encode(toLcm(update));
    putBigEndian32(bytes, 8 + 8 + 8 + 8 + 1 + 8, 1u << 28);  // num_keyframes
    return bytes;
  }
  if (kind == "keyframe-huge-counts") {
    auto bytes = spoiledKeyframe(map_id, [](rgbdslam::keyframe_t& m) { m.measurements.clear(), m.new_points.clear(), m.num_measurements = m.num_new_points = 0; });
    // num_measurements, then num_new_points (4), new_part (1) and the anchor (8 + 7 * 8)
    putBigEndian32(bytes, bytes.size() - (4 + 4 + 1 + 8 + 7 * 8), 100000000);
    return bytes;
  }
  if (kind == "status-huge-counts") {
    rgbdslam::status_t status;
    status.component = "c", status.state = "s", status.num_counters = status.num_timings = 0;
    auto bytes = encode(status);
    putBigEndian32(bytes, 8 + 8 + 4 + 2 + 4 + 2, 100000000);  // num_counters
    return bytes;
  }
  if (kind == "keyframe-level-4") {
    return spoiledKeyframe(map_id, [](rgbdslam::keyframe_t& m) { m.measurements[0].level = 4, m.new_points[0].level = 4; });
  }
  if (kind == "keyframe-far") return spoiledKeyframe(map_id, [](rgbdslam::keyframe_t& m) { m.position[0] = 1e155; });
  return {};
}

std::vector<uint8_t> validMessage(const std::string& type) {
  if (type == "frame") return encode(toLcm(smallFrame(640, 480), FrameEncoding{}));
  if (type == "keyframe") return keyframeBytes(1);
  if (type == "map") return mapBytes(1, 5);
  return encodePose(0, 1);
}

std::vector<uint8_t> badMessage(const std::string& kind, const std::string& type, int64_t map_id) {
  if (kind == "keyframe-foreign-map") return keyframeBytes(424242);
  if (kind == "map-stale") return mapBytes(map_id, 1);
  if (kind == "map-foreign-map") return mapBytes(424242, 1000000000);
  if (kind == "frame-wrong-size") return encode(toLcm(smallFrame(320, 240), FrameEncoding{}));
  if (auto hostile = hostileMessage(kind, map_id); !hostile.empty()) return hostile;
  std::vector<uint8_t> bytes = validMessage(type);
  if (kind == "truncated") bytes.resize(bytes.size() / 2);
  else if (kind == "oversized") bytes.resize(bytes.size() + 1000, 0x5A);
  else if (kind == "wrongtype") {
    rgbdslam::status_t status;
    status.component = "not-a-" + type;
    status.num_counters = status.num_timings = 0;
    bytes.resize(status.getEncodedSize());
    status.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  } else {
    bytes.assign(64, 0xFF);
  }
  return bytes;
}

}  // namespace

int main(int argc, char** argv) {
  CommandLine cli("send-messages", "Test tool: publishes test messages.");
  cli.option("channel", "NAME", "channel", "SLAM_POSE");
  cli.option("poses", "N", "valid pose_t messages to send", "0");
  cli.option("rate", "HZ", "messages per second", "200");
  cli.option("bad", "KIND", "one bad message: truncated|oversized|wrongtype|garbage|keyframe-foreign-map|map-stale|map-foreign-map|frame-wrong-size|map-huge-count|keyframe-huge-counts|status-huge-counts|keyframe-level-4|keyframe-far");
  cli.option("type", "T", "message type the malformed kinds start from: pose|frame|keyframe|map", "pose");
  cli.option("map-id", "ID", "map id of the poses and of --bad map-stale", "1");
  addLcmUrlOption(cli);
  if (Status s = cli.parse(argc, argv); !s) return usageError("send-messages", s.error());
  if (cli.helpRequested()) return std::cout << cli.helpText(), 0;
  auto lcm = openLcm(cli.get("lcm-url"));
  if (!lcm) return usageError("send-messages", lcm.error());
  const std::string channel = cli.get("channel");
  if (cli.has("bad")) {
    const auto bytes = badMessage(cli.get("bad"), cli.get("type"), *cli.getInt("map-id"));
    (*lcm)->publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
  }
  const long n = *cli.getInt("poses");
  const auto period = std::chrono::microseconds(static_cast<int64_t>(1e6 / *cli.getDouble("rate")));
  for (long i = 0; i < n; ++i) {
    const auto bytes = encodePose(i, *cli.getInt("map-id"));
    (*lcm)->publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
    std::this_thread::sleep_for(period);
  }
  return 0;
}
