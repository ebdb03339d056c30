#include "rgbdslam/tracking/depth_dead_reckoning.h"

#include <gtest/gtest.h>

#include <cmath>

#include "plane_world.h"
#include "rgbdslam/tracking/tracker.h"

namespace rgbdslam {
namespace {

// A room 4 m wide and 6 m long around the camera: walls, floor 1 m below, ceiling (y down).
const std::vector<Plane> kRoom = {{Vec3(0, 0, 1), 3.0},  {Vec3(0, 0, 1), -3.0}, {Vec3(1, 0, 0), -2.0},
                                  {Vec3(1, 0, 0), 2.0},  {Vec3(0, 1, 0), 1.0},  {Vec3(0, 1, 0), -1.5}};
// A corridor along z without an end in view: nothing in the depth fixes the slide along it.
const std::vector<Plane> kCorridor = {{Vec3(1, 0, 0), -1.0}, {Vec3(1, 0, 0), 1.0}, {Vec3(0, 1, 0), 1.0},
                                      {Vec3(0, 1, 0), -1.5}};

constexpr double kFrameS = 1.0 / 30.0;
constexpr int64_t kStartUtime = 1000000;
constexpr double kCoastS = 1.0;  // how long past the last frame held the guess may coast

int64_t utimeOf(int k) { return kStartUtime + static_cast<int64_t>(std::llround(k * kFrameS * 1e6)); }

// Frame k's camera (T_w_c): 0.6 m/s forward up to the loss at k = 0, then a stop within
// 0.5 s and a turn about the vertical speeding up to 0.4 rad/s: what the velocity at the
// loss does not foresee.
SE3 truthAt(int k) {
  const double t = k * kFrameS;
  double z = 0.6 * t, yaw = 0.0;
  if (t > 0.0) {
    const double ramp = std::min(t, 0.5);
    z = 0.6 * ramp - 0.6 * ramp * ramp;  // decelerating at 1.2 m/s^2: 0.15 m at 0.5 s
    yaw = 0.4 * ramp * ramp + 0.4 * std::max(0.0, t - 0.5);
  }
  return SE3(Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Vec3::UnitY())), Vec3(0.0, 0.0, z));
}

RgbdFrame frameAt(const std::vector<Plane>& world, int k, const SE3& T_w_c) {
  RgbdFrame frame = frameWithDepth(renderDepth(world, T_w_c, kinectCamera()));
  frame.utime = utimeOf(k);
  return frame;
}

// The tracker's motion prior at the loss: ten frames tracked along 'path' up to frame 0.
MotionPrior priorAtTheLoss(SE3 (*path)(int) = truthAt) {
  MotionPrior prior;
  for (int k = -10; k <= 0; ++k) prior.update(utimeOf(k), path(k).inverse(), 1e6 * Mat6::Identity());
  return prior;
}

DepthDeadReckoning makeReckoning() {
  const TrackerOptions tracker;
  return DepthDeadReckoning(kinectCamera(), DepthAlignmentOptions{}, PoseOptimizerOptions{}, 0.3, 8.0,
                            tracker.relocalise_reckoning_sigma_m, tracker.relocalise_reckoning_sigma_deg * M_PI / 180.0);
}

// The surfaces of a keyframe made at the loss's pose (in a world moved by T_new_old), as
// the tracker passes the nearest.
std::vector<SurfaceAnchor> keyframeAnchors(const std::vector<Plane>& world = kRoom, const SE3& T_w_k = truthAt(0),
                                           const SE3& T_new_old = SE3()) {
  std::vector<SurfaceAnchor> anchors;
  appendAnchors(sampleSurface(renderDepth(world, T_w_k, kinectCamera()), kinectCamera(), NoiseModel{},
                              DepthAlignmentOptions{}),
                T_new_old * T_w_k, &anchors);
  return anchors;
}

double metresOff(const SE3& T_c_w, const SE3& truth_w_c) {
  return (T_c_w.inverse().translation() - truth_w_c.translation()).norm();
}
double degreesOff(const SE3& T_c_w, const SE3& truth_w_c) {
  return (T_c_w * truth_w_c).log().tail<3>().norm() * 180.0 / M_PI;
}

TEST(DepthDeadReckoning, FollowsAStopAndATurnThatTheVelocityDoesNotForesee) {
  DepthDeadReckoning reckoning = makeReckoning();
  const MotionPrior prior = priorAtTheLoss();
  reckoning.start(prior);
  ASSERT_TRUE(reckoning.running());
  EXPECT_FALSE(reckoning.poseAt(utimeOf(1), kCoastS));  // nothing held yet: the caller coasts
  const std::vector<SurfaceAnchor> keyframe = keyframeAnchors();
  constexpr int kLost = 45;  // 1.5 s
  for (int k = 1; k <= kLost; ++k) reckoning.step(frameAt(kRoom, k, truthAt(k)), keyframe);
  EXPECT_GE(reckoning.framesHeld(), kLost - 2);
  ASSERT_TRUE(reckoning.poseAt(utimeOf(kLost), kCoastS));
  const SE3 reckoned = *reckoning.poseAt(utimeOf(kLost), kCoastS);
  // The coast (the velocity at the loss, 30 frames) is far off: the test means something.
  const SE3 coasted = SE3::exp(30 * kFrameS * prior.velocity()) * prior.pose();
  EXPECT_GT(metresOff(coasted, truthAt(kLost)), 0.3);
  EXPECT_GT(degreesOff(coasted, truthAt(kLost)), 20.0);
  // Depth follows it (exact depth here, stored in 0.2 mm units; measured 2.3 cm, 0.16 deg).
  EXPECT_LT(metresOff(reckoned, truthAt(kLost)), 0.05);
  EXPECT_LT(degreesOff(reckoned, truthAt(kLost)), 1.0);
}

// 1.2 m/s along the corridor, the speed it had at the loss.
SE3 alongTheCorridor(int k) { return SE3(Eigen::Quaterniond::Identity(), Vec3(0.0, 0.0, 1.2 * k * kFrameS)); }

TEST(DepthDeadReckoning, CarriesTheSlideAlongACorridorOnTheVelocity) {
  DepthDeadReckoning reckoning = makeReckoning();
  reckoning.start(priorAtTheLoss(alongTheCorridor));
  const std::vector<SurfaceAnchor> keyframe = keyframeAnchors(kCorridor, alongTheCorridor(0));
  constexpr int kLost = 45;
  for (int k = 1; k <= kLost; ++k) reckoning.step(frameAt(kCorridor, k, alongTheCorridor(k)), keyframe);
  EXPECT_GE(reckoning.framesHeld(), kLost / 2);
  // The slide is the velocity's, and the vehicle kept it (measured: 7 mm along the
  // corridor after 1.8 m).
  const SE3 reckoned = *reckoning.poseAt(utimeOf(kLost), kCoastS);
  EXPECT_LT(std::abs(reckoned.inverse().translation().z() - alongTheCorridor(kLost).translation().z()), 0.03);
  // The walls, floor and ceiling fix the rest, the floor and ceiling only near the camera
  // (seen more obliquely than 75 deg beyond 3.7 m and 5.6 m): height and pitch drift
  // with each new reference (measured: 8 cm and 2.2 deg after 1.8 m).
  EXPECT_LT(metresOff(reckoned, alongTheCorridor(kLost)), 0.15);
  EXPECT_LT(degreesOff(reckoned, alongTheCorridor(kLost)), 4.0);
}

TEST(DepthDeadReckoning, ASurfaceFarFromThePredictionIsNotHeld) {
  DepthDeadReckoning reckoning = makeReckoning();
  reckoning.start(priorAtTheLoss());
  // The frame's depth as if the camera were 0.5 m from where a vehicle can be in a frame.
  const SE3 jumped = SE3(Eigen::Quaterniond::Identity(), Vec3(0.0, 0.0, 0.5)) * truthAt(1);
  EXPECT_FALSE(reckoning.step(frameAt(kRoom, 1, jumped), keyframeAnchors()));
  EXPECT_EQ(reckoning.framesHeld(), 0);
  EXPECT_FALSE(reckoning.poseAt(utimeOf(1), kCoastS));
  // No depth: nothing to hold, and not an error.
  RgbdFrame no_depth = frameAt(kRoom, 2, truthAt(2));
  no_depth.depth = cv::Mat();
  EXPECT_FALSE(reckoning.step(no_depth, keyframeAnchors()));
  EXPECT_TRUE(reckoning.running());
}

TEST(DepthDeadReckoning, EndsAfterAGapAndCoastsNoLongerThanAsked) {
  DepthDeadReckoning reckoning = makeReckoning();
  const MotionPrior prior = priorAtTheLoss();
  reckoning.start(prior);
  ASSERT_TRUE(reckoning.step(frameAt(kRoom, 1, truthAt(1)), keyframeAnchors()));
  const double max_gap_s = prior.options().max_gap_s;
  const int64_t at_gap = utimeOf(1) + static_cast<int64_t>(max_gap_s * 1e6);
  // Carried on by the velocity for at most the coast asked for after the last frame held.
  EXPECT_LT(metresOff(*reckoning.poseAt(at_gap + 10000000, 0.2), reckoning.poseAt(utimeOf(1) + 200000, 0.2)->inverse()), 1e-9);
  EXPECT_GT(metresOff(*reckoning.poseAt(utimeOf(1) + 200000, 0.2), reckoning.poseAt(utimeOf(1), 0.2)->inverse()), 0.05);
  EXPECT_TRUE(reckoning.heldRecently(at_gap));
  EXPECT_FALSE(reckoning.heldRecently(at_gap + 1000));
  // A frame after a longer gap ends it; the last pose held stays the guess.
  RgbdFrame late = frameAt(kRoom, 1, truthAt(1));
  late.utime = at_gap + 1000;
  EXPECT_FALSE(reckoning.step(late, keyframeAnchors()));
  EXPECT_FALSE(reckoning.running());
  EXPECT_TRUE(reckoning.poseAt(late.utime, kCoastS));
  // Time going back ends it too.
  reckoning.start(prior);
  RgbdFrame earlier = frameAt(kRoom, 1, truthAt(1));
  earlier.utime = utimeOf(-5);
  EXPECT_FALSE(reckoning.step(earlier, keyframeAnchors()));
  EXPECT_FALSE(reckoning.running());
  // A prior without a pose starts nothing.
  reckoning.start(MotionPrior{});
  EXPECT_FALSE(reckoning.running());
  EXPECT_FALSE(reckoning.step(frameAt(kRoom, 1, truthAt(1)), keyframeAnchors()));
}

TEST(DepthDeadReckoning, MovesWithTheWorld) {
  DepthDeadReckoning reckoning = makeReckoning();
  reckoning.start(priorAtTheLoss());
  ASSERT_TRUE(reckoning.step(frameAt(kRoom, 1, truthAt(1)), keyframeAnchors()));
  const SE3 before = *reckoning.poseAt(utimeOf(2), kCoastS);
  Vec6 xi;
  xi << 1.0, -2.0, 0.5, 0.1, 0.2, -0.3;
  const SE3 T_new_old = SE3::exp(xi);
  reckoning.moveWorld(T_new_old);
  const SE3 after = *reckoning.poseAt(utimeOf(2), kCoastS);
  EXPECT_LT(metresOff(after, T_new_old * before.inverse()), 1e-9);
  EXPECT_LT(degreesOff(after, T_new_old * before.inverse()), 1e-6);
  // The next frame, seen in the moved world, is held where the moved world puts it.
  ASSERT_TRUE(reckoning.step(frameAt(kRoom, 2, truthAt(2)), keyframeAnchors(kRoom, truthAt(0), T_new_old)));
  EXPECT_LT(metresOff(*reckoning.poseAt(utimeOf(2), kCoastS), T_new_old * truthAt(2)), 0.01);
}

// A lone wall 3 m ahead: it fixes the distance to it and the camera's tilt against it, not
// the slide along it nor the roll about its normal.
const std::vector<Plane> kLoneWall = {{Vec3(0, 0, 1), 3.0}};

// Towards the wall at 0.3 m/s, turning at 0.15 rad/s about the vertical up to the loss at
// k = 0; then, within 0.5 s, a stop and the turn reversed (-0.15 rad/s): the wall must
// correct the velocity at the loss in the directions it fixes.
SE3 towardsTheWall(int k) {
  const double t = k * kFrameS;
  double z = 0.3 * t, yaw = 0.15 * t;
  if (t > 0.0) {
    const double ramp = std::min(t, 0.5);
    z = 0.3 * ramp - 0.3 * ramp * ramp;
    yaw = 0.15 * ramp - 0.3 * ramp * ramp - 0.15 * std::max(0.0, t - 0.5);
  }
  return SE3(Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Vec3::UnitY())), Vec3(0.0, 0.0, z));
}

// Frame k with a structured-light sensor's depth noise: 2.5 mm at 1 m, growing with the
// square of the depth (2.3 cm at the wall).
RgbdFrame noisyFrameAt(const std::vector<Plane>& world, int k, const SE3& T_w_c) {
  cv::Mat depth = renderDepth(world, T_w_c, kinectCamera());
  cv::RNG rng(static_cast<uint64_t>(k) + 1);
  for (float& z : cv::Mat_<float>(depth)) {
    if (std::isfinite(z)) z += static_cast<float>(rng.gaussian(2.5e-3 * z * z));
  }
  RgbdFrame frame = frameWithDepth(depth);
  frame.utime = utimeOf(k);
  return frame;
}

// The tracker's prior at the loss as its points leave it: their information couples the
// pose's directions, so the filter's pose and velocity are correlated across directions.
MotionPrior correlatedPriorAtTheLoss(SE3 (*path)(int)) {
  Eigen::Matrix<double, 12, 6> J;
  for (int r = 0; r < 12; ++r) {
    for (int c = 0; c < 6; ++c) J(r, c) = std::sin(1.7 * r + 2.3 * c + 0.4 * r * c);
  }
  MotionPrior prior;
  for (int k = -10; k <= 0; ++k) prior.update(utimeOf(k), path(k).inverse(), 1e4 * J.transpose() * J);
  return prior;
}

// The camera's true velocity at frame k as the filter holds it: the twist on T_c_w,
// T_c_w(k + 1) = exp(v dt) T_c_w(k).
Vec6 truthVelocity(SE3 (*path)(int), int k) { return (path(k + 1).inverse() * path(k)).log() / kFrameS; }

TEST(DepthDeadReckoning, KeepsTheVelocityWhereTheSurfacesFixNothing) {
  DepthDeadReckoning reckoning = makeReckoning();
  const MotionPrior prior = correlatedPriorAtTheLoss(towardsTheWall);
  reckoning.start(prior);
  const std::vector<SurfaceAnchor> wall = keyframeAnchors(kLoneWall, towardsTheWall(0));
  constexpr int kLost = 45;
  for (int k = 1; k <= kLost; ++k) reckoning.step(noisyFrameAt(kLoneWall, k, towardsTheWall(k)), wall);
  EXPECT_GE(reckoning.framesHeld(), kLost - 2);
  // The velocity at the loss, kept, is far off in turn rate (measured: 17.2 deg/s; 0.30
  // m/s in speed): the test means something.
  const Vec6 coasting_error = prior.velocity() - truthVelocity(towardsTheWall, kLost);
  EXPECT_GT(coasting_error.tail<3>().norm() * 180.0 / M_PI, 15.0);
  // Conditioned on the whole pose, with the fit's whole move taken, the depth noise drove
  // the velocity where the wall fixes little or nothing: 19.6 deg/s and 0.78 m/s off the
  // truth, the pose 0.96 m and 3.1 deg off (on a path without the stop and the reversed
  // turn: 119 deg/s, 2.2 m/s and 29.6 deg). Measured now: 2.4 deg/s and 0.27 m/s, the pose
  // 0.37 m and 1.1 deg off. The speed is no better than the loss's: the wall's normals,
  // estimated from noisy depth, lend the slide along it a little information, and where
  // that passes the bar the slide takes their noise (docs/open_work.md, session 39).
  const Vec6 error = reckoning.velocity() - truthVelocity(towardsTheWall, kLost);
  EXPECT_LT(error.tail<3>().norm() * 180.0 / M_PI, 8.0);
  EXPECT_LT(error.head<3>().norm(), 0.5);
  const SE3 reckoned = *reckoning.poseAt(utimeOf(kLost), kCoastS);
  EXPECT_LT(degreesOff(reckoned, towardsTheWall(kLost)), 5.0);
  EXPECT_LT(metresOff(reckoned, towardsTheWall(kLost)), 0.6);
}

}  // namespace
}  // namespace rgbdslam
