#pragma once
// PTAM's keyframe decision. Why: a new keyframe is worth its cost (mapping, bundle
// adjustment) only when tracking is good, some frames have passed since the last one, and
// the camera sees the scene from a place no keyframe covers: every keyframe is either
// farther than a fraction of the scene depth or rotated by more than an angle.
// With depth a keyframe also restores the supply of points: when the frame's found points
// fall below few_points (the view moving into unmapped space, e.g. forward in a corridor
// where points leave the image within metres), a keyframe is due after
// few_points_min_frames whatever the distance, if the caller says new points can come
// from depth ('points_from_depth').
// Without depth (mono) a keyframe brings points only through the mapper's epipolar search
// against an earlier keyframe, so the same rule has its own threshold and wait
// (few_points_no_depth, few_points_no_depth_min_frames).
// Call order: after the pose of a frame is final; shouldAddKeyframe(...).
// Frames and units: T_w_c camera to world [m]; angles in degrees.
#include <vector>

#include "rgbdslam/geometry/se3.h"
#include "rgbdslam/map/map.h"

namespace rgbdslam {

struct KeyframePolicyOptions {
  int min_frames_between_keyframes = 10;  // frames since the last keyframe
  double distance_ratio = 0.1;            // distance / median scene depth to count as "far"
  double angle_deg = 15.0;                // rotation to count as "turned" [deg]
  int few_points = 0;                     // fewer found points: keyframe due (0: off)
  int few_points_min_frames = 3;          // ...after at least this many frames
  int few_points_no_depth = 0;            // the same when no points come from depth (0: off)
  int few_points_no_depth_min_frames = 3;  // ...after at least this many frames
};

struct KeyframePolicyInput {
  bool tracking_good = false;       // state tracking (not dodgy, not lost)
  int frames_since_keyframe = 0;    // frames tracked since the last keyframe was added
  double median_depth_m = 0.0;      // median depth of the points found in this frame [m]
  SE3 T_w_c;                        // this frame's pose
  int points_found = 0;             // map points found in this frame
  bool points_from_depth = false;   // a keyframe now would get points from measured depth
};

// True if no keyframe is both within distance_ratio * median depth and within angle_deg,
// or if few points were found (see above).
bool shouldAddKeyframe(const Map& map, const KeyframePolicyInput& input,
                       const KeyframePolicyOptions& options);

}  // namespace rgbdslam
