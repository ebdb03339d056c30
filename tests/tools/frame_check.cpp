// frame-check (test tool): subscribes to rgbd_frame_t messages and checks them.
//   --expect SRC --camera CAM : every received frame must equal, pixel for pixel, frame
//                               'seq' of the same source read locally (tum:, synth:).
//   --count N                 : exit once N frames have arrived (success if all matched).
//   --timeout S               : give up after S seconds (failure).
//   --ready FILE              : created once subscribed, so a test can start the publisher.
// Prints "received N matched M bad B" and exits 0 only if N == count and M == N (or, without
// --expect, every frame decoded).
#include <fstream>
#include <iostream>
#include <map>

#include "common/cli.h"
#include "common/lcm_conversions.h"
#include "common/process.h"
#include "common/source_factory.h"
#include "rgbdslam/camera/calibration_io.h"
#include "rgbdslam/io/tum_dataset.h"

using namespace rgbdslam;

namespace {

class FrameChecker {
 public:
  explicit FrameChecker(std::map<int64_t, RgbdFrame> expected) : expected_(std::move(expected)) {}
  void onMessage(const lcm::ReceiveBuffer* buffer, const std::string&) {
    ++received_;
    auto msg = decodeMessage<rgbdslam::rgbd_frame_t>(buffer->data, buffer->data_size);
    auto frame = msg ? fromLcm(*msg) : Expected<RgbdFrame>(Error{msg.error()});
    if (!frame) {
      ++bad_;
      std::cerr << "frame-check: bad message: " << frame.error() << "\n";
      return;
    }
    if (expected_.empty()) return;
    const auto it = expected_.find(frame->seq);
    if (it == expected_.end()) {
      std::cerr << "frame-check: unexpected seq " << frame->seq << "\n";
      return;
    }
    const RgbdFrame& want = it->second;
    const bool same = want.utime == frame->utime && want.colour.size() == frame->colour.size() &&
                      cv::norm(want.colour, frame->colour, cv::NORM_INF) == 0 &&
                      cv::norm(want.depth, frame->depth, cv::NORM_INF) == 0 &&
                      want.depth_scale == frame->depth_scale;
    if (same) ++matched_;
    else std::cerr << "frame-check: frame " << frame->seq << " differs from the source\n";
  }
  long received_ = 0, matched_ = 0, bad_ = 0;

 private:
  std::map<int64_t, RgbdFrame> expected_;
};

Expected<std::map<int64_t, RgbdFrame>> loadExpected(const std::string& spec, const std::string& camera_path) {
  std::map<int64_t, RgbdFrame> frames;
  if (spec.empty()) return frames;
  std::optional<PinholeCamera> camera;
  if (!camera_path.empty()) {
    auto loaded = loadCamera(camera_path);
    if (!loaded) return Error{loaded.error()};
    camera = *loaded;
  }
  auto source = openSource(spec, camera);
  if (!source) return Error{source.error()};
  for (FrameResult r = (*source)->next(); r.status != FrameResult::Status::kEnd; r = (*source)->next()) {
    if (r.status != FrameResult::Status::kFrame) return Error{r.error};
    frames[r.frame.seq] = r.frame;
  }
  return frames;
}

}  // namespace

int main(int argc, char** argv) {
  CommandLine cli("frame-check", "Test tool: checks rgbd_frame_t messages against a source.");
  cli.option("expect", "SRC", "source whose frames must arrive unchanged");
  cli.option("camera", "FILE", "camera file for --expect");
  cli.option("count", "N", "frames to wait for", "1");
  cli.option("timeout", "S", "give up after this many seconds", "60");
  cli.option("ready", "FILE", "file created once subscribed");
  cli.option("channel", "NAME", "channel", "RGBD_FRAME");
  addLcmUrlOption(cli);
  if (Status s = cli.parse(argc, argv); !s) return usageError("frame-check", s.error());
  if (cli.helpRequested()) return std::cout << cli.helpText(), 0;
  auto expected = loadExpected(cli.get("expect"), cli.get("camera"));
  if (!expected) return usageError("frame-check", expected.error());
  auto lcm = openLcm(cli.get("lcm-url"));
  if (!lcm) return usageError("frame-check", lcm.error());
  FrameChecker checker(std::move(*expected));
  auto subscription = subscribeRaw(lcm->get(), cli.get("channel"), &checker, &FrameChecker::onMessage);
  if (cli.has("ready")) std::ofstream(cli.get("ready")) << "ready\n";
  const long count = *cli.getInt("count");
  const int64_t deadline = utimeNow() + static_cast<int64_t>(*cli.getDouble("timeout") * 1e6);
  const std::atomic<bool>& stop = installStopHandlers();
  while (!stop && checker.received_ < count && utimeNow() < deadline) (*lcm)->handleTimeout(100);
  std::cout << "received " << checker.received_ << " matched " << checker.matched_ << " bad "
            << checker.bad_ << std::endl;
  const bool all_matched = cli.get("expect").empty() ? checker.bad_ == 0 : checker.matched_ == checker.received_;
  return (checker.received_ == count && all_matched) ? 0 : 1;
}
