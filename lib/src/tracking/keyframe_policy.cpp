#include "rgbdslam/tracking/keyframe_policy.h"

#include <algorithm>
#include <cmath>

namespace rgbdslam {
namespace {

double rotationAngleDeg(const SE3& a, const SE3& b) {
  return a.rotation().angularDistance(b.rotation()) * 180.0 / M_PI;
}

}  // namespace

void KeyframePolicyOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "min_frames_between_keyframes", &min_frames_between_keyframes, 0, 100000, "frames",
          "frames since the last keyframe before another");
  r->bind(s, "keyframe_distance_ratio", &distance_ratio, 0.0, 10.0, "",
          "new keyframe when every keyframe is farther than this times the median depth...");
  r->bind(s, "keyframe_angle_deg", &angle_deg, 0.0, 180.0, "deg", "...or rotated by more than this");
  r->bind(s, "keyframe_few_points", &few_points, 0, 100000, "points",
          "fewer points found, and the mode makes points from depth: a keyframe is due "
          "whatever the distance (0: off)");
  r->bind(s, "keyframe_few_points_min_frames", &few_points_min_frames, 0, 100000, "frames",
          "...after at least this many frames since the last keyframe");
  r->bind(s, "keyframe_pose_sigma_m", &uncertain_pose_sigma_m, 0.0, 100.0, "m",
          "the pose's translation sigma above this for keyframe_pose_sigma_frames frames in a "
          "row while at least keyframe_few_points are found, and the mode makes points from "
          "depth: a keyframe is due (0: off)");
  r->bind(s, "keyframe_pose_sigma_frames", &uncertain_pose_frames, 1, 100000, "frames",
          "...this many frames");
  r->bind(s, "keyframe_few_points_mono", &few_points_no_depth, 0, 100000, "points",
          "mono (no points from depth): fewer points found gives a keyframe whatever the "
          "distance (0: off)");
  r->bind(s, "keyframe_few_points_mono_min_frames", &few_points_no_depth_min_frames, 0, 100000,
          "frames", "...after at least this many frames since the last keyframe");
}

bool shouldAddKeyframe(const Map& map, const KeyframePolicyInput& input,
                       const KeyframePolicyOptions& options) {
  if (!input.tracking_good) return false;
  const int few_points = input.points_from_depth ? options.few_points : options.few_points_no_depth;
  const int few_points_min_frames = input.points_from_depth ? options.few_points_min_frames
                                                            : options.few_points_no_depth_min_frames;
  const bool corners_to_gain = input.corners < 0 || input.corners >= few_points;
  if (input.points_found < few_points && input.frames_since_keyframe >= few_points_min_frames &&
      corners_to_gain) {
    return true;
  }
  if (input.points_from_depth && options.uncertain_pose_sigma_m > 0.0 &&
      input.uncertain_frames >= options.uncertain_pose_frames && input.points_found >= few_points && corners_to_gain) {
    return true;
  }
  if (input.frames_since_keyframe < options.min_frames_between_keyframes) return false;
  if (!(input.median_depth_m > 0.0)) return false;
  const double max_distance = options.distance_ratio * input.median_depth_m;
  for (const auto& [id, keyframe] : map.keyframes()) {
    if (keyframe->part != input.part) continue;
    const double distance = (keyframe->T_w_c.translation() - input.T_w_c.translation()).norm();
    if (distance <= max_distance && rotationAngleDeg(keyframe->T_w_c, input.T_w_c) <= options.angle_deg) {
      return false;  // this keyframe already covers the view
    }
  }
  return true;
}

}  // namespace rgbdslam
