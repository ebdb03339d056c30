// send-messages (test tool): publishes test traffic on one channel.
//   --poses N [--rate HZ]          N valid pose_t messages (seq 0..N-1, a moving pose)
//   --bad truncated|oversized|wrongtype|garbage   one malformed message of that kind
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

std::vector<uint8_t> encodePose(int64_t seq) {
  PoseEstimate pose;
  pose.utime = 1700000000000000 + seq * 33333;
  pose.seq = seq;
  Vec6 xi;
  xi << 0.01 * seq, 0.002 * seq, -0.001 * seq, 0.001 * seq, 0.002 * seq, 0.0;
  pose.T_w_c = SE3::exp(xi);
  pose.state = TrackingState::kTracking;
  pose.points_tracked = 100;
  pose.quality = 0.9;
  pose.latency_ms = 2.5;
  const rgbdslam::pose_t msg = toLcm(pose);
  std::vector<uint8_t> bytes(msg.getEncodedSize());
  msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

std::vector<uint8_t> badMessage(const std::string& kind) {
  std::vector<uint8_t> bytes = encodePose(0);
  if (kind == "truncated") bytes.resize(bytes.size() / 2);
  else if (kind == "oversized") bytes.resize(bytes.size() + 1000, 0x5A);
  else if (kind == "wrongtype") {
    rgbdslam::status_t status;
    status.component = "not-a-pose";
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
  cli.option("bad", "KIND", "one malformed message: truncated|oversized|wrongtype|garbage");
  addLcmUrlOption(cli);
  if (Status s = cli.parse(argc, argv); !s) return usageError("send-messages", s.error());
  if (cli.helpRequested()) return std::cout << cli.helpText(), 0;
  auto lcm = openLcm(cli.get("lcm-url"));
  if (!lcm) return usageError("send-messages", lcm.error());
  const std::string channel = cli.get("channel");
  if (cli.has("bad")) {
    const auto bytes = badMessage(cli.get("bad"));
    (*lcm)->publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
  }
  const long n = *cli.getInt("poses");
  const auto period = std::chrono::microseconds(static_cast<int64_t>(1e6 / *cli.getDouble("rate")));
  for (long i = 0; i < n; ++i) {
    const auto bytes = encodePose(i);
    (*lcm)->publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
    std::this_thread::sleep_for(period);
  }
  return 0;
}
