#include "rgbdslam/tracking/relocaliser.h"

#include <algorithm>

namespace rgbdslam {

std::vector<RelocalisationCandidate> relocalisationCandidates(const Map& map,
                                                              const SmallBlurryImage& sbi,
                                                              const PinholeCamera& camera,
                                                              int n) {
  std::vector<RelocalisationCandidate> candidates;
  for (const auto& [id, keyframe] : map.keyframes()) {
    if (keyframe->sbi.image.size() != sbi.image.size()) continue;
    // Rank by the error left after the SE(2) alignment: the plain ZMSSD of two views a few
    // degrees apart is dominated by the shift and ranks unrelated views alike.
    double error = 0.0;
    const Se2 se2 = alignSmallBlurryImages(keyframe->sbi, sbi, kSbiAlignIterations, &error);
    candidates.push_back({id, error, keyframe->T_w_c * rotationFromSe2(se2, camera, sbi.scale)});
  }
  const size_t keep = std::min(candidates.size(), static_cast<size_t>(std::max(n, 0)));
  std::partial_sort(candidates.begin(), candidates.begin() + static_cast<std::ptrdiff_t>(keep),
                    candidates.end(), [](const RelocalisationCandidate& a,
                                         const RelocalisationCandidate& b) {
                      return a.score < b.score;
                    });
  candidates.resize(keep);
  return candidates;
}

}  // namespace rgbdslam
