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

// The state's name as logs and status reports show it ("tracking", "lost", ...).
inline const char* toString(TrackingState state) {
  switch (state) {
    case TrackingState::kInitialising: return "initialising";
    case TrackingState::kTracking: return "tracking";
    case TrackingState::kDodgy: return "dodgy";
    case TrackingState::kLost: return "lost";
    case TrackingState::kRelocalised: return "relocalised";
  }
  return "unknown";
}

struct PoseEstimate {
  int64_t utime = 0;     // the frame's acquisition time [us]
  int64_t seq = 0;       // the frame's sequence number
  // The published pose: the map's corrections (bundle adjustment, loop closures, a part
  // joined to another) taken in at most at TrackerOptions::correction_rate_*, so that it
  // never jumps.
  SE3 T_w_c;
  // The pose in the map as it is now, corrections and all (it jumps when the map is
  // corrected); T_w_c's distance from it is the correction not yet taken in.
  SE3 map_T_w_c;
  // The part of the map the pose is in (Keyframe::part, as the tracker knew it then; 0: the
  // map's start). Another part's place in the world is a guess until the ground joins it.
  int64_t part = 0;
  TrackingState state = TrackingState::kInitialising;
  int points_tracked = 0;
  double quality = 0.0;     // fraction of searched points found [0, 1]
  // From the frame's utime to the publication of this pose [ms]: only the process that
  // publishes knows it and sets it (rgbd-tracker); the tracker leaves 0. The tracker's own
  // time for the frame is TrackResult::track_ms.
  double latency_ms = 0.0;
};

}  // namespace rgbdslam
