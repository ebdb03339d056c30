#include "rgbdslam/map/map_diff.h"

#include <gtest/gtest.h>

namespace rgbdslam {
namespace {

// A map with two keyframes (blank images: only poses matter here) and three points.
Map makeMap() {
  Map map;
  for (KeyframeId id : {0, 1}) {
    KeyframeData data;
    data.id = id;
    data.grey = cv::Mat(48, 64, CV_8UC1, cv::Scalar(128));
    data.T_w_c = SE3(Eigen::Quaterniond::Identity(), Vec3(0.1 * id, 0, 0));
    map.addKeyframe(makeKeyframe(data, KeyframeBuildOptions{}));
  }
  for (PointId id : {1, 2, 3}) {
    MapPoint p;
    p.id = id;
    p.p_w = Vec3(0, 0, 1.0 + id);
    p.source_keyframe = 0;
    map.addPoint(p);
  }
  return map;
}

TEST(MapDiffer, SnapshotHoldsEverythingAndAnUnchangedMapGivesAnEmptyDelta) {
  Map map = makeMap();
  MapDiffer differ;
  MapUpdate snapshot = differ.snapshot(map);
  EXPECT_TRUE(snapshot.is_snapshot);
  EXPECT_EQ(snapshot.keyframes.size(), 2u);
  EXPECT_EQ(snapshot.points.size(), 3u);
  MapChanges touched;  // reported changed, but nothing moved
  touched.points = {1, 2, 3};
  touched.keyframes = {0, 1};
  MapUpdate delta = differ.delta(map, touched);
  EXPECT_FALSE(delta.is_snapshot);
  EXPECT_TRUE(delta.keyframes.empty() && delta.points.empty() && delta.moved_points.empty() &&
              delta.removed_points.empty());
}

TEST(MapDiffer, SendsMovesAboveTheThresholdNewPointsAndRemovals) {
  Map map = makeMap();
  MapDiffer differ;  // 1 mm
  differ.snapshot(map);
  map.point(1)->p_w.x() += 0.0005;  // below: not sent
  map.point(2)->p_w.x() += 0.002;   // above: sent
  map.removePoint(3);
  MapPoint p;
  p.id = 4;
  p.source_keyframe = 1;
  map.addPoint(p);
  map.keyframe(1)->T_w_c = SE3(Eigen::Quaterniond::Identity(), Vec3(0.1, 0.01, 0));
  MapChanges changes;
  changes.points = {1, 2, 4};
  changes.removed_points = {3};
  changes.keyframes = {0, 1};
  MapUpdate delta = differ.delta(map, changes);
  ASSERT_EQ(delta.points.size(), 1u);  // the new one, in full
  EXPECT_EQ(delta.points[0].id, 4);
  ASSERT_EQ(delta.moved_points.size(), 1u);  // the moved one, position only
  EXPECT_EQ(delta.moved_points[0].id, 2);
  EXPECT_DOUBLE_EQ(delta.moved_points[0].p_w.x(), map.point(2)->p_w.x());
  ASSERT_EQ(delta.removed_points.size(), 1u);
  EXPECT_EQ(delta.removed_points[0], 3);
  ASSERT_EQ(delta.keyframes.size(), 1u);
  EXPECT_EQ(delta.keyframes[0].id, 1);
}

TEST(MapDiffer, SlowDriftAccumulatesUntilItCrossesTheThreshold) {
  Map map = makeMap();
  MapDiffer differ;
  differ.snapshot(map);
  for (int step = 1; step <= 3; ++step) {
    map.point(1)->p_w.x() += 0.0004;  // 0.4, 0.8, 1.2 mm from the published position
    MapChanges changes;
    changes.points = {1};
    MapUpdate delta = differ.delta(map, changes);
    EXPECT_EQ(delta.moved_points.size(), step == 3 ? 1u : 0u) << "step " << step;
  }
}

TEST(MapDiffer, AnnouncesEveryRemovalAndSkipsPointsAddedAndRemovedSincePublished) {
  Map map = makeMap();
  MapDiffer differ;
  differ.snapshot(map);
  MapPoint p;
  p.id = 7;  // a point the tracker may hold (provisional), never published
  p.source_keyframe = 1;
  map.addPoint(p);
  map.removePoint(7);
  MapChanges changes;
  changes.removed_points = {7};
  MapUpdate delta = differ.delta(map, changes);
  EXPECT_TRUE(delta.points.empty());
  ASSERT_EQ(delta.removed_points.size(), 1u);
  EXPECT_EQ(delta.removed_points[0], 7);
}

// A keyframe culled: listed as removed; a point it described, re-described by another
// keyframe, goes in full again (the tracker needs the new patch), not as a move.
TEST(MapDiffer, SendsCulledKeyframesAndReDescribedPointsInFull) {
  Map map = makeMap();
  MapDiffer differ;
  differ.snapshot(map);
  map.point(2)->source_keyframe = 1;
  map.point(2)->source_uv = Eigen::Vector2d(7, 8);
  map.removeKeyframe(0);
  MapChanges changes;
  changes.points = {2};
  changes.removed_keyframes = {0};
  const MapUpdate delta = differ.delta(map, changes);
  ASSERT_EQ(delta.points.size(), 1u);
  EXPECT_EQ(delta.points[0].source_keyframe, 1);
  EXPECT_EQ(delta.points[0].uv, Eigen::Vector2d(7, 8));
  EXPECT_TRUE(delta.moved_points.empty());
  EXPECT_EQ(delta.removed_keyframes, (std::vector<KeyframeId>{0}));
  const MapUpdate snapshot = differ.snapshot(map);
  ASSERT_EQ(snapshot.keyframes.size(), 1u) << "a snapshot holds the keyframes that are left";
  EXPECT_EQ(snapshot.keyframes[0].id, 1);
  EXPECT_EQ(snapshot.removed_keyframes, (std::vector<KeyframeId>{0})) << "every keyframe culled so far";
}

TEST(MapChanges, MergeKeepsTheLaterOfAnAdditionAndARemoval) {
  MapChanges a, b;
  a.points = {1, 2};
  b.removed_points = {2};
  b.points = {3};
  a.merge(b);
  EXPECT_EQ(a.points, (std::set<PointId>{1, 3}));
  EXPECT_EQ(a.removed_points, (std::set<PointId>{2}));
  MapChanges c;
  c.points = {2};  // re-added after removal
  a.merge(c);
  EXPECT_TRUE(a.points.count(2));
  EXPECT_FALSE(a.removed_points.count(2));
  MapChanges d;
  d.removed_keyframes = {4};
  a.keyframes = {4, 5};
  a.merge(d);
  EXPECT_EQ(a.keyframes, (std::set<KeyframeId>{5})) << "a culled keyframe's pose is not sent";
  EXPECT_EQ(a.removed_keyframes, (std::set<KeyframeId>{4}));
  EXPECT_FALSE(d.empty());
}

}  // namespace
}  // namespace rgbdslam
