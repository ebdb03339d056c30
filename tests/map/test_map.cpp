#include "rgbdslam/map/map.h"

#include <gtest/gtest.h>

namespace rgbdslam {
namespace {

// Three keyframes measuring point 7; keyframe 0 also measures point 8.
Map threeViews() {
  Map map;
  for (KeyframeId id : {0, 1, 2}) {
    auto keyframe = std::make_unique<Keyframe>();
    keyframe->id = id;
    map.addKeyframe(std::move(keyframe));
  }
  for (PointId id : {7, 8}) map.addPoint(MapPoint(MapPointData{id, Vec3(0, 0, 2), 0, {10, 20}, 1}));
  for (KeyframeId kf : {0, 1, 2}) map.addMeasurement(kf, Measurement{7, {10.0 + kf, 20}, 1, 2.0});
  map.addMeasurement(0, Measurement{8, {30, 40}, 0, 1.5});
  return map;
}

TEST(Map, RemovingOneMeasurementKeepsThePointAndTheObserversInStep) {
  Map map = threeViews();
  map.removeMeasurement(1, 7);
  ASSERT_NE(map.point(7), nullptr);
  EXPECT_EQ(map.observers(7), (std::vector<KeyframeId>{0, 2}));
  EXPECT_EQ(map.keyframe(1)->measurements().count(7), 0u);
  EXPECT_EQ(map.keyframe(2)->measurements().at(7).uv.x(), 12.0);
  map.removeMeasurement(1, 7);  // already gone: nothing happens
  map.removeMeasurement(0, 7);
  map.removeMeasurement(2, 7);
  EXPECT_TRUE(map.observers(7).empty());
  EXPECT_NE(map.point(7), nullptr);
  EXPECT_EQ(map.observers(8), (std::vector<KeyframeId>{0}));
}

TEST(Map, RemovingAPointRemovesItsMeasurements) {
  Map map = threeViews();
  map.removePoint(7);
  EXPECT_EQ(map.point(7), nullptr);
  EXPECT_TRUE(map.observers(7).empty());
  for (KeyframeId kf : {0, 1, 2}) EXPECT_EQ(map.keyframe(kf)->measurements().count(7), 0u);
  EXPECT_EQ(map.keyframe(0)->measurements().count(8), 1u);
}

TEST(Map, DepthOfAMeasurementChangesThroughTheMap) {
  Map map = threeViews();
  map.setMeasurementDepth(1, 7, 0.0);
  EXPECT_EQ(map.keyframe(1)->measurements().at(7).depth, 0.0);
  EXPECT_EQ(map.keyframe(0)->measurements().at(7).depth, 2.0);
  map.setMeasurementDepth(1, 8, 3.0);  // not measured there: nothing happens
  EXPECT_EQ(map.keyframe(1)->measurements().count(8), 0u);
}

TEST(Map, MeasurementsOfAnAddedKeyframeAreIndexed) {
  Map map = threeViews();
  KeyframeData data;
  data.id = 3;
  data.grey = cv::Mat(48, 64, CV_8UC1, cv::Scalar(128));
  data.measurements = {Measurement{8, {5, 6}, 0, 0.0}};
  map.addKeyframe(makeKeyframe(data, KeyframeBuildOptions{}));
  EXPECT_EQ(map.observers(8), (std::vector<KeyframeId>{0, 3}));
}

TEST(Map, KeyframesWithinADistanceOfACamera) {
  Map map = threeViews();
  for (KeyframeId id : {0, 1, 2}) map.keyframe(id)->T_w_c = SE3(Mat3::Identity(), Vec3(2.0 * id, 0, 0));
  const SE3 camera(Mat3::Identity(), Vec3(1.0, 0.5, 0));  // 1.12 m from 0 and 1, 3.04 m from 2
  EXPECT_EQ(map.keyframesWithin(camera, 1.2), (std::vector<KeyframeId>{0, 1}));
  EXPECT_EQ(map.keyframesWithin(camera, 1.0), (std::vector<KeyframeId>{}));
  EXPECT_EQ(map.keyframesWithin(camera, 3.1), (std::vector<KeyframeId>{0, 1, 2}));
}

TEST(MapPoint, FromItsMessageDescription) {
  const MapPointData data{provisionalPointId(4, 2), Vec3(1, 2, 3), 4, {100.5, 50.25}, 2};
  const MapPoint point(data);
  EXPECT_EQ(point.id, data.id);
  EXPECT_EQ(point.source_keyframe, 4);
  EXPECT_EQ(point.source_level, 2);
  EXPECT_EQ(point.source_uv, data.uv);
  EXPECT_EQ(point.p_w, data.p_w);
  EXPECT_EQ(point.times_projected, 0);
  EXPECT_EQ(point.data().uv, data.uv);
}

TEST(PointIds, BlocksPerKeyframeWithProvisionalAndMapperHalves) {
  EXPECT_EQ(provisionalPointId(3, 0), 3 * kPointsPerKeyframe);
  EXPECT_EQ(mapperPointId(3, 0), 3 * kPointsPerKeyframe + kPointsPerKeyframe / 2);
  EXPECT_EQ(keyframeOfPoint(provisionalPointId(3, 5)), 3);
  EXPECT_EQ(keyframeOfPoint(mapperPointId(3, 5)), 3);
  EXPECT_TRUE(isProvisionalPointOf(provisionalPointId(3, 5), 3));
  EXPECT_FALSE(isProvisionalPointOf(mapperPointId(3, 0), 3));
  EXPECT_FALSE(isProvisionalPointOf(provisionalPointId(4, 0), 3));
}

}  // namespace
}  // namespace rgbdslam
