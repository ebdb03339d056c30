// Map clean-up: points that bundle adjustment carried off leave the map at once.
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

}  // namespace
}  // namespace rgbdslam
