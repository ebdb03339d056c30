#pragma once
// --frame-log FILE.csv of rgbd-slam and rgbd-tracker: one line per frame tracked, so that a
// batch run and a real-time run can be read with the same tools. Columns:
//   seq, t_s (the frame's time [s]), status (initialised / tracked / lost / relocalised /
//   bad_frame / not_initialised), state (the pose's tracking state), points (found),
//   quality, sigma_m and sigma_deg (the pose's sigma [m], [deg]), correction_m (map
//   correction not yet published [m]), depth_aided, inconsistent, keyframe (the frame made
//   one: 0 / 1), track_ms (tracking [ms]), after_pose_ms (the frame's work after its pose
//   was published: keyframe, local map [ms]; rgbd-tracker only), latency_ms (frame time to
//   the pose's publication [ms]; rgbd-tracker only), reason (why lost or bad, quoted).
// A column a process does not measure is left empty.
#include <fstream>
#include <optional>
#include <string>

#include "rgbdslam/tracking/tracker.h"
#include "rgbdslam/util/expected.h"

namespace rgbdslam {

class FrameLog {
 public:
  FrameLog() = default;  // closed: write() does nothing
  // Creates FILE and writes the header; an error names the file.
  static Expected<FrameLog> open(const std::string& path);

  struct Times {
    std::optional<double> after_pose_ms, latency_ms;
  };
  void write(const TrackResult& result, bool keyframe, const Times& times = {});

 private:
  std::ofstream out_;
};

}  // namespace rgbdslam
