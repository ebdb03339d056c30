#include "rgbd-capture/capture.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <limits>
#include <sstream>
#include <thread>

#include "common/process.h"
#include "common/source_factory.h"
#include "rgbdslam/camera/calibration_io.h"

namespace rgbdslam {
namespace {
constexpr int64_t kSleepSliceUs = 20000;  // [us] longest sleep between checks of the stop flag
}

Expected<CaptureOptions> CaptureOptions::fromCommandLine(const CommandLine& cli) {
  CaptureOptions o;
  if (!cli.has("source")) return Error{"--source is required (see --help)"};
  o.source = cli.get("source");
  o.camera_path = cli.get("camera");
  if (cli.has("rate")) {
    auto rate = cli.getDouble("rate", 0.0, kMaxRateHz);
    if (!rate) return Error{rate.error() + " [frames/s]"};
    o.rate_hz = *rate;
  }
  o.step = cli.has("step");
  o.channel = cli.get("channel");
  const std::string colour = cli.get("colour"), depth = cli.get("depth");
  if (colour != "raw" && colour != "jpeg") return Error{"--colour must be raw or jpeg"};
  if (depth != "raw" && depth != "zlib") return Error{"--depth must be raw or zlib"};
  o.encoding.jpeg_colour = colour == "jpeg";
  o.encoding.zlib_depth = depth == "zlib";
  auto quality = cli.getInt("jpeg-quality", 1, 100);
  if (!quality) return Error{quality.error()};
  o.encoding.jpeg_quality = static_cast<int>(*quality);
  auto max_frames = cli.getInt("max-frames", 0, std::numeric_limits<long>::max());
  if (!max_frames) return Error{max_frames.error()};
  o.max_frames = *max_frames;
  o.lcm_url = cli.get("lcm-url");
  o.groundtruth_out = cli.get("groundtruth-out");
  const std::string clock = cli.get("clock");
  if (clock != "recorded" && clock != "host") return Error{"--clock must be recorded or host"};
  o.host_clock = clock == "host";
  return o;
}

std::string CaptureOptions::describe() const {
  std::ostringstream out;
  out << "rgbd-capture configuration:\n  source " << source << "\n  camera "
      << (camera_path.empty() ? "(none)" : camera_path) << "\n  rate "
      << (rate_hz ? (*rate_hz > 0 ? std::to_string(*rate_hz) + " Hz" : "unpaced") : "recorded timestamps")
      << (step ? ", one frame per Enter" : "") << "\n  channel " << channel << "\n  colour "
      << (encoding.jpeg_colour ? "jpeg q" + std::to_string(encoding.jpeg_quality) : "raw")
      << "\n  depth " << (encoding.zlib_depth ? "zlib" : "raw") << "\n  max-frames "
      << max_frames << "\n  clock " << (host_clock ? "host" : "recorded") << "\n  lcm-url " << lcm_url << "\n";
  return out.str();
}

Expected<std::unique_ptr<Capture>> Capture::create(const CaptureOptions& options) {
  std::optional<PinholeCamera> camera;
  if (!options.camera_path.empty()) {
    auto loaded = loadCamera(options.camera_path);
    if (!loaded) return Error{loaded.error()};
    camera = *loaded;
  }
  auto source = openSource(options.source, camera);
  if (!source) return Error{source.error()};
  auto lcm = openLcm(options.lcm_url);
  if (!lcm) return Error{lcm.error()};
  std::unique_ptr<Capture> capture(new Capture(options, camera, std::move(*source), std::move(*lcm)));
  if (!options.groundtruth_out.empty()) {
    capture->groundtruth_ = groundTruthFor(options.source);
    if (!capture->groundtruth_) return Error{"--groundtruth-out: " + options.source + " has no ground truth"};
    // With the host clock the stamps are known once the frames are published: written then.
    if (!options.host_clock) {
      if (Status s = capture->writeGroundtruth(); !s) return Error{s.error()};
    }
  }
  return capture;
}

// Re-stamps the ground truth like the frames: each time maps through the (recorded, host)
// pairs of the published frames, linearly between them and by the nearest shift outside;
// ground truth of a recording that published nothing is not written.
Status Capture::writeGroundtruth() const {
  Trajectory out = *groundtruth_;
  if (options_.host_clock) {
    if (stamps_.empty()) return Status{};
    for (TimedPose& pose : out) {
      const auto recorded = static_cast<int64_t>(std::llround(pose.t * 1e6));
      auto after = std::lower_bound(stamps_.begin(), stamps_.end(), std::make_pair(recorded, int64_t{0}));
      double shift_us;
      if (after == stamps_.begin()) {
        shift_us = static_cast<double>(stamps_.front().second - stamps_.front().first);
      } else if (after == stamps_.end()) {
        shift_us = static_cast<double>(stamps_.back().second - stamps_.back().first);
      } else {
        const auto before = after - 1;
        const double f = after->first == before->first ? 0.0 :
            static_cast<double>(recorded - before->first) / static_cast<double>(after->first - before->first);
        shift_us = (1 - f) * static_cast<double>(before->second - before->first) +
                   f * static_cast<double>(after->second - after->first);
      }
      pose.t = (static_cast<double>(recorded) + shift_us) * 1e-6;
    }
  }
  return writeTumTrajectory(options_.groundtruth_out, out);
}

Capture::Capture(CaptureOptions options, std::optional<PinholeCamera> camera,
                 std::unique_ptr<FrameSource> source, std::unique_ptr<lcm::LCM> lcm)
    : options_(std::move(options)), camera_(std::move(camera)), source_(std::move(source)),
      lcm_(std::move(lcm)) {}

std::string Capture::describeSource() const { return "  opened " + source_->describe(); }

std::string Capture::checkAgainstCamera(const RgbdFrame& frame) const {
  if (!camera_) return "";
  if (frame.width() != camera_->width || frame.height() != camera_->height) {
    return "frame " + std::to_string(frame.seq) + " is " + std::to_string(frame.width()) + "x" +
           std::to_string(frame.height()) + " but " + options_.camera_path + " says " +
           std::to_string(camera_->width) + "x" + std::to_string(camera_->height);
  }
  return "";
}

bool Capture::waitForTurn(const RgbdFrame& frame, const std::atomic<bool>& stop) {
  if (options_.step) {
    std::cerr << "frame " << frame.seq << ": press Enter to publish" << std::endl;
    std::string line;
    return static_cast<bool>(std::getline(std::cin, line)) && !stop;
  }
  const int64_t now = utimeNow();
  if (published_ == 0 || !paceableGap(frame)) {
    first_utime_ = last_utime_ = frame.utime;
    first_wall_us_ = now;
    first_published_ = published_;
    return !stop;
  }
  last_utime_ = frame.utime;
  int64_t due = now;
  if (!options_.rate_hz) {
    if (source_->nominalRateHz() > 0) due = first_wall_us_ + (frame.utime - first_utime_);
  } else if (*options_.rate_hz > 0) {
    due = first_wall_us_ + static_cast<int64_t>((published_ - first_published_) * 1e6 / *options_.rate_hz);
  }
  for (int64_t wait = due - utimeNow(); wait > 0 && !stop; wait = due - utimeNow()) {
    std::this_thread::sleep_for(std::chrono::microseconds(std::min(wait, kSleepSliceUs)));
  }
  return !stop;
}

// Pacing by recorded timestamps: a recorded gap to the previous frame beyond kMaxPacedGapS,
// or a step back in time, is not waited for. It is reported, and pacing starts again from
// this frame (a recording's clock jump or a corrupt stamp must not stall the capture).
bool Capture::paceableGap(const RgbdFrame& frame) {
  if (options_.rate_hz || options_.step || source_->nominalRateHz() <= 0) return true;
  const double gap_s = (static_cast<double>(frame.utime) - static_cast<double>(last_utime_)) * 1e-6;
  if (gap_s >= 0 && gap_s <= kMaxPacedGapS) return true;
  std::cerr << "rgbd-capture: frame " << frame.seq << " is stamped " << gap_s << " s after the previous one"
            << " (beyond [0, " << kMaxPacedGapS << "] s): not waiting for it, pacing restarts at this frame\n";
  ++pacing_restarts_;
  return false;
}

int Capture::run(const std::atomic<bool>& stop) {
  bool failed = false;
  while (!stop && (options_.max_frames == 0 || published_ < options_.max_frames)) {
    FrameResult result = source_->next();
    if (result.status == FrameResult::Status::kEnd) break;
    if (result.status == FrameResult::Status::kFailed) {
      std::cerr << "rgbd-capture: error: " << result.error << "\n";
      failed = true;
      break;
    }
    std::string problem = result.status == FrameResult::Status::kBadFrame ? result.error : checkAgainstCamera(result.frame);
    if (!problem.empty()) {
      std::cerr << "rgbd-capture: error: " << problem << " (frame skipped)\n";
      ++bad_;
      continue;
    }
    if (!waitForTurn(result.frame, stop)) break;
    if (options_.host_clock) {
      const int64_t recorded = result.frame.utime;
      result.frame.utime = utimeNow();
      // Recorded times increase; a source that repeats one keeps the first pairing.
      if (stamps_.empty() || recorded > stamps_.back().first) stamps_.emplace_back(recorded, result.frame.utime);
    }
    const rgbdslam::rgbd_frame_t msg = toLcm(result.frame, options_.encoding);
    if (lcm_->publish(options_.channel, &msg) != 0) {
      std::cerr << "rgbd-capture: error: publishing frame " << result.frame.seq << " failed\n";
      ++bad_;
      continue;
    }
    ++published_;
  }
  if (options_.host_clock && groundtruth_) {
    if (Status s = writeGroundtruth(); !s) {
      std::cerr << "rgbd-capture: error: " << s.error() << "\n";
      failed = true;
    }
  }
  std::cerr << "rgbd-capture: published " << published_ << " frames, " << bad_ << " bad";
  if (pacing_restarts_ > 0) std::cerr << ", pacing restarted " << pacing_restarts_ << " times at gaps in the recording";
  std::cerr << "\n";
  return (failed || bad_ > 0) ? 1 : 0;
}

}  // namespace rgbdslam
