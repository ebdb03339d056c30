// Map clean-up: points that bundle adjustment carried off leave the map at once; redundant
// keyframes leave it with their points re-described by other keyframes.
#include "rgbdslam/mapping/map_maintenance.h"

#include <gtest/gtest.h>

namespace rgbdslam {
namespace {

// Keyframe 3 at (1, 0, 0) looking along +z; points 1-5 in it, measured there and in keyframe 4.
Map mapWithPointsAt(const std::vector<Vec3>& positions) {
  Map map;
  for (KeyframeId id : {3, 4}) {
    auto keyframe = std::make_unique<Keyframe>();
    keyframe->id = id;
    keyframe->T_w_c = SE3(Eigen::Quaterniond::Identity(), Vec3(1.0 + 0.1 * (id - 3), 0, 0));
    map.addKeyframe(std::move(keyframe));
  }
  PointId id = 1;
  for (const Vec3& p : positions) {
    map.addPoint(MapPoint(MapPointData{id, p, 3, {320, 240}, 0}));
    for (KeyframeId kf : {3, 4}) map.addMeasurement(kf, Measurement{id, {320, 240}, 0, 0.0});
    ++id;
  }
  return map;
}

TEST(MapMaintenance, PointsBehindOrBeyondTheDepthLimitOfTheirSourceGo) {
  // depths in keyframe 3: 2 m, 999 m, 1001 m, 23 km (as seen on the corridor), behind (-1 m)
  Map map = mapWithPointsAt({Vec3(1, 0, 2), Vec3(1.5, 0, 999), Vec3(1, 0, 1001), Vec3(-3250, -2235, 23460),
                             Vec3(1, 0, -1)});
  const std::vector<PointId> removed = cullDivergedPoints(&map, {1, 2, 3, 4, 5, 99}, 1000.0);
  EXPECT_EQ(removed, (std::vector<PointId>{3, 4, 5}));  // 99 does not exist: ignored
  EXPECT_NE(map.point(1), nullptr);
  EXPECT_NE(map.point(2), nullptr);
  EXPECT_EQ(map.point(4), nullptr);
  EXPECT_EQ(map.keyframe(4)->measurements().count(4), 0u);  // its measurements went with it
  EXPECT_EQ(map.numPoints(), 2u);
}

TEST(MapMaintenance, OnlyTheCandidatesAreJudged) {
  Map map = mapWithPointsAt({Vec3(1, 0, 2), Vec3(1, 0, 5000)});
  EXPECT_TRUE(cullDivergedPoints(&map, {1}, 1000.0).empty());
  EXPECT_EQ(map.numPoints(), 2u);
  EXPECT_EQ(cullDivergedPoints(&map, {2}, 1000.0), (std::vector<PointId>{2}));
}

// Keyframes 0 to count - 1 along x, 0.1 m apart, measuring nothing.
Map keyframesAlongX(int count) {
  Map map;
  for (KeyframeId id = 0; id < count; ++id) {
    auto keyframe = std::make_unique<Keyframe>();
    keyframe->id = id;
    keyframe->T_w_c = SE3(Eigen::Quaterniond::Identity(), Vec3(0.1 * static_cast<double>(id), 0, 0));
    map.addKeyframe(std::move(keyframe));
  }
  return map;
}

// Keyframes 0-5 along x, 0.1 m apart; points 1-100 measured at level 1 in every keyframe but
// keyframe 5, and described by keyframe 2; point 200 seen in keyframe 2 only (its source),
// point 201 in keyframes 2 and 0 (source 2).
Map redundantMap() {
  Map map = keyframesAlongX(6);
  for (PointId pid = 1; pid <= 100; ++pid) {
    map.addPoint(MapPoint(MapPointData{pid, Vec3(0, 0, 2), 2, {100, 100}, 1}));
    for (KeyframeId kf = 0; kf < 5; ++kf) {
      // keyframe 4 at the finest level, keyframe 3 nearer to keyframe 2 but coarser
      const int level = kf == 4 ? 0 : kf == 3 ? 2 : 1;
      map.addMeasurement(kf, Measurement{pid, Eigen::Vector2d(100 + kf, 100), level, 2.0});
    }
  }
  map.addPoint(MapPoint(MapPointData{200, Vec3(0, 0, 3), 2, {50, 50}, 0}));
  map.addMeasurement(2, Measurement{200, {50, 50}, 0, 3.0});
  map.addPoint(MapPoint(MapPointData{201, Vec3(0, 0, 3), 2, {60, 60}, 0}));
  map.addMeasurement(2, Measurement{201, {60, 60}, 0, 3.0});
  map.addMeasurement(0, Measurement{201, {61, 60}, 0, 3.0});
  return map;
}

TEST(KeyframeCulling, ARedundantKeyframeGoesAndItsPointsTakeAnotherPatch) {
  Map map = redundantMap();
  std::set<std::pair<PointId, KeyframeId>> pending{{7, 2}, {7, 3}};
  CullOptions options;
  options.keyframe_cull_min_points = 0;
  options.keyframe_redundant_observers = 3;
  // Keyframe 2: 100 of 102 measurements are also in 3 others at level 1 or finer (0, 1, 4).
  const KeyframeCullResult culled = cullRedundantKeyframes(&map, {2}, options, &pending);
  ASSERT_EQ(culled.removed_keyframes, (std::vector<KeyframeId>{2}));
  EXPECT_FALSE(map.hasKeyframe(2));
  EXPECT_EQ(culled.resourced_points.size(), 100u);
  for (PointId pid = 1; pid <= 100; ++pid) {
    const MapPoint& p = *map.point(pid);
    EXPECT_EQ(p.source_keyframe, 4) << "the finest level wins over the nearer camera";
    EXPECT_EQ(p.source_level, 0);
    EXPECT_EQ(p.source_uv, Eigen::Vector2d(104, 100)) << "the patch where keyframe 4 measured it";
    EXPECT_EQ(map.observers(pid), (std::vector<KeyframeId>{0, 1, 3, 4}));
  }
  // Seen nowhere else: gone. Seen only in keyframe 0 besides: gone too (keyframe 0's points
  // hold the scale in the 2-D modes, so it never takes over a patch).
  EXPECT_EQ(culled.removed_points, (std::vector<PointId>{200, 201}));
  EXPECT_EQ(map.point(200), nullptr);
  EXPECT_EQ(map.point(201), nullptr);
  EXPECT_EQ(map.keyframe(0)->measurements().count(201), 0u);
  EXPECT_EQ(pending, (std::set<std::pair<PointId, KeyframeId>>{{7, 3}})) << "the removed keyframe's outliers go";
}

TEST(KeyframeCulling, KeepsKeyframeZeroAndKeyframesWithTheirOwnPointsOrTooFewPoints) {
  Map map = redundantMap();
  std::set<std::pair<PointId, KeyframeId>> pending;
  CullOptions options;
  options.keyframe_cull_min_points = 0;
  // Keyframe 0 is the gauge; keyframe 5 measures nothing; keyframe 2's points are in only
  // 3 others at its level or finer (keyframe 3 measures them coarser).
  options.keyframe_redundant_observers = 4;
  EXPECT_TRUE(cullRedundantKeyframes(&map, {0, 2, 5}, options, &pending).removed_keyframes.empty());
  options.keyframe_redundant_observers = 0;  // the default in mono and depth-init: no culling
  EXPECT_TRUE(cullRedundantKeyframes(&map, {0, 1, 2, 3, 4, 5}, options, &pending).removed_keyframes.empty());
  options.keyframe_redundant_observers = 3;
  options.keyframe_cull_min_points = 103;  // keyframe 2 measures 102
  EXPECT_TRUE(cullRedundantKeyframes(&map, {0, 2, 5}, options, &pending).removed_keyframes.empty());
  EXPECT_EQ(map.numKeyframes(), 6u);
  // Each removal counts for the next test: once keyframe 2 is gone, keyframe 1's points are
  // in only 0 and 4 at its level or finer (kept); keyframe 3's in 0, 1 and 4 (culled).
  options.keyframe_cull_min_points = 0;
  const KeyframeCullResult culled = cullRedundantKeyframes(&map, {0, 2, 1, 3, 5}, options, &pending);
  EXPECT_EQ(culled.removed_keyframes, (std::vector<KeyframeId>{2, 3}));
  for (KeyframeId id : {0, 1, 4, 5}) EXPECT_TRUE(map.hasKeyframe(id)) << id;
}

// Keyframes 0-4 along a turn: points 1-40 in keyframes 0, 1 and 2, points 41-80 in 2, 3 and 4.
// Keyframe 2 is redundant (each of its points in two others) but the only link between the
// two groups: keyframes 1 and 3 share nothing.
Map chainMap() {
  Map map = keyframesAlongX(5);
  for (PointId pid = 1; pid <= 80; ++pid) {
    const KeyframeId first = pid <= 40 ? 0 : 2;
    map.addPoint(MapPoint(MapPointData{pid, Vec3(0, 0, 2), first + 1, {100, 100}, 0}));
    for (KeyframeId kf = first; kf < first + 3; ++kf) map.addMeasurement(kf, Measurement{pid, {100, 100}, 0, 2.0});
  }
  return map;
}

TEST(KeyframeCulling, KeepsAKeyframeThatHoldsTheChainTogether) {
  std::set<std::pair<PointId, KeyframeId>> pending;
  CullOptions options;
  options.keyframe_cull_min_points = 0;
  options.keyframe_redundant_observers = 2;
  Map map = chainMap();
  EXPECT_TRUE(cullRedundantKeyframes(&map, {2}, options, &pending).removed_keyframes.empty());
  // Keyframe 1 links nothing that keyframes 0 and 2 do not share (points 1-40).
  EXPECT_EQ(cullRedundantKeyframes(&map, {1}, options, &pending).removed_keyframes, (std::vector<KeyframeId>{1}));
  map = chainMap();
  options.keyframe_cull_min_shared = 0;  // off: redundancy alone
  EXPECT_EQ(cullRedundantKeyframes(&map, {2}, options, &pending).removed_keyframes, (std::vector<KeyframeId>{2}));
}

TEST(KeyframeCulling, SaysWhyEachKeyframeStays) {
  CullOptions options;
  options.keyframe_cull_min_age = 1;  // keyframe 4
  options.keyframe_cull_min_points = 0;
  options.keyframe_redundant_observers = 2;
  const Map map = chainMap();
  // Keyframes 1 and 3 are redundant and culling could take either; 2 holds the chain.
  KeyframesKept kept = keyframesKept(map, options);
  EXPECT_EQ(kept.gauge, 1);
  EXPECT_EQ(kept.young, 1);
  EXPECT_EQ(kept.redundant, 2);
  EXPECT_EQ(kept.bridge, 1);
  EXPECT_EQ(kept.few_points + kept.not_redundant, 0);
  options.keyframe_cull_min_points = 41;  // keyframes 1 and 3 measure 40 points, 2 measures 80
  options.keyframe_redundant_observers = 3;
  kept = keyframesKept(map, options);
  EXPECT_EQ(kept.few_points, 2);
  EXPECT_EQ(kept.not_redundant, 1);
  EXPECT_EQ(kept.redundant + kept.bridge, 0);
}

TEST(KeyframeCulling, RemovingAKeyframeTakesItsMeasurementsOnly) {
  Map map = redundantMap();
  map.removeKeyframe(3);
  EXPECT_FALSE(map.hasKeyframe(3));
  EXPECT_EQ(map.observers(1), (std::vector<KeyframeId>{0, 1, 2, 4}));
  EXPECT_EQ(map.numPoints(), 102u);
  EXPECT_EQ(map.point(1)->source_keyframe, 2);
  map.removeKeyframe(99);  // unknown: nothing happens
  EXPECT_EQ(map.numKeyframes(), 5u);
}

}  // namespace
}  // namespace rgbdslam
