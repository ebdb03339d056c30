#pragma once
// The capture loop: read a frame from the source, check it against the camera, pace it,
// encode and publish it. Bad frames are reported (naming the file) and skipped; the exit
// status tells whether any were.
#include <atomic>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <optional>
#include <string>

#include "common/cli.h"
#include "common/lcm_conversions.h"
#include "common/process_options.h"
#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/io/frame_source.h"
#include "rgbdslam/io/trajectory_io.h"

namespace rgbdslam {

// Largest publishing rate --rate accepts: 10 kHz is 300x a camera's 30 Hz.
constexpr double kMaxRateHz = 10000.0;  // [frames/s]
// Largest recorded gap between two frames that pacing by recorded timestamps waits for:
// a minute is beyond any sensor dropout; a larger gap (31 years from a corrupt stamp) or
// a step back is reported and pacing restarts at that frame.
constexpr double kMaxPacedGapS = 60.0;  // [s]

struct CaptureOptions {
  std::string source;                 // source spec (tum:, synth:, openni2:, lcmlog:)
  std::string camera_path;            // calibration file; empty = none
  std::optional<double> rate_hz;      // [frames/s]; 0 = unpaced; nullopt = recorded timestamps
  bool step = false;                  // one frame per Enter key
  std::string channel = ChannelOptions{}.frame;
  FrameEncoding encoding;
  long max_frames = 0;                // 0 = all
  std::string groundtruth_out;        // where to write the source's ground truth; empty = nowhere
  // false: frames keep their recorded utime; true: each frame is stamped with the host clock
  // when it is published (as a live camera stamps at acquisition; latency downstream is then
  // measurable, and the renderer's own time is not counted). The ground truth is written at
  // the end with the same stamps (times between frames mapped linearly).
  bool host_clock = false;
  std::string lcm_url;

  static Expected<CaptureOptions> fromCommandLine(const CommandLine& cli);
  std::string describe() const;       // the effective configuration, one option per line
};

class Capture {
 public:
  static Expected<std::unique_ptr<Capture>> create(const CaptureOptions& options);
  std::string describeSource() const;
  // Runs until the source ends, fails, max_frames, or 'stop'. Returns the exit status:
  // 0 all frames published, 1 some frames bad or the source failed.
  int run(const std::atomic<bool>& stop);

 private:
  Capture(CaptureOptions options, std::optional<PinholeCamera> camera,
          std::unique_ptr<FrameSource> source, std::unique_ptr<lcm::LCM> lcm);
  std::string checkAgainstCamera(const RgbdFrame& frame) const;  // empty when fine
  bool waitForTurn(const RgbdFrame& frame, const std::atomic<bool>& stop);
  bool paceableGap(const RgbdFrame& frame);  // false: report the gap and restart pacing

  CaptureOptions options_;
  std::optional<PinholeCamera> camera_;
  std::unique_ptr<FrameSource> source_;
  std::unique_ptr<lcm::LCM> lcm_;
  Status writeGroundtruth() const;
  std::optional<Trajectory> groundtruth_;  // to write, when --groundtruth-out is given
  std::vector<std::pair<int64_t, int64_t>> stamps_;  // (recorded, host) utime per published frame
  long published_ = 0, bad_ = 0;
  int64_t first_utime_ = 0, first_wall_us_ = 0;  // pacing's anchor: a frame and when it went out
  int64_t last_utime_ = 0;                         // the previous paced frame's stamp
  long first_published_ = 0, pacing_restarts_ = 0;
};

}  // namespace rgbdslam
