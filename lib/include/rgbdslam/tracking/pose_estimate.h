#pragma once
// The tracker's output for one frame.
#include <cstdint>

#include "rgbdslam/geometry/se3.h"

namespace rgbdslam {

enum class TrackingState : int8_t {
  kInitialising = 0,  // no map yet
  kTracking = 1,      // good
  kDodgy = 2,         // tracked, few points found
  kLost = 3,          // pose is the last good one; relocalising
  kRelocalised = 4,   // first pose after recovering
};

struct PoseEstimate {
  int64_t utime = 0;     // the frame's acquisition time [us]
  int64_t seq = 0;       // the frame's sequence number
  SE3 T_w_c;
  TrackingState state = TrackingState::kInitialising;
  int points_tracked = 0;
  double quality = 0.0;     // fraction of searched points found [0, 1]
  double latency_ms = 0.0;  // frame utime to publication [ms]
};

}  // namespace rgbdslam
