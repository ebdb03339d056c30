#include "rgbdslam/tracking/relocaliser.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>
#include <opencv2/imgproc.hpp>

#include "rgbdslam/synth/scene.h"

namespace rgbdslam {
namespace {

const SyntheticScene& rankingRoom() {
  static const SyntheticScene scene(*parseSyntheticSpec("room,frames=400"));
  return scene;
}

SmallBlurryImage sbiOfFrame(size_t i) {
  cv::Mat grey;
  cv::cvtColor(rankingRoom().render(i).colour, grey, cv::COLOR_BGR2GRAY);
  return makeSmallBlurryImage(buildPyramid(grey));
}

// Keyframes every 20 frames of the room's turn, their SBIs compact as the replica keeps them.
const Map& roomKeyframes() {
  static const Map map = [] {
  Map map;
  for (size_t i = 0; i < 400; i += 20) {
    auto keyframe = std::make_unique<Keyframe>();
    keyframe->id = static_cast<KeyframeId>(i / 20);
    keyframe->T_w_c = rankingRoom().groundTruthPose(i);
    keyframe->sbi = sbiOfFrame(i);
    compactSmallBlurryImage(&keyframe->sbi);
    map.addKeyframe(std::move(keyframe));
  }
  return map;
  }();
  return map;
}

double degreesBetween(const SE3& a, const SE3& b) {
  return logSO3(a.rotationMatrix().transpose() * b.rotationMatrix()).norm() * 180.0 / M_PI;
}

// Ranked coarse to fine (20 keyframes, 2 wanted: 4 refined at full resolution), the best
// candidates are those of the full-resolution ranking (n = 20 refines all), with the same
// poses; a view between keyframes 5 and 6 (frames 100 and 120) finds one of them, its
// candidate pose turned towards the view's.
TEST(Relocaliser, RanksCoarseToFineAsAtFullResolution) {
  const Map& map = roomKeyframes();
  const SmallBlurryImage query = sbiOfFrame(108);
  const std::vector<RelocalisationCandidate> coarse = relocalisationCandidates(map, query, rankingRoom().camera(), 2);
  const std::vector<RelocalisationCandidate> full = relocalisationCandidates(map, query, rankingRoom().camera(), 20);
  ASSERT_EQ(coarse.size(), 2u);
  ASSERT_EQ(full.size(), 20u);
  for (size_t k = 0; k < coarse.size(); ++k) {
    EXPECT_EQ(coarse[k].keyframe, full[k].keyframe) << k;
    EXPECT_NEAR(coarse[k].score, full[k].score, 1e-3 * full[k].score) << k;
    EXPECT_LT(degreesBetween(coarse[k].T_w_c, full[k].T_w_c), 0.05) << k;
  }
  EXPECT_TRUE(coarse[0].keyframe == 5 || coarse[0].keyframe == 6) << coarse[0].keyframe;
  const SE3 truth = rankingRoom().groundTruthPose(108);
  const SE3 keyframe_pose = map.keyframe(coarse[0].keyframe)->T_w_c;
  EXPECT_LT(degreesBetween(coarse[0].T_w_c, truth), 0.5 * degreesBetween(keyframe_pose, truth));
}

// Where no more than two keyframes per candidate are ranked, each is aligned from the
// identity at full resolution, as before the coarse stage: the scores are exactly those.
TEST(Relocaliser, RanksFewKeyframesAtFullResolutionOnly) {
  const Map& map = roomKeyframes();
  const SmallBlurryImage query = sbiOfFrame(108);
  const std::vector<KeyframeId> among = {3, 4, 5, 6, 7, 8};  // 6 ranked, 3 wanted: 6 refined
  const std::vector<RelocalisationCandidate> ranked =
      relocalisationCandidates(map, query, rankingRoom().camera(), 3, &among);
  ASSERT_EQ(ranked.size(), 3u);
  for (const RelocalisationCandidate& candidate : ranked) {
    SmallBlurryImage sbi = map.keyframe(candidate.keyframe)->sbi;
    restoreSmallBlurryImage(&sbi);
    double error = -1.0;
    alignSmallBlurryImages(sbi, query, kSbiAlignIterations, &error);
    EXPECT_EQ(candidate.score, error) << candidate.keyframe;
  }
}

// Only the keyframes named are ranked; ids not in the map are skipped.
TEST(Relocaliser, RanksOnlyTheShortlist) {
  const Map& map = roomKeyframes();
  const std::vector<KeyframeId> among = {0, 1, 2, 3, 4, 7, 8, 9, 10, 11, 99};
  const std::vector<RelocalisationCandidate> ranked =
      relocalisationCandidates(map, sbiOfFrame(108), rankingRoom().camera(), 2, &among);
  ASSERT_EQ(ranked.size(), 2u);
  for (const RelocalisationCandidate& candidate : ranked) {
    EXPECT_NE(std::find(among.begin(), among.end() - 1, candidate.keyframe), among.end() - 1);
  }
}

// A shortlist for one part (a rejoin: where the camera was lost is known in that part's
// frame only) holds that part's keyframes alone, within the reach; without a part the
// nearest keyframes of any part come in.
TEST(Relocaliser, ShortlistsOnePartWithinTheReach) {
  Map map;
  for (size_t i = 0; i < 400; i += 20) {
    auto keyframe = std::make_unique<Keyframe>();
    keyframe->id = static_cast<KeyframeId>(i / 20);
    keyframe->part = keyframe->id < 10 ? 0 : 10;  // a second part from keyframe 10 on
    keyframe->T_w_c = rankingRoom().groundTruthPose(i);
    map.addKeyframe(std::move(keyframe));
  }
  // The 5 nearest to keyframe 12 are all in part 10: the part's own nearest must be sought.
  const SE3 lost_at = map.keyframe(12)->T_w_c;
  const BowIndex no_words;
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<KeyframeId> any = relocalisationShortlist(map, no_words, BowVector{}, lost_at, inf, 10, 4, nullptr);
  ASSERT_FALSE(any.empty());
  EXPECT_TRUE(std::all_of(any.begin(), any.end(), [](KeyframeId id) { return id >= 10; })) << "the control";
  const std::vector<KeyframeId> in_part =
      relocalisationShortlist(map, no_words, BowVector{}, lost_at, inf, 10, 4, nullptr, KeyframeId{0});
  ASSERT_FALSE(in_part.empty());
  for (KeyframeId id : in_part) EXPECT_LT(id, 10) << "keyframe " << id << " is in part 10";
  // Within 0.3 m of keyframe 3's pose: keyframes near it only.
  const SE3 near3 = map.keyframe(3)->T_w_c;
  for (KeyframeId id : relocalisationShortlist(map, no_words, BowVector{}, near3, 0.3, 30, 4, nullptr, KeyframeId{0})) {
    EXPECT_LE((map.keyframe(id)->T_w_c.translation() - near3.translation()).norm(), 0.3) << "keyframe " << id;
  }
}

}  // namespace
}  // namespace rgbdslam
