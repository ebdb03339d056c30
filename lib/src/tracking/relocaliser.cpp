#include "rgbdslam/tracking/relocaliser.h"

#include <algorithm>

namespace rgbdslam {

std::vector<RelocalisationCandidate> relocalisationCandidates(const Map& map,
                                                              const SmallBlurryImage& sbi,
                                                              const PinholeCamera& camera,
                                                              int n,
                                                              const std::vector<KeyframeId>* among) {
  std::vector<RelocalisationCandidate> candidates;
  const auto consider = [&](KeyframeId id, const Keyframe& keyframe) {
    if (keyframe.sbi.image.size() != sbi.image.size()) return;
    SmallBlurryImage restored;  // the replica keeps its keyframes' SBIs compact (map_replica.h)
    if (!keyframe.sbi.complete()) {
      restored.image = keyframe.sbi.image;  // shared, not copied
      restored.scale = keyframe.sbi.scale;
      restoreSmallBlurryImage(&restored);
    }
    const SmallBlurryImage& from = keyframe.sbi.complete() ? keyframe.sbi : restored;
    // Rank by the error left after the SE(2) alignment: the plain ZMSSD of two views a few
    // degrees apart is dominated by the shift and ranks unrelated views alike.
    double error = 0.0;
    const Se2 se2 = alignSmallBlurryImages(from, sbi, kSbiAlignIterations, &error);
    candidates.push_back({id, error, keyframe.T_w_c * rotationFromSe2(se2, camera, sbi.scale)});
  };
  if (among) {
    for (KeyframeId id : *among) {
      if (const Keyframe* keyframe = map.keyframe(id)) consider(id, *keyframe);
    }
  } else {
    for (const auto& [id, keyframe] : map.keyframes()) consider(id, *keyframe);
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

std::vector<KeyframeId> relocalisationShortlist(const Map& map, const BowIndex& index, const BowVector& bag,
                                                const SE3& T_w_last, double reach_m, size_t n,
                                                size_t by_words_wanted, std::vector<KeyframeId>* by_words) {
  const auto beyond = [&](KeyframeId id) {
    const Keyframe* keyframe = map.keyframe(id);
    return !keyframe || (keyframe->T_w_c.translation() - T_w_last.translation()).norm() > reach_m;
  };
  std::vector<KeyframeId> shortlist = map.nearestKeyframes(T_w_last, n / 2);
  shortlist.erase(std::remove_if(shortlist.begin(), shortlist.end(), beyond), shortlist.end());
  if (bag.empty()) return shortlist;
  // Up to n / 2 of the best by words may be among the nearest already.
  const std::vector<BowIndex::Hit> hits = index.query(bag, std::max(n + n / 2, by_words_wanted), beyond);
  for (const BowIndex::Hit& hit : hits) {
    if (by_words && by_words->size() < by_words_wanted) by_words->push_back(hit.image);
    if (shortlist.size() < n && std::find(shortlist.begin(), shortlist.end(), hit.image) == shortlist.end()) {
      shortlist.push_back(hit.image);
    }
  }
  return shortlist;
}

}  // namespace rgbdslam
