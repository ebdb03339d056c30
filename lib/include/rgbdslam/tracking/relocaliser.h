#pragma once
// PTAM's relocaliser. Why: after tracking is lost (camera covered, fast motion, dropped
// frames), the current view is compared as a whole with every keyframe's small blurry image;
// each keyframe's SBI is aligned to the current one by an SE(2) warp (ESM); the keyframes
// with the smallest remaining error, each turned by the rotation that explains the warp,
// give candidate poses from which the tracker tries to track again. (PTAM ranks by the
// plain ZMSSD first; with keyframes several degrees apart that ranking is nearly random.)
// Cost: 0.23 ms per keyframe (up to 10 ESM iterations on 40x30 images; measured on the
// flight: 19 ms per lost frame with 83 keyframes), so it grows with the map: a long flight
// needs an index (place recognition's words) in front of it (docs/open_work.md).
// Call order: relocalisationCandidates(map, sbi, camera, n) -> try each pose in order.
// Frames: T_w_c camera to world.
#include <vector>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/image/small_blurry_image.h"
#include "rgbdslam/map/map.h"

namespace rgbdslam {

struct RelocalisationCandidate {
  KeyframeId keyframe = -1;
  double score = 0.0;  // mean squared SBI error after alignment [grey^2] (smaller is better)
  SE3 T_w_c;           // the keyframe's pose turned by the SBI rotation
};

// The n keyframes most similar to 'sbi', best first, with their candidate poses.
std::vector<RelocalisationCandidate> relocalisationCandidates(const Map& map,
                                                              const SmallBlurryImage& sbi,
                                                              const PinholeCamera& camera,
                                                              int n);

}  // namespace rgbdslam
