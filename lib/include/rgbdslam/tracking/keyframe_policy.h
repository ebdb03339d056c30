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
// With depth a keyframe can also come before the pose's uncertainty reaches the loss limit:
// when the fit's translation sigma has been over uncertain_pose_sigma_m for
// uncertain_pose_frames frames in a row while points are plenty (at least few_points: the
// points found lie far, beyond the depth range, where a sideways step and a turn look
// alike), a keyframe brings near points from depth while the pose can still place them.
// One frame over it is not enough: a single uncertain frame (a blur, a fast turn) would
// become a keyframe with its poor pose, while thinning points persist. Where points are
// scarce the few-points rule decides alone: there the sigma grows because points are few,
// and keyframes on those uncertain poses cost the corridor accuracy through the suite
// (the rule without this condition: 155, 148, 61 and 26 mm against 28, 47 and 40 mm).
// Call order: after the pose of a frame is final; shouldAddKeyframe(...).
// Frames and units: T_w_c camera to world [m]; angles in degrees.
#include <vector>

#include "rgbdslam/geometry/se3.h"
#include "rgbdslam/map/map.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

struct KeyframePolicyOptions {
  int min_frames_between_keyframes = 10;  // frames since the last keyframe
  double distance_ratio = 0.1;            // distance / median scene depth to count as "far"
  double angle_deg = 15.0;                // rotation to count as "turned" [deg]
  // With depth for new points, a frame that found fewer points than few_points gets a
  // keyframe after few_points_min_frames, wherever it is (0: off).
  int few_points = 60;                    // [points]
  int few_points_min_frames = 3;          // [frames]
  // With depth for new points, a frame that found at least few_points and whose pose sigma
  // (translation, worst direction) has exceeded this for uncertain_pose_frames frames gets a
  // keyframe (0: off). 1.5 cm: 30 % of the loss limit (tracker.max_pose_sigma_m, 5 cm), so
  // the keyframe's points are placed from a pose still three times better than a lost one;
  // above the 99th percentile of tracked frames in the corridor (1.2 cm) and the room
  // (0.4 cm). It carries the flight past the hall (batch, 2 minutes: 985 -> 2824 posed);
  // room, teddy, the corridor and the office are byte-identical with and without it (batch).
  double uncertain_pose_sigma_m = 0.015;  // [m]
  int uncertain_pose_frames = 3;          // [frames]
  // The same in mono, where a keyframe gets its points only from the mapper's epipolar
  // search against an earlier keyframe (0: off). Measured on the synthetic corridor (900
  // frames, final position error) with one epipolar partner: 80 points with a wait of 2, 3
  // or 4 frames 0.16, 0.05, 0.12 %; 100 and 3: 0.11 %; 60 and 2-4: 0.4-0.8 %, but 60 and 5
  // or 40 and 3 let the points run short and the scale collapsed (50-70 %), 60 and 8 lost
  // tracking. With two partners (mapper.epipolar_partners_mono) 60 and 5: 0.18 %, 40 and
  // 3: 0.09 %.
  int few_points_no_depth = 80;           // [points]
  int few_points_no_depth_min_frames = 3;  // [frames]

  void bind(OptionRegistry* registry, const std::string& section);  // the tracker's keys
};

struct KeyframePolicyInput {
  bool tracking_good = false;       // state tracking (not dodgy, not lost)
  int frames_since_keyframe = 0;    // frames tracked since the last keyframe was added
  double median_depth_m = 0.0;      // median depth of the points found in this frame [m]
  SE3 T_w_c;                        // this frame's pose
  int points_found = 0;             // map points found in this frame
  bool points_from_depth = false;   // a keyframe now would get points from measured depth
  // Corners the frame offers (FAST, all levels; -1: unknown). Fewer than the few-points
  // threshold: a keyframe here could not bring the points that are short (a plain wall), so
  // the few-points rule waits; the distance and angle rule still applies.
  int corners = -1;
  // Consecutive tracked frames, this one included, whose pose sigma (the fit's translation
  // sigma, worst direction) exceeded uncertain_pose_sigma_m.
  int uncertain_frames = 0;
  // The part of the map the frame is tracked in (Keyframe::part): only its keyframes cover a
  // view (another part's lie where a guess put them).
  KeyframeId part = 0;
};

// True if no keyframe is both within distance_ratio * median depth and within angle_deg,
// or if few points were found or the pose is uncertain (see above).
bool shouldAddKeyframe(const Map& map, const KeyframePolicyInput& input,
                       const KeyframePolicyOptions& options);

}  // namespace rgbdslam
