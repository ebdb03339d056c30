#include "rgbdslam/tracking/depth_alignment.h"

#include <gtest/gtest.h>

#include <cmath>

#include "plane_world.h"
#include "rgbdslam/map/map.h"
#include "rgbdslam/synth/scene.h"
#include "rgbdslam/tracking/tracker.h"

namespace rgbdslam {
namespace {

// A room corner seen from 2-3 m: back wall, left wall and floor (y down in the camera).
const std::vector<Plane> kCorner = {{Vec3(0, 0, 1), 3.0}, {Vec3(1, 0, 0), -1.2}, {Vec3(0, 1, 0), 1.0}};
const std::vector<Plane> kWall = {{Vec3(0, 0, 1), 2.0}};

Vec6 cornerMotion() {
  Vec6 xi;
  xi << 0.03, -0.02, 0.04, 0.01, -0.015, 0.02;  // 3-4 cm, about 1.5 deg
  return xi;
}

PoseOptimizerResult alignTo(const std::vector<Plane>& planes, const SE3& T_w_c) {
  const PinholeCamera camera = kinectCamera();
  const NoiseModel noise;
  const DepthAlignmentOptions options;
  const std::vector<SurfaceSample> samples = sampleSurface(renderDepth(planes, SE3(), camera), camera, noise, options);
  std::vector<SurfaceAnchor> anchors;
  appendAnchors(samples, SE3(), &anchors);
  const RgbdFrame frame = frameWithDepth(renderDepth(planes, T_w_c, camera));
  const PointToPlaneResiduals residuals(anchors, frame, camera, noise, 0.3, 8.0, options.max_incidence_deg);
  PoseOptimizerOptions pose;
  pose.iterations = 30;
  return optimisePose(camera, SE3(), {}, pose, nullptr, &residuals);
}

TEST(DepthAlignment, SamplesAFlatWallOnTheGrid) {
  const PinholeCamera camera = kinectCamera();
  const DepthAlignmentOptions options;
  const std::vector<SurfaceSample> samples =
      sampleSurface(renderDepth(kWall, SE3(), camera), camera, NoiseModel{}, options);
  // 640 x 480 at 16 px: 40 x 30 cells, all flat (edges of the image included: the fit
  // takes the readings that are inside).
  EXPECT_EQ(samples.size(), 1200u);
  for (const SurfaceSample& s : samples) {
    EXPECT_NEAR(s.p.z(), 2.0, 1e-4);
    EXPECT_NEAR(s.n.z(), -1.0, 1e-4);  // towards the camera
    EXPECT_GT(s.sigma, 0.f);
  }
}

TEST(DepthAlignment, NoSampleAcrossADepthEdge) {
  const PinholeCamera camera = kinectCamera();
  cv::Mat depth(camera.height, camera.width, CV_32FC1, cv::Scalar(1.5));
  depth.colRange(320, camera.width).setTo(2.5);  // a step of 1 m at column 320
  const std::vector<SurfaceSample> samples = sampleSurface(depth, camera, NoiseModel{}, DepthAlignmentOptions{});
  ASSERT_FALSE(samples.empty());
  for (const SurfaceSample& s : samples) {
    const double u = camera.fx * s.p.x() / s.p.z() + camera.cx;
    EXPECT_GT(std::abs(u - 319.5), 6.0) << "a sample straddles the edge at u = " << u;
  }
  // Surfaces seen more obliquely than max_incidence_deg give none: a floor 0.3 m below a
  // camera looking along it is seen at 75-90 deg in the upper two thirds of the image.
  const DepthAlignmentOptions options;
  const std::vector<Plane> floor_plane = {{Vec3(0, 1, 0), 0.3}};
  const std::vector<SurfaceSample> floor =
      sampleSurface(renderDepth(floor_plane, SE3(), camera), camera, NoiseModel{}, options);
  ASSERT_FALSE(floor.empty());
  const double min_cos = std::cos(options.max_incidence_deg * M_PI / 180.0);
  for (const SurfaceSample& s : floor) {
    EXPECT_GE(-s.n.cast<double>().dot(s.p.cast<double>().normalized()), min_cos - 1e-6);
    EXPECT_GT(camera.fy * s.p.y() / s.p.z() + camera.cy, 239.5 + 0.25 * camera.fy) << "a sample near the horizon";
  }
}

TEST(DepthAlignment, ACornerFixesTheWholePose) {
  const SE3 T_w_c = SE3::exp(cornerMotion());
  const PoseOptimizerResult fit = alignTo(kCorner, T_w_c);
  ASSERT_TRUE(fit.ok);
  const SE3 error = fit.T_c_w * T_w_c;  // identity when right
  EXPECT_LT(error.translation().norm(), 2e-3);  // depth stored in 0.2 mm units
  EXPECT_LT(error.log().tail<3>().norm() * 180.0 / M_PI, 0.05);
  const PoseUncertainty u = poseUncertainty(fit.information);
  EXPECT_LT(u.translation_m, 0.01);
  EXPECT_LT(u.rotation_rad, 0.01);
}

TEST(DepthAlignment, OnePlaneFixesOnlyDistanceAndTilt) {
  const SE3 T_w_c = SE3::exp(cornerMotion());
  const PoseOptimizerResult fit = alignTo(kWall, T_w_c);
  ASSERT_TRUE(fit.ok);
  const SE3 error = fit.T_c_w * T_w_c;
  // The wall's distance along its normal (world z) and its tilts are found...
  const Vec3 camera_position = fit.T_c_w.inverse().translation();
  EXPECT_NEAR(camera_position.z(), T_w_c.translation().z(), 1e-3);
  // ...the slide along it and the turn about its normal are not: the fit leaves them at
  // the start (the identity) and says so in its uncertainty.
  EXPECT_NEAR(camera_position.x(), 0.0, 1e-3);
  EXPECT_GT(error.translation().norm(), 0.02);
  EXPECT_TRUE(std::isinf(poseUncertainty(fit.information).translation_m) ||
              poseUncertainty(fit.information).translation_m > 1.0);
}

// The room with the lights out: from frame 60 the image is black (no corners at all) while
// the depth camera, which brings its own infrared light, sees as before. Depth must hold
// the pose, and the tracker must say that vision does not (dodgy, depth-aided).
struct DarkRoomRun {
  int posed = 0, depth_aided = 0, reported_good = 0;
  double max_error_m = 0.0;
};

DarkRoomRun runDarkRoom(bool depth_align) {
  const SyntheticScene room(*parseSyntheticSpec("room,frames=150"));
  TrackerOptions options;
  options.depth_align.enabled = depth_align;
  Tracker tracker(room.camera(), options, SlamMode::kDepthBa, 1);
  DarkRoomRun run;
  const SE3 T_c0_w = room.groundTruthPose(0).inverse();
  for (size_t i = 0; i < room.numFrames(); ++i) {
    RgbdFrame frame = room.render(i);
    if (i < 60) {
      tracker.track(frame);
      continue;
    }
    frame.colour.setTo(cv::Scalar(6, 6, 6));
    const TrackResult result = tracker.track(frame);
    if (result.status != TrackResult::Status::kTracked) continue;
    ++run.posed;
    run.depth_aided += result.depth_aided;
    run.reported_good += result.pose.state == TrackingState::kTracking;
    const SE3 truth = T_c0_w * room.groundTruthPose(i);
    run.max_error_m = std::max(run.max_error_m, (truth.translation() - result.pose.T_w_c.translation()).norm());
  }
  return run;
}

TEST(DepthAlignment, HoldsThePoseInTheDarkRoom) {
  const DarkRoomRun with = runDarkRoom(true);
  // Depth alone holds it for a while (measured: 52 frames within 3.5 cm; without the depth
  // reference 47 frames within 5.1 cm: no keyframe is added in the dark, so the two aligned
  // against are those from before the lights went);
  // where the surfaces in view stop fixing it the tracker says lost rather than slide.
  EXPECT_GE(with.posed, 40);
  EXPECT_EQ(with.depth_aided, with.posed);
  EXPECT_EQ(with.reported_good, 0);  // dodgy: vision did not hold it
  EXPECT_LT(with.max_error_m, 0.06);  // measured 5.1 cm, within the pose sigma it reports
  const DarkRoomRun without = runDarkRoom(false);
  EXPECT_EQ(without.posed, 0);  // lost at once: no point can be found in a black image
}

// The office's plain walls, corners and a box (synth:office without sensor effects): from
// frame ~250 the camera sees no corner to find, only planes. The keyframes' surfaces hold
// the pose until the camera has moved past their view; the depth reference (a depth-aided
// frame's own surfaces) holds it on while the planes in view fix it.
struct OfficeRun {
  int posed = 0, posed_late = 0, reported_good_aided = 0;
  double max_error_m = 0.0, max_error_early_m = 0.0;
};

TEST(DepthAlignment, TheReferenceHoldsThePoseWhereTheKeyframesLeftTheView) {
  // Without a reference: lost for good at 252-271 (at 301 since the motion prior, 2026-11-27).
  constexpr size_t kFrames = 420, kLate = 300;
  const SyntheticScene office(*parseSyntheticSpec("office,effects=none,frames=420"));
  TrackerOptions with_options, without_options;
  without_options.depth_align.reference_step_m = 0.0;
  Tracker with(office.camera(), with_options, SlamMode::kDepthBa, 1);
  Tracker without(office.camera(), without_options, SlamMode::kDepthBa, 1);
  OfficeRun runs[2];
  const SE3 T_c0_w = office.groundTruthPose(0).inverse();
  for (size_t i = 0; i < std::min(kFrames, office.numFrames()); ++i) {
    const RgbdFrame frame = office.render(i);
    const SE3 truth = T_c0_w * office.groundTruthPose(i);
    for (int k = 0; k < 2; ++k) {
      const TrackResult result = (k == 0 ? with : without).track(frame);
      if (result.status != TrackResult::Status::kTracked) continue;
      OfficeRun& run = runs[k];
      ++run.posed;
      run.posed_late += i >= kLate;
      run.reported_good_aided += result.depth_aided && result.pose.state == TrackingState::kTracking;
      const double error = (truth.translation() - result.pose.T_w_c.translation()).norm();
      run.max_error_m = std::max(run.max_error_m, error);
      if (i < kLate) run.max_error_early_m = std::max(run.max_error_early_m, error);
    }
  }

  printf("with the reference: %d posed, %d from frame %zu, largest error %.4f m (%.4f m before)\n"
         "without: %d posed, %d from frame %zu, largest error %.4f m\n",
         runs[0].posed, runs[0].posed_late, kLate, runs[0].max_error_m, runs[0].max_error_early_m,
         runs[1].posed, runs[1].posed_late, kLate, runs[1].max_error_m);
  EXPECT_LT(runs[1].posed_late, 10);  // the keyframes' surfaces alone lose it
  EXPECT_EQ(runs[0].posed_late, static_cast<int>(kFrames - kLate));
  EXPECT_EQ(runs[0].reported_good_aided, 0);  // dodgy: vision did not hold it
  // The same frames as without up to frame 252; then drift of depth odometry, no jump.
  // Measured (a tracker without the mapper's bundle adjustment): 5.76 cm by frame 300 with
  // and without, 6.96 cm by frame 420 with the reference.
  EXPECT_LT(runs[0].max_error_m, runs[0].max_error_early_m + 0.02);
}

}  // namespace
}  // namespace rgbdslam
