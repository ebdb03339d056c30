// The photometric integrity check on the rendered room: a keyframe's points, found in a later
// frame by the tracker's own search from the true pose, are checked where a pose puts them.
#include "rgbdslam/tracking/photometric_integrity.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "rgbdslam/image/corners.h"
#include "rgbdslam/synth/scene.h"
#include "rgbdslam/tracking/map_replica.h"

namespace rgbdslam {
namespace {

class PhotometricCheck : public ::testing::Test {
 protected:
  void SetUp() override {
    const SyntheticScene scene(*parseSyntheticSpec("room,frames=30"));
    camera = scene.camera();
    replica = std::make_unique<MapReplica>(camera);
    // Keyframe 0 at frame 0; its points at level-0 FAST maxima, placed by the rendered depth.
    const RgbdFrame key_frame = scene.render(0);
    KeyframeData data;
    data.id = 0;
    data.T_w_c = scene.groundTruthPose(0);
    cv::cvtColor(key_frame.colour, data.grey, cv::COLOR_BGR2GRAY);
    std::unique_ptr<Keyframe> keyframe = makeKeyframe(data, KeyframeBuildOptions{});
    std::vector<Eigen::Vector2d> pixels;
    for (const cv::Point2i& p : keyframe->corners[0].maxima) pixels.emplace_back(p.x, p.y);
    replica->addKeyframe(std::move(keyframe));
    PointId id = 0;
    for (size_t i = 0; i < pixels.size(); i += 4) {
      const uint16_t raw = key_frame.depth.at<uint16_t>(static_cast<int>(pixels[i].y()), static_cast<int>(pixels[i].x()));
      if (raw == 0) continue;
      const Vec3 p_w = data.T_w_c * camera.unproject(pixels[i], raw / key_frame.depth_scale);
      NewPoint point;
      point.point = MapPoint(MapPointData{id, p_w, 0, pixels[i], 0});
      point.measurement = Measurement{id, pixels[i], 0, raw / key_frame.depth_scale};
      replica->addProvisionalPoint(point);
      ++id;
    }
    // Frame 10, searched from its true pose as the tracker's fine stage does.
    const RgbdFrame frame = scene.render(10);
    cv::cvtColor(frame.colour, grey, cv::COLOR_BGR2GRAY);
    pyramid = buildPyramid(grey);
    std::vector<LevelCorners> corners;
    detectPyramidCorners(pyramid, CornerOptions{}, false, &corners);
    T_c_w = scene.groundTruthPose(10).inverse();
    std::vector<KeyframeView> views;
    makeKeyframeViews(replica->map(), T_c_w, &views);
    for (PointSlot& slot : replica->slots()) {
      if (projectPoint(camera, T_c_w, views, ProjectionOptions{}, &slot) && ensurePatch(&slot, 0.05)) {
        slots.push_back(&slot);
      }
    }
    found = searchPoints(slots, pyramid, corners, 4, search);
  }

  PhotometricIntegrity check(const SE3& pose) const {
    return checkPhotometricIntegrity(slots, pose, pyramid, camera, search, PhotometricIntegrityOptions{});
  }

  PinholeCamera camera;
  std::unique_ptr<MapReplica> replica;
  cv::Mat grey;
  ImagePyramid pyramid;
  SE3 T_c_w;
  std::vector<PointSlot*> slots;
  PointSearchOptions search;
  int found = 0;
};

TEST_F(PhotometricCheck, TheTruePoseAgreesAPoseCentimetresOffDoesNot) {
  ASSERT_GT(found, 100);
  const PhotometricIntegrity right = check(T_c_w);
  EXPECT_TRUE(right.judged);
  EXPECT_TRUE(right.consistent);
  EXPECT_GT(right.checked, 100);
  EXPECT_LT(right.mismatchRatio(), 0.05);
  // The room's walls are 2-4 m away (f = 525 px): 2 cm sideways moves the patches 3-5 px,
  // half a degree of yaw 4.6 px; both are rejected where the pose puts them.
  const PhotometricIntegrity sideways = check(SE3(Mat3::Identity(), Vec3(0.02, 0, 0)) * T_c_w);
  EXPECT_FALSE(sideways.consistent);
  EXPECT_GT(sideways.mismatchRatio(), 0.5);
  EXPECT_NE(sideways.describe().find("do not match where the pose puts them"), std::string::npos);
  const SE3 yawed(Eigen::AngleAxisd(0.5 * M_PI / 180.0, Vec3::UnitY()).toRotationMatrix(), Vec3::Zero());
  EXPECT_FALSE(check(yawed * T_c_w).consistent);
}

TEST_F(PhotometricCheck, NoVerdictOnTooFewPatchesOrWhenOff) {
  const SE3 off = SE3(Mat3::Identity(), Vec3(0.05, 0, 0)) * T_c_w;
  PhotometricIntegrityOptions options;
  EXPECT_FALSE(checkPhotometricIntegrity(slots, off, pyramid, camera, search, options).consistent);
  std::vector<PointSlot*> few_slots;
  for (PointSlot* slot : slots) {
    if (slot->found && few_slots.size() < 10) few_slots.push_back(slot);
  }
  const PhotometricIntegrity few = checkPhotometricIntegrity(few_slots, off, pyramid, camera, search, options);
  EXPECT_EQ(few.checked, 10);
  EXPECT_FALSE(few.judged);
  EXPECT_TRUE(few.consistent);
  options.enabled = false;
  const PhotometricIntegrity off_check = checkPhotometricIntegrity(slots, off, pyramid, camera, search, options);
  EXPECT_TRUE(off_check.consistent);
  EXPECT_EQ(off_check.checked, 0) << "no work when off";
}

}  // namespace
}  // namespace rgbdslam
