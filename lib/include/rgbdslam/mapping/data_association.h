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
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

// Patch acceptance of the mapper's searches (epipolar search and re-finding).
struct PatchMatchOptions {
  int max_zmssd_per_pixel = 400;      // accepted patch difference [grey^2 per patch pixel]
  // ...and below this times the template's zero-mean energy, which a textureless patch
  // exceeds (as the tracker's PointSearchOptions::max_zmssd_flat_ratio; 0: off) [-]
  double max_zmssd_flat_ratio = 0.7;

  // The ZMSSD a match of 'patch' must stay below (flatCappedAcceptance).
  int acceptance(const Patch& patch) const;
  void bind(OptionRegistry* registry, const std::string& section);
};

struct RefindOptions {
  int search_radius_px = 5;   // around the predicted position [px of the search level]
  double border_px = 8.0;     // predictions closer to the image edge are not searched [px]

  void bind(OptionRegistry* registry, const std::string& section);  // the radius
};

// The measurement of 'point' (whose patch lives in 'source') in 'target' (depth 0), or
// nullopt when it projects outside, behind, at a degenerate warp, or is not found.
std::optional<Measurement> findPointInKeyframe(const MapPoint& point, const Keyframe& source,
                                               const Keyframe& target, const PinholeCamera& camera,
                                               const RefindOptions& options,
                                               const PatchMatchOptions& matching);

// The ZMSSD acceptance for 'patch': min(max_zmssd, flat_ratio * its zero-mean energy), or
// max_zmssd when flat_ratio <= 0. A weak template is not accepted on a textureless patch.
int flatCappedAcceptance(const Patch& patch, int max_zmssd, double flat_ratio);

// The 2x2 affine map from small offsets around the point's pixel in 'source' to offsets in
// 'target' [level-0 px / level-0 px], by projecting offset pixels at the point's depth.
// nullopt when the point is behind either camera.
std::optional<Eigen::Matrix2d> patchWarp(const MapPoint& point, const Keyframe& source,
                                         const Keyframe& target, const PinholeCamera& camera);

}  // namespace rgbdslam
