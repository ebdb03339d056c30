#pragma once
// The image's word on a tracked pose (issue 12): each tracked patch must look, where the
// pose puts its map point, like it does where it was found. For a sample of the found points
// (inliers of the fine stage), the point is projected with the pose and its warped patch is
// compared with the current image there (ZMSSD, bilinear at the sub-pixel projection, at the
// level it was found on). The acceptance is the search's own (patchAcceptance(): what the
// search would accept as this patch). At a right pose a found point projects within its
// measurement noise of where it was found (well under a pixel of its level), and its patch is
// accepted there too. A pose that compromises between matches that do not agree (wrong
// matches, a coarse stage pulled off, a depth fit that the corners do not follow) leaves
// patches pixels away from where they were found, and a textured patch a pixel or two off is
// rejected. The pose is inconsistent when more than max_mismatch_ratio of the checked patches
// are rejected where it puts them.
// What it cannot see: matches that are all wrong the same way (a pose that explains them
// well); there the image agrees with the wrong pose, and only depth or the motion can tell.
// Cost: one projection and a 64-pixel bilinear ZMSSD per sampled patch.
#include <string>
#include <vector>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/geometry/se3.h"
#include "rgbdslam/image/pyramid.h"
#include "rgbdslam/tracking/point_projection.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

struct PhotometricIntegrityOptions {
  bool enabled = true;               // in every mode (it needs no depth)
  int max_samples = 100;             // found patches checked per frame at most [patches]
  int min_samples = 20;              // fewer found patches: no verdict [patches]
  double max_mismatch_ratio = 0.5;   // more patches rejected where the pose puts them: inconsistent

  void bind(OptionRegistry* registry, const std::string& section);  // as photometric_*
};

struct PhotometricIntegrity {
  int checked = 0;     // found patches compared where the pose puts them
  int mismatched = 0;  // ...that the search would not accept there
  bool judged = false;  // enough patches were checked for a verdict
  bool consistent = true;
  double mismatchRatio() const { return checked > 0 ? static_cast<double>(mismatched) / checked : 0.0; }
  std::string describe() const;  // "30 of 80 tracked patches do not match where the pose puts them"
};

// 'slots': the stage's slots; those found (found, with a patch made at the level found)
// are checked. 'pyramid': the current frame's. Nothing is checked when the option is off.
PhotometricIntegrity checkPhotometricIntegrity(const std::vector<PointSlot*>& slots, const SE3& T_c_w,
                                               const ImagePyramid& pyramid, const PinholeCamera& camera,
                                               const PointSearchOptions& search,
                                               const PhotometricIntegrityOptions& options);

}  // namespace rgbdslam
