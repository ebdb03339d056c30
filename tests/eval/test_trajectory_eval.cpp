#include <gtest/gtest.h>

#include <cstdlib>
#include <opencv2/imgcodecs.hpp>
#include <random>

#include "rgbdslam/eval/trajectory_eval.h"
#include "test_support.h"

namespace rgbdslam {
namespace {

constexpr double kStartTime_s = 1341841873.0;  // TUM-like absolute stamps
constexpr double kFramePeriod_s = 0.05;

Vec6 makeXi(double a, double b, double c, double d, double e, double f) {
  Vec6 xi;
  xi << a, b, c, d, e, f;
  return xi;
}

// 30 s of a helix with varying orientation: extent in all three axes, 0.6 m/s.
Trajectory helixGroundTruth() {
  Trajectory trajectory;
  for (int k = 0; k < 600; ++k) {
    const double s = k * kFramePeriod_s;
    const Vec3 position(2.0 * std::cos(0.3 * s), 2.0 * std::sin(0.3 * s), 1.0 + 0.2 * std::sin(s));
    const Mat3 R = expSO3(Vec3(0.1 * std::sin(s), 0.05, 0.3 * s));
    trajectory.push_back(TimedPose{kStartTime_s + s, SE3(R, position)});
  }
  return trajectory;
}

// 20 s of a straight line along y at 0.5 m/s, constant orientation.
Trajectory straightGroundTruth() {
  Trajectory trajectory;
  for (int k = 0; k < 400; ++k) {
    const double s = k * kFramePeriod_s;
    trajectory.push_back(
        TimedPose{kStartTime_s + s, SE3(Mat3::Identity(), Vec3(0.0, 0.5 * s, 1.0))});
  }
  return trajectory;
}

// The same camera poses seen from another world: T_est_c = T_est_gt * T_gt_c, positions
// divided by 'scale_gt_per_est' (a monocular run with the wrong scale).
Trajectory inOtherWorld(const Trajectory& groundtruth, const SE3& T_est_gt,
                        double scale_gt_per_est = 1.0) {
  Trajectory estimate;
  for (const TimedPose& pose : groundtruth) {
    const SE3 T_est_c = T_est_gt * pose.T_w_c;
    estimate.push_back(
        TimedPose{pose.t, SE3(T_est_c.rotation(), T_est_c.translation() / scale_gt_per_est)});
  }
  return estimate;
}

const SE3 kT_est_gt = SE3::exp(makeXi(0.8, -2.0, 0.3, 0.2, -0.4, 1.9));

double jsonNumber(const std::string& json, const std::string& key) {
  const std::string needle = "\"" + key + "\": ";
  const size_t at = json.find(needle);
  if (at == std::string::npos) return std::nan("");
  return std::strtod(json.c_str() + at + needle.size(), nullptr);
}

TEST(TrajectoryEval, RigidlyMovedTrajectoryHasZeroAteAndRecoversTransform) {
  const Trajectory groundtruth = helixGroundTruth();
  const auto result =
      evaluateTrajectory(groundtruth, inOtherWorld(groundtruth, kT_est_gt), EvalOptions{});
  ASSERT_TRUE(result.ok()) << result.error();
  EXPECT_EQ(result->num_associated, groundtruth.size());
  EXPECT_LT(result->ate_m.max, 1e-9);
  EXPECT_LT(result->ate_m.rmse, 1e-9);
  EXPECT_EQ(result->S_gt_est.scale, 1.0);
  const SE3 T_gt_est_true = kT_est_gt.inverse();
  EXPECT_LT((result->S_gt_est.R - T_gt_est_true.rotationMatrix()).norm(), 1e-9);
  EXPECT_LT((result->S_gt_est.t - T_gt_est_true.translation()).norm(), 1e-9);
  EXPECT_LT(result->rpe_per_s.trans_m.rmse, 1e-9);
  EXPECT_LT(result->rpe_per_s.rot_deg.rmse, 1e-6);
  EXPECT_GT(result->rpe_per_s.trans_m.count, 500u);
  EXPECT_GT(result->rpe_per_m.trans_m.count, 400u);
}

// Issue 12: the figure a flight controller feels. A 5 cm jump held for a dozen frames, then
// undone: two frame-to-frame errors of 5 cm (there and back), found at the right time,
// although the ATE hardly shows them.
TEST(TrajectoryEval, FrameToFrameErrorFindsAJumpAndCountsThoseAboveTheThreshold) {
  const Trajectory groundtruth = straightGroundTruth();
  Trajectory estimate = groundtruth;
  for (size_t k = 200; k < 212; ++k) {
    estimate[k].T_w_c = SE3(estimate[k].T_w_c.rotation(), estimate[k].T_w_c.translation() + Vec3(0.05, 0, 0));
  }
  const auto result = evaluateTrajectory(groundtruth, inOtherWorld(estimate, kT_est_gt), EvalOptions{});
  ASSERT_TRUE(result.ok()) << result.error();
  EXPECT_EQ(result->jumps, 2u);
  ASSERT_EQ(result->jump_pairs.size(), 2u);
  EXPECT_EQ(result->pairs[result->jump_pairs[0]].est_index, 200u);
  EXPECT_EQ(result->pairs[result->jump_pairs[1]].est_index, 212u);
  EXPECT_NEAR(result->frame_to_frame_m.max, 0.05, 0.002);
  EXPECT_LT(result->frame_to_frame_m.median, 1e-3);
  const double t_jump = groundtruth[200].t, t_back = groundtruth[212].t;
  EXPECT_TRUE(std::abs(result->worst_jump_t_s - t_jump) < 1e-6 || std::abs(result->worst_jump_t_s - t_back) < 1e-6)
      << result->worst_jump_t_s - kStartTime_s;
  EvalOptions loose;
  loose.jump_threshold_m = 0.06;
  EXPECT_EQ(evaluateTrajectory(groundtruth, estimate, loose)->jumps, 0u);
  const std::string text = toKeyValueText(*result);
  EXPECT_NE(text.find("jumps 2\n"), std::string::npos) << text;
  EXPECT_NE(text.find("f2f_max_m 0.05"), std::string::npos) << text;
  loose.jump_threshold_m = 0.0;
  EXPECT_FALSE(evaluateTrajectory(groundtruth, estimate, loose));
}

TEST(TrajectoryEval, IsotropicNoiseOfOneCentimetreGivesThatAte) {
  const Trajectory groundtruth = helixGroundTruth();
  Trajectory estimate = groundtruth;
  std::mt19937 rng(42);
  std::normal_distribution<double> normal;
  for (TimedPose& pose : estimate) {
    const Vec3 direction = Vec3(normal(rng), normal(rng), normal(rng)).normalized();
    pose.T_w_c = SE3(pose.T_w_c.rotation(), pose.T_w_c.translation() + 0.01 * direction);
  }
  const auto result =
      evaluateTrajectory(groundtruth, inOtherWorld(estimate, kT_est_gt), EvalOptions{});
  ASSERT_TRUE(result.ok()) << result.error();
  EXPECT_NEAR(result->ate_m.rmse, 0.01, 0.0003);  // alignment absorbs a little of the noise
  EXPECT_NEAR(result->ate_m.median, 0.01, 0.001);
  EXPECT_LT(result->ate_m.max, 0.0125);
}

TEST(TrajectoryEval, SimilarityRecoversScaleAndRigidDoesNot) {
  const Trajectory groundtruth = helixGroundTruth();
  const Trajectory estimate = inOtherWorld(groundtruth, kT_est_gt, 2.5);
  EvalOptions options;
  options.similarity = true;
  const auto similar = evaluateTrajectory(groundtruth, estimate, options);
  ASSERT_TRUE(similar.ok()) << similar.error();
  EXPECT_EQ(similar->alignment, AlignmentKind::kSimilarity);
  EXPECT_NEAR(similar->S_gt_est.scale, 2.5, 1e-9);
  EXPECT_LT(similar->ate_m.rmse, 1e-9);
  EXPECT_LT(similar->rpe_per_s.trans_m.rmse, 1e-9);  // estimate translations scaled first

  const auto rigid = evaluateTrajectory(groundtruth, estimate, EvalOptions{});
  ASSERT_TRUE(rigid.ok()) << rigid.error();
  EXPECT_EQ(rigid->S_gt_est.scale, 1.0);
  EXPECT_GT(rigid->ate_m.rmse, 0.5);
  EXPECT_GT(rigid->rpe_per_s.trans_m.rmse, 0.3);
}

TEST(TrajectoryEval, AssociationRespectsMaxDtAndCoverage) {
  const Trajectory groundtruth = straightGroundTruth();  // every 0.05 s
  Trajectory estimate;
  for (size_t k = 0; k < groundtruth.size(); k += 2) {  // 200 poses, every 0.1 s
    TimedPose pose = groundtruth[k];
    pose.t += (k % 4 == 0) ? 0.015 : -0.025;  // -0.025: 0.025 s from both neighbours
    estimate.push_back(pose);
  }
  EvalOptions options;
  options.num_frames = 200;
  const auto result = evaluateTrajectory(groundtruth, estimate, options);
  ASSERT_TRUE(result.ok()) << result.error();
  EXPECT_EQ(result->num_estimate, 200u);
  EXPECT_EQ(result->num_groundtruth, 400u);
  EXPECT_EQ(result->num_associated, 100u);
  ASSERT_TRUE(result->coverage.has_value());
  EXPECT_DOUBLE_EQ(*result->coverage, 0.5);
  for (const PosePair& pair : result->pairs) EXPECT_LE(std::abs(pair.dt_s), 0.02 + 1e-9);

  options.max_dt_s = 0.03;
  const auto wider = evaluateTrajectory(groundtruth, estimate, options);
  ASSERT_TRUE(wider.ok()) << wider.error();
  EXPECT_EQ(wider->num_associated, 200u);
  EXPECT_DOUBLE_EQ(*wider->coverage, 1.0);

  options.num_frames = 150;  // more associated poses than frames: a fraction, capped at 1
  const auto capped = evaluateTrajectory(groundtruth, estimate, options);
  ASSERT_TRUE(capped.ok()) << capped.error();
  EXPECT_DOUBLE_EQ(*capped->coverage, 1.0);
}

TEST(TrajectoryEval, PosesThreeHundredthsOffAreNotAssociated) {
  const Trajectory groundtruth = {TimedPose{0.0, SE3()}, TimedPose{1.0, SE3()},
                                  TimedPose{2.0, SE3()}};
  const Trajectory estimate = {TimedPose{0.03, SE3()}, TimedPose{1.019, SE3()},
                               TimedPose{1.97, SE3()}};
  const std::vector<PosePair> pairs = associateByTime(groundtruth, estimate, 0.02);
  ASSERT_EQ(pairs.size(), 1u);
  EXPECT_EQ(pairs[0].gt_index, 1u);
  EXPECT_EQ(pairs[0].est_index, 1u);
  EXPECT_NEAR(pairs[0].dt_s, 0.019, 1e-12);
}

TEST(TrajectoryEval, AssociationIsOneToOneNearestFirst) {
  const Trajectory groundtruth = {TimedPose{0.0, SE3()}, TimedPose{1.0, SE3()}};
  const Trajectory estimate = {TimedPose{1.01, SE3()}, TimedPose{0.015, SE3()},
                               TimedPose{0.005, SE3()}};
  const std::vector<PosePair> pairs = associateByTime(groundtruth, estimate, 0.02);
  ASSERT_EQ(pairs.size(), 2u);
  EXPECT_EQ(pairs[0].est_index, 2u);  // sorted by estimate time; 0.005 beats 0.015 for gt 0
  EXPECT_EQ(pairs[0].gt_index, 0u);
  EXPECT_EQ(pairs[1].est_index, 0u);
  EXPECT_EQ(pairs[1].gt_index, 1u);
}

TEST(TrajectoryEval, NoAssociationIsAnError) {
  const Trajectory groundtruth = straightGroundTruth();
  Trajectory estimate = groundtruth;
  for (TimedPose& pose : estimate) pose.t += 100.0;
  const auto result = evaluateTrajectory(groundtruth, estimate, EvalOptions{});
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.error().find("max_dt"), std::string::npos) << result.error();
}

// The straight ground truth with the estimate drifting by drift_m_per_s along x and
// drift_deg_per_s about the camera's z axis.
Trajectory driftingEstimate(const Trajectory& groundtruth, double drift_m_per_s,
                            double drift_deg_per_s) {
  Trajectory estimate;
  for (size_t k = 0; k < groundtruth.size(); ++k) {
    const double s = k * kFramePeriod_s;
    const TimedPose& pose = groundtruth[k];
    const double angle_rad = drift_deg_per_s * s * 3.14159265358979323846 / 180.0;
    const Mat3 R = pose.T_w_c.rotationMatrix() * expSO3(Vec3(0.0, 0.0, angle_rad));
    estimate.push_back(
        TimedPose{pose.t, SE3(R, pose.T_w_c.translation() + Vec3(drift_m_per_s * s, 0.0, 0.0))});
  }
  return estimate;
}

TEST(TrajectoryEval, ConstantTranslationDriftGivesKnownRpe) {
  // Ground truth moves 0.5 m/s; the estimate drifts 1 cm/s sideways.
  const Trajectory groundtruth = straightGroundTruth();
  const auto result =
      evaluateTrajectory(groundtruth, driftingEstimate(groundtruth, 0.01, 0.0), EvalOptions{});
  ASSERT_TRUE(result.ok()) << result.error();
  EXPECT_EQ(result->rpe_per_s.trans_m.count, 400u - 20u);
  EXPECT_NEAR(result->rpe_per_s.trans_m.rmse, 0.01, 1e-9);
  EXPECT_NEAR(result->rpe_per_s.trans_m.max, 0.01, 1e-9);
  EXPECT_LT(result->rpe_per_s.rot_deg.rmse, 1e-9);
  EXPECT_EQ(result->rpe_per_m.trans_m.count, 400u - 40u);  // 1 m takes 2 s
  EXPECT_NEAR(result->rpe_per_m.trans_m.rmse, 0.02, 1e-9);
}

TEST(TrajectoryEval, ConstantRotationDriftGivesKnownRpe) {
  const Trajectory groundtruth = straightGroundTruth();
  const auto result =
      evaluateTrajectory(groundtruth, driftingEstimate(groundtruth, 0.0, 1.0), EvalOptions{});
  ASSERT_TRUE(result.ok()) << result.error();
  EXPECT_NEAR(result->rpe_per_s.rot_deg.rmse, 1.0, 1e-6);
  EXPECT_NEAR(result->rpe_per_m.rot_deg.rmse, 2.0, 1e-6);
}

TEST(TrajectoryEval, EndPointErrorOfARigidlyMovedTrajectoryIsZero) {
  // The map starts wherever the first posed frame is: another world frame is no error.
  const Trajectory groundtruth = helixGroundTruth();
  const auto error = endPointError(groundtruth, inOtherWorld(groundtruth, kT_est_gt), 0.02);
  ASSERT_TRUE(error.ok()) << error.error();
  EXPECT_LT(error->position_m, 1e-9);
  EXPECT_LT(error->rotation_deg, 1e-6);
  EXPECT_GT(error->distance_m, 10.0);
}

TEST(TrajectoryEval, EndPointErrorOfConstantDriftIsItsIntegral) {
  // 20 s at 0.5 m/s (10 m minus one frame); 1 cm/s sideways drift, then 1 deg/s of yaw.
  const Trajectory groundtruth = straightGroundTruth();
  const double duration_s = 399 * kFramePeriod_s;
  const auto sideways = endPointError(groundtruth, driftingEstimate(groundtruth, 0.01, 0.0), 0.02);
  ASSERT_TRUE(sideways.ok()) << sideways.error();
  EXPECT_NEAR(sideways->position_m, 0.01 * duration_s, 1e-9);
  EXPECT_NEAR(sideways->distance_m, 0.5 * duration_s, 1e-9);
  EXPECT_NEAR(sideways->position_percent, 2.0, 1e-6);  // 1 cm/s of 0.5 m/s
  EXPECT_LT(sideways->rotation_deg, 1e-9);
  const auto turning = endPointError(groundtruth, driftingEstimate(groundtruth, 0.0, 1.0), 0.02);
  ASSERT_TRUE(turning.ok()) << turning.error();
  EXPECT_NEAR(turning->rotation_deg, duration_s, 1e-6);
  EXPECT_NE(toKeyValueText(*sideways).find("final_position_error_percent 2.0000"),
            std::string::npos);
}

TEST(TrajectoryEval, EndPointErrorUsesOnlyTheAssociatedSpan) {
  // The estimate covers the middle half: distance and error are over that span only.
  const Trajectory groundtruth = straightGroundTruth();
  const Trajectory drifting = driftingEstimate(groundtruth, 0.01, 0.0);
  const Trajectory middle(drifting.begin() + 100, drifting.begin() + 300);
  const auto error = endPointError(groundtruth, middle, 0.02);
  ASSERT_TRUE(error.ok()) << error.error();
  EXPECT_NEAR(error->distance_m, 0.5 * 199 * kFramePeriod_s, 1e-9);
  EXPECT_NEAR(error->position_m, 0.01 * 199 * kFramePeriod_s, 1e-9);
  EXPECT_FALSE(endPointError(groundtruth, Trajectory(drifting.begin(), drifting.begin() + 1), 0.02).ok());
}

TEST(TrajectoryEval, JsonAndTextCarryTheResults) {
  const Trajectory groundtruth = helixGroundTruth();
  Trajectory estimate = groundtruth;
  for (size_t k = 0; k < estimate.size(); ++k) {
    const Vec3 offset = (k % 2 ? 0.02 : -0.02) * Vec3::UnitZ();  // ATE close to 0.02
    estimate[k].T_w_c = SE3(estimate[k].T_w_c.rotation(), estimate[k].T_w_c.translation() + offset);
  }
  const auto result = evaluateTrajectory(groundtruth, estimate, EvalOptions{});
  ASSERT_TRUE(result.ok()) << result.error();
  ASSERT_GT(result->ate_m.rmse, 0.015);

  const std::string json = toJson(*result);
  EXPECT_NEAR(jsonNumber(json, "ate_rmse_m"), result->ate_m.rmse, 1e-8) << json;
  EXPECT_NEAR(jsonNumber(json, "ate_max_m"), result->ate_m.max, 1e-8) << json;
  EXPECT_NEAR(jsonNumber(json, "scale"), 1.0, 1e-12) << json;
  EXPECT_EQ(jsonNumber(json, "num_associated"), 600.0) << json;
  EXPECT_NE(json.find("\"coverage\": null"), std::string::npos) << json;
  EXPECT_NE(json.find("\"alignment\": \"rigid\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"rpe_per_s_trans_rmse_m\": "), std::string::npos) << json;
  EXPECT_EQ(json.front(), '{');

  char expected_line[64];
  std::snprintf(expected_line, sizeof(expected_line), "ate_rmse_m %.6f\n", result->ate_m.rmse);
  EXPECT_NE(toKeyValueText(*result).find(expected_line), std::string::npos)
      << toKeyValueText(*result);
}

TEST(TrajectoryEval, PlotIsAReadablePngOfTheExpectedSize) {
  const test::TempDir dir;
  const Trajectory groundtruth = helixGroundTruth();
  const Trajectory estimate = inOtherWorld(groundtruth, kT_est_gt);
  const auto result = evaluateTrajectory(groundtruth, estimate, EvalOptions{});
  ASSERT_TRUE(result.ok()) << result.error();

  const std::string png = dir.file("plot.png");
  const Status written = writeTrajectoryPlot(png, groundtruth, estimate, *result);
  ASSERT_TRUE(written.ok()) << written.error();
  const cv::Mat image = cv::imread(png, cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(image.empty());
  EXPECT_EQ(image.cols, 1200);
  EXPECT_EQ(image.rows, 600);
  EXPECT_EQ(image.channels(), 3);
  EXPECT_GT(cv::countNonZero(image.reshape(1) != 255), 1000);  // something was drawn

  EXPECT_FALSE(writeTrajectoryPlot(dir.file("plot.jpg"), groundtruth, estimate, *result).ok());
  EXPECT_FALSE(
      writeTrajectoryPlot(dir.file("missing/plot.png"), groundtruth, estimate, *result).ok());
}

}  // namespace
}  // namespace rgbdslam
