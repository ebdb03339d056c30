#pragma once
// PTAM's relocaliser. Why: after tracking is lost (camera covered, fast motion, dropped
// frames), the current view is compared as a whole with every keyframe's small blurry image;
// each keyframe's SBI is aligned to the current one by an SE(2) warp (ESM); the keyframes
// with the smallest remaining error, each turned by the rotation that explains the warp,
// give candidate poses from which the tracker tries to track again. (PTAM ranks by the
// plain ZMSSD first; with keyframes several degrees apart that ranking is nearly random.)
// Cost: 0.23 ms per keyframe at full resolution (up to 10 ESM iterations on 40x30 images;
// measured on the flight: 19 ms per lost frame with 83 keyframes), so it grows with the map:
// a long flight needs an index in front of it: above tracker.relocalise_shortlist keyframes
// the tracker aligns only a shortlist, chosen by the bag of words and by distance
// (tracker.h). And where more than 2 n keyframes are ranked for n candidates, the ranking
// is coarse to fine: every keyframe aligned at half the SBI's resolution (20x15 at
// 640x480, a quarter of the pixels), the best 2 n again at full resolution from there, and
// ranked by that error: 1.3 ms for a shortlist of 30 and 4 candidates, against 3.1 ms at
// full resolution (bench_place_recognition, BM_RelocalisationRanking).
// Call order: relocalisationCandidates(map, sbi, camera, n) -> try each pose in order.
// Frames: T_w_c camera to world.
#include <optional>
#include <vector>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/image/small_blurry_image.h"
#include "rgbdslam/map/map.h"
#include "rgbdslam/mapping/binary_vocabulary.h"

namespace rgbdslam {

struct RelocalisationCandidate {
  KeyframeId keyframe = -1;
  double score = 0.0;  // mean squared SBI error after alignment [grey^2] (smaller is better)
  SE3 T_w_c;           // the keyframe's pose turned by the SBI rotation
};

// The n keyframes most similar to 'sbi', best first, with their candidate poses: among all
// the map's keyframes, or only among 'among' (ids not in the map are skipped), which bounds
// the cost on a large map (the tracker's shortlist: tracker.h, relocalise_shortlist).
std::vector<RelocalisationCandidate> relocalisationCandidates(const Map& map,
                                                              const SmallBlurryImage& sbi,
                                                              const PinholeCamera& camera,
                                                              int n,
                                                              const std::vector<KeyframeId>* among = nullptr);

// A lost frame's shortlist on a large map (tracker.relocalise_shortlist = n): the n / 2
// keyframes nearest 'T_w_last' (the last good pose: a short disturbance), then the best by
// bag of words over all keyframes in 'index' (images = keyframe ids; ids not in the map are
// skipped) up to n in all; only keyframes within 'reach_m' of T_w_last (infinity: all). The
// bag's best 'by_words_wanted' go to '*by_words' as well (the feature relocaliser's
// candidates; may be null). 'bag' empty (no features): the nearest only. 'part': only that
// part's keyframes (Keyframe::part; T_w_last is in its frame).
std::vector<KeyframeId> relocalisationShortlist(const Map& map, const BowIndex& index, const BowVector& bag,
                                                const SE3& T_w_last, double reach_m, size_t n,
                                                size_t by_words_wanted, std::vector<KeyframeId>* by_words,
                                                std::optional<KeyframeId> part = std::nullopt);

}  // namespace rgbdslam
