#pragma once
// Re-finding map points in keyframes that did not measure them (PTAM's ReFindNewlyMade):
// project the point with the keyframe's pose, warp its patch from the source keyframe into
// the keyframe's view, search it among the FAST corners of the matching pyramid level near
// the prediction (ZMSSD) and refine the match to sub-pixel accuracy.
// Frames and units: T_w_c camera to world; pixels at level 0; ZMSSD over 64 pixels.
#include <optional>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/image/patch.h"
#include "rgbdslam/map/map.h"

namespace rgbdslam {

struct RefindOptions {
  int search_radius_px = 5;   // around the predicted position [px of the search level]
  int max_zmssd = 400 * 64;   // accepted patch difference [grey^2 over 64 px]
  // ...and below this times the template's zero-mean energy, which a textureless patch
  // exceeds (as the tracker's PointSearchOptions::max_zmssd_flat_ratio; 0: off) [-]
  double max_zmssd_flat_ratio = 0.0;
  double border_px = 8.0;     // predictions closer to the image edge are not searched [px]
};

// The measurement of 'point' (whose patch lives in 'source') in 'target' (depth 0), or
// nullopt when it projects outside, behind, at a degenerate warp, or is not found.
std::optional<Measurement> findPointInKeyframe(const MapPoint& point, const Keyframe& source,
                                               const Keyframe& target, const PinholeCamera& camera,
                                               const RefindOptions& options);

// The ZMSSD acceptance for 'patch': min(max_zmssd, flat_ratio * its zero-mean energy), or
// max_zmssd when flat_ratio <= 0. A weak template is not accepted on a textureless patch.
int flatCappedAcceptance(const Patch& patch, int max_zmssd, double flat_ratio);

// The 2x2 affine map from small offsets around the point's pixel in 'source' to offsets in
// 'target' [level-0 px / level-0 px], by projecting offset pixels at the point's depth.
// nullopt when the point is behind either camera.
std::optional<Eigen::Matrix2d> patchWarp(const MapPoint& point, const Keyframe& source,
                                         const Keyframe& target, const PinholeCamera& camera);

}  // namespace rgbdslam
