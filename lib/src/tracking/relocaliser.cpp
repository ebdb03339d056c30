#include "rgbdslam/tracking/relocaliser.h"

#include <algorithm>

namespace rgbdslam {

namespace {

// Above this many keyframes per candidate wanted, the ranking is coarse to fine: all are
// aligned at half the SBI's resolution, and only this many per candidate at full
// resolution, from the coarse warp. (The margin: the halved SBIs' ranking may swap close
// neighbours; the full resolution's error decides among them.)
constexpr size_t kRefinedPerCandidate = 2;

struct Ranked {
  KeyframeId id = -1;
  const Keyframe* keyframe = nullptr;
  double error = 0.0;  // the coarse stage's [grey^2]
  Se2 start;           // where the full-resolution alignment starts
};

}  // namespace

std::vector<RelocalisationCandidate> relocalisationCandidates(const Map& map,
                                                              const SmallBlurryImage& sbi,
                                                              const PinholeCamera& camera,
                                                              int n,
                                                              const std::vector<KeyframeId>* among) {
  std::vector<Ranked> ranked;
  const auto consider = [&](KeyframeId id, const Keyframe* keyframe) {
    if (keyframe && keyframe->sbi.image.size() == sbi.image.size()) ranked.push_back({id, keyframe, 0.0, Se2{}});
  };
  if (among) {
    for (KeyframeId id : *among) consider(id, map.keyframe(id));
  } else {
    for (const auto& [id, keyframe] : map.keyframes()) consider(id, keyframe.get());
  }
  const size_t keep = std::min(ranked.size(), static_cast<size_t>(std::max(n, 0)));
  if (keep == 0) return {};
  const size_t refined = kRefinedPerCandidate * keep;
  if (ranked.size() > refined) {
    const SmallBlurryImage sbi_half = halveSmallBlurryImage(sbi);
    for (Ranked& r : ranked) {
      const Se2 se2 = alignSmallBlurryImages(halveSmallBlurryImage(r.keyframe->sbi), sbi_half, kSbiAlignIterations,
                                             &r.error);
      r.start = fullResolutionSe2(se2, sbi.image.size());
    }
    std::partial_sort(ranked.begin(), ranked.begin() + static_cast<std::ptrdiff_t>(refined), ranked.end(),
                      [](const Ranked& a, const Ranked& b) { return a.error < b.error; });
    ranked.resize(refined);
  }
  std::vector<RelocalisationCandidate> candidates;
  for (const Ranked& r : ranked) {
    SmallBlurryImage restored;  // the replica keeps its keyframes' SBIs compact (map_replica.h)
    if (!r.keyframe->sbi.complete()) {
      restored.image = r.keyframe->sbi.image;  // shared, not copied
      restored.scale = r.keyframe->sbi.scale;
      restoreSmallBlurryImage(&restored);
    }
    const SmallBlurryImage& from = r.keyframe->sbi.complete() ? r.keyframe->sbi : restored;
    // Rank by the error left after the SE(2) alignment: the plain ZMSSD of two views a few
    // degrees apart is dominated by the shift and ranks unrelated views alike.
    double error = 0.0;
    const Se2 se2 = alignSmallBlurryImages(from, sbi, kSbiAlignIterations, &error, r.start);
    candidates.push_back({r.id, error, r.keyframe->T_w_c * rotationFromSe2(se2, camera, sbi.scale)});
  }
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
                                                size_t by_words_wanted, std::vector<KeyframeId>* by_words,
                                                std::optional<KeyframeId> part) {
  const auto beyond = [&](KeyframeId id) {
    const Keyframe* keyframe = map.keyframe(id);
    return !keyframe || (part && keyframe->part != *part) ||
           (keyframe->T_w_c.translation() - T_w_last.translation()).norm() > reach_m;
  };
  std::vector<KeyframeId> shortlist =
      part ? map.nearestKeyframesInPart(T_w_last, n / 2, *part) : map.nearestKeyframes(T_w_last, n / 2);
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
