#include "rgbdslam/tracking/motion_prior.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <cmath>
#include <random>

#include "rgbdslam/tracking/pose_optimizer.h"

namespace rgbdslam {
namespace {

constexpr int64_t kPriorFrameUs = 33333;  // 30 Hz

Vec6 priorTwist(double vx, double vy, double vz, double wx, double wy, double wz) {
  Vec6 v;
  v << vx, vy, vz, wx, wy, wz;
  return v;
}

// Starts 'prior' at the identity at time 0 and feeds it 'frames' poses measured with
// 'measured' along the constant twist 'v', one per frame at 30 Hz; returns the last pose.
SE3 flyConstantVelocity(MotionPrior* prior, const Vec6& v, const Mat6& measured, int frames) {
  SE3 T;
  prior->reset(0, T, measured);
  for (int k = 1; k <= frames; ++k) {
    T = SE3::exp(kPriorFrameUs * 1e-6 * v) * T;
    prior->update(k * kPriorFrameUs, T, measured);
  }
  return T;
}

double priorPositionError(const SE3& a, const SE3& b) {
  return (a.inverse().translation() - b.inverse().translation()).norm();
}

// Poses measured exactly (information 1e8: 0.1 mm) along a constant velocity: the filter
// learns the velocity and predicts the next pose, and its prior tightens to the
// acceleration's share.
TEST(MotionPrior, LearnsAConstantVelocityAndPredictsTheNextPose) {
  MotionPrior prior;
  const Vec6 v = priorTwist(2.0, 0.0, 0.1, 0.0, 0.5, 0.0);  // 2 m/s, 29 deg/s
  const Mat6 measured = 1e8 * Mat6::Identity();
  const SE3 T = flyConstantVelocity(&prior, v, measured, 30);
  EXPECT_LT((prior.velocity() - v).norm(), 1e-3);
  const std::optional<PosePrior> next = prior.predict(31 * kPriorFrameUs);
  ASSERT_TRUE(next);
  const SE3 truth = SE3::exp(kPriorFrameUs * 1e-6 * v) * T;
  EXPECT_LT(priorPositionError(next->T_c_w, truth), 1e-4);
  // The prior's sigma in translation: the acceleration's 0.5 a dt^2 (2.8 mm at 5 m/s^2)
  // and the velocity's uncertainty, a few mm at most.
  const double sigma_x = std::sqrt(next->information.inverse()(0, 0));
  EXPECT_GT(sigma_x, 0.5 * 0.5 * 5.0 * std::pow(kPriorFrameUs * 1e-6, 2));
  EXPECT_LT(sigma_x, 0.01);
}

TEST(MotionPrior, NoPriorWithoutAPoseAfterAGapOrWhenTimeGoesBackOrWhenOff) {
  MotionPrior prior;
  EXPECT_FALSE(prior.predict(kPriorFrameUs));  // no pose yet
  prior.reset(0, SE3(), Mat6::Identity());
  EXPECT_TRUE(prior.predict(kPriorFrameUs));
  EXPECT_FALSE(prior.predict(0));                         // no time passed
  EXPECT_FALSE(prior.predict(-kPriorFrameUs));                 // time went back
  EXPECT_FALSE(prior.predict(static_cast<int64_t>(0.6e6)));  // beyond max_gap_s (0.5 s)
  prior.clear();
  EXPECT_FALSE(prior.predict(kPriorFrameUs));
  MotionPriorOptions off;
  off.enabled = false;
  MotionPrior disabled(off);
  disabled.reset(0, SE3(), Mat6::Identity());
  EXPECT_FALSE(disabled.predict(kPriorFrameUs));
}

// After a reset the velocity is unknown: the next frame's prior is as weak as the top
// speed says (3 m/s over a frame: 10 cm), not a claim that the camera stands still.
TEST(MotionPrior, AfterAResetThePriorIsWeak) {
  MotionPrior prior;
  prior.reset(0, SE3(), 1e8 * Mat6::Identity());
  const std::optional<PosePrior> next = prior.predict(kPriorFrameUs);
  ASSERT_TRUE(next);
  const double sigma_x = std::sqrt(next->information.inverse()(0, 0));
  EXPECT_NEAR(sigma_x, 3.0 * kPriorFrameUs * 1e-6, 0.01);
}

// A direction the measurements do not fix is predicted by the filter (dead reckoning),
// with an uncertainty that grows frame by frame, while fixed directions stay tight.
TEST(MotionPrior, AnUnmeasuredDirectionIsCarriedByTheVelocity) {
  MotionPrior prior;
  const Vec6 v = priorTwist(0.0, 0.0, 2.0, 0.0, 0.0, 0.0);  // forward along the optical axis
  Mat6 all = 1e8 * Mat6::Identity();
  Mat6 no_z = all;
  no_z(2, 2) = 0.0;
  SE3 T = flyConstantVelocity(&prior, v, all, 20);
  int k = 21;
  double last_sigma_z = 0.0;
  for (; k <= 40; ++k) {
    const std::optional<PosePrior> next = prior.predict(k * kPriorFrameUs);
    ASSERT_TRUE(next);
    const Mat6 covariance = next->information.inverse();
    const double sigma_z = std::sqrt(covariance(2, 2));
    EXPECT_GT(sigma_z, last_sigma_z);
    EXPECT_LT(std::sqrt(covariance(0, 0)), 0.01);
    last_sigma_z = sigma_z;
    T = SE3::exp(kPriorFrameUs * 1e-6 * v) * T;
    prior.update(k * kPriorFrameUs, next->T_c_w, no_z);  // the fit followed the prior in z
  }
  EXPECT_LT(priorPositionError(prior.predict(k * kPriorFrameUs)->T_c_w, SE3::exp(kPriorFrameUs * 1e-6 * v) * T), 1e-3);
}

// A depth-aided fit's information is a difference and may be indefinite; the filter takes
// its negative part as nothing measured, so the next prior stays positive definite.
TEST(MotionPrior, AnIndefiniteMeasurementLeavesThePriorPositiveDefinite) {
  MotionPrior prior;
  Mat6 indefinite = 1e6 * Mat6::Identity();
  indefinite(2, 2) = -50.0;
  prior.reset(0, SE3(), indefinite);
  prior.update(kPriorFrameUs, SE3(), indefinite);
  const std::optional<PosePrior> next = prior.predict(2 * kPriorFrameUs);
  ASSERT_TRUE(next);
  const Eigen::SelfAdjointEigenSolver<Mat6> eig(next->information);
  EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0);
  Mat6 nan = Mat6::Identity();
  nan(0, 0) = std::nan("");
  prior.update(3 * kPriorFrameUs, SE3(), nan);
  ASSERT_TRUE(prior.predict(4 * kPriorFrameUs));
  EXPECT_TRUE(prior.predict(4 * kPriorFrameUs)->information.allFinite());
}

// Frames stamped a millisecond apart (a burst on arrival) are one instant: no prior that
// would claim the camera cannot have moved, and the velocity learnt before stays.
TEST(MotionPrior, FramesCloserThanTheMinimumGapAreOneInstant) {
  MotionPrior prior;
  const Vec6 v = priorTwist(0.0, 0.0, 2.0, 0.0, 0.0, 0.0);
  const Mat6 measured = 1e8 * Mat6::Identity();
  const SE3 T = flyConstantVelocity(&prior, v, measured, 10);
  const int64_t burst = 10 * kPriorFrameUs + 1000;
  EXPECT_FALSE(prior.predict(burst));
  prior.update(burst, T, measured);
  EXPECT_LT((prior.velocity() - v).norm(), 1e-2);
}

// A map correction moves the world frame: the prediction moves with it.
TEST(MotionPrior, FollowsAMovedWorld) {
  MotionPrior prior;
  prior.reset(0, SE3(), 1e8 * Mat6::Identity());
  const SE3 T_new_old = SE3::exp(priorTwist(0.1, 0.0, 0.0, 0.0, 0.0, 0.0));
  prior.moveWorld(T_new_old);
  const std::optional<PosePrior> next = prior.predict(kPriorFrameUs);
  ASSERT_TRUE(next);
  // The camera stood at the old world's origin, which is at (0.1, 0, 0) in the new world.
  EXPECT_LT((next->T_c_w.inverse().translation() - Vec3(0.1, 0.0, 0.0)).norm(), 1e-9);
}

struct PriorScene {
  PinholeCamera camera;
  SE3 T_c_w_true;
  std::vector<PoseObservation> observations;
};

// Points 'near' to 'far' m ahead, seen exactly, no depth. On a far plane they fix rotation
// well and translation across the view poorly.
PriorScene priorPointsAhead(int n, double near, double far, unsigned seed) {
  PriorScene scene;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), distance(near, far);
  scene.T_c_w_true = SE3::exp(priorTwist(0.2, -0.1, 0.3, 0.05, -0.1, 0.02));
  const SE3 T_w_c = scene.T_c_w_true.inverse();
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d uv(320 + 300 * unit(rng), 240 + 220 * unit(rng));
    scene.observations.push_back({T_w_c * scene.camera.unproject(uv, distance(rng)), uv, 0, 0.0});
  }
  return scene;
}

// Wrong matches on far points pull the fit sideways where nothing else fixes it; the prior,
// centred on the truth, holds the pose, and the information reported is the measurements'
// alone.
TEST(MotionPrior, HoldsTheFitWhereFarPointsAndWrongMatchesWouldCarryItOff) {
  PriorScene scene = priorPointsAhead(40, 20.0, 20.0, 3);
  PoseOptimizerOptions options;
  options.use_depth = false;
  // Half the matches shifted alike by 3 px: a consistent wrong match (a repeated
  // texture), which the robust fit cannot tell from a sideways step at 20 m.
  for (size_t i = 0; i < scene.observations.size(); i += 2) scene.observations[i].uv.x() += 3.0;
  const PoseOptimizerResult free_fit = optimisePose(scene.camera, scene.T_c_w_true, scene.observations, options);
  ASSERT_TRUE(free_fit.ok);
  PosePrior prior;
  prior.T_c_w = scene.T_c_w_true;
  prior.information.diagonal() << 1e5, 1e5, 1e5, 1e3, 1e3, 1e3;  // 3 mm, 1.8 deg
  const PoseOptimizerResult held =
      optimisePose(scene.camera, scene.T_c_w_true, scene.observations, options, nullptr, nullptr, &prior);
  ASSERT_TRUE(held.ok);
  EXPECT_GT(priorPositionError(free_fit.T_c_w, scene.T_c_w_true), 0.02);
  EXPECT_LT(priorPositionError(held.T_c_w, scene.T_c_w_true), 0.01);
  // The reported information excludes the prior: the far plane fixes the sideways
  // translation no better with it.
  EXPECT_LT(poseUncertainty(held.information).translation_m * 0.5, poseUncertainty(free_fit.information).translation_m);
  EXPECT_GT(poseUncertainty(held.information).translation_m, 0.01);
}

// Where the points fix the pose (near, at several depths, with depth readings), a prior
// 3 cm off does not move it. (On a plane facing the camera the points tell a sideways step
// from a turn only by perspective, and such a prior moves a fit by a centimetre: there the
// prior is worth as much as they are.)
TEST(MotionPrior, PointsThatFixThePoseOutweighAWrongPrior) {
  const PriorScene scene = priorPointsAhead(100, 1.0, 4.0, 4);
  PoseOptimizerOptions options;
  PosePrior prior;
  prior.T_c_w = SE3::exp(priorTwist(0.03, 0.0, 0.0, 0.0, 0.0, 0.0)) * scene.T_c_w_true;  // 3 cm off
  prior.information.diagonal() << 1e5, 1e5, 1e5, 1e3, 1e3, 1e3;
  std::vector<PoseObservation> with_depth = scene.observations;
  for (PoseObservation& obs : with_depth) obs.depth = (scene.T_c_w_true * obs.p_w).z();
  const PoseOptimizerResult fit =
      optimisePose(scene.camera, scene.T_c_w_true, with_depth, options, nullptr, nullptr, &prior);
  ASSERT_TRUE(fit.ok);
  EXPECT_LT(priorPositionError(fit.T_c_w, scene.T_c_w_true), 0.003);
}

}  // namespace
}  // namespace rgbdslam
