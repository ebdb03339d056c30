#include <gtest/gtest.h>

#include <random>

#include "rgbdslam/geometry/alignment.h"

namespace rgbdslam {
namespace {

std::vector<Vec3> randomPoints(size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(-3.0, 3.0);
  std::vector<Vec3> points;
  for (size_t i = 0; i < n; ++i) points.emplace_back(uniform(rng), uniform(rng), uniform(rng));
  return points;
}

Sim3 knownSim3(double scale) {
  Vec6 xi;
  xi << 1.5, -0.7, 2.0, 0.4, -1.1, 2.3;  // translation [m], rotation vector [rad]
  const SE3 T = SE3::exp(xi);
  return Sim3{scale, T.rotationMatrix(), T.translation()};
}

std::vector<Vec3> transformed(const Sim3& S, const std::vector<Vec3>& points) {
  std::vector<Vec3> out;
  for (const Vec3& p : points) out.push_back(S * p);
  return out;
}

double rmsResidual(const Sim3& S, const std::vector<Vec3>& source,
                   const std::vector<Vec3>& target) {
  double sum = 0.0;
  for (size_t i = 0; i < source.size(); ++i) sum += (target[i] - S * source[i]).squaredNorm();
  return std::sqrt(sum / static_cast<double>(source.size()));
}

TEST(Alignment, RigidRecoversKnownTransform) {
  const std::vector<Vec3> p_est = randomPoints(50, 1);
  const Sim3 S_gt_est_true = knownSim3(1.0);
  const std::vector<Vec3> p_gt = transformed(S_gt_est_true, p_est);

  const auto S_gt_est = alignPoints(p_est, p_gt, AlignmentKind::kRigid);
  ASSERT_TRUE(S_gt_est.ok()) << S_gt_est.error();
  EXPECT_EQ(S_gt_est->scale, 1.0);
  EXPECT_LT((S_gt_est->R - S_gt_est_true.R).norm(), 1e-9);
  EXPECT_LT((S_gt_est->t - S_gt_est_true.t).norm(), 1e-9);
  EXPECT_LT(rmsResidual(*S_gt_est, p_est, p_gt), 1e-9);
}

TEST(Alignment, SimilarityRecoversKnownScale) {
  const std::vector<Vec3> p_est = randomPoints(40, 2);
  const Sim3 S_gt_est_true = knownSim3(2.5);
  const std::vector<Vec3> p_gt = transformed(S_gt_est_true, p_est);

  const auto S_gt_est = alignPoints(p_est, p_gt, AlignmentKind::kSimilarity);
  ASSERT_TRUE(S_gt_est.ok()) << S_gt_est.error();
  EXPECT_NEAR(S_gt_est->scale, 2.5, 1e-9);
  EXPECT_LT((S_gt_est->R - S_gt_est_true.R).norm(), 1e-9);
  EXPECT_LT((S_gt_est->t - S_gt_est_true.t).norm(), 1e-9);
  EXPECT_LT(rmsResidual(*S_gt_est, p_est, p_gt), 1e-9);
}

TEST(Alignment, RigidCannotAbsorbAScale) {
  const std::vector<Vec3> p_est = randomPoints(40, 3);
  const std::vector<Vec3> p_gt = transformed(knownSim3(2.5), p_est);
  const auto S_gt_est = alignPoints(p_est, p_gt, AlignmentKind::kRigid);
  ASSERT_TRUE(S_gt_est.ok()) << S_gt_est.error();
  EXPECT_GT(rmsResidual(*S_gt_est, p_est, p_gt), 0.5);
}

TEST(Alignment, ReturnsAProperRotationForMirroredPoints) {
  const std::vector<Vec3> p_est = randomPoints(30, 4);
  std::vector<Vec3> p_gt = p_est;
  for (Vec3& p : p_gt) p.z() = -p.z();  // a reflection: no rotation maps one onto the other
  const auto S_gt_est = alignPoints(p_est, p_gt, AlignmentKind::kRigid);
  ASSERT_TRUE(S_gt_est.ok()) << S_gt_est.error();
  EXPECT_NEAR(S_gt_est->R.determinant(), 1.0, 1e-9);
  EXPECT_LT((S_gt_est->R * S_gt_est->R.transpose() - Mat3::Identity()).norm(), 1e-9);
}

TEST(Alignment, AcceptsCollinearPoints) {
  std::vector<Vec3> p_est;
  for (int i = 0; i < 10; ++i) p_est.emplace_back(0.1 * i, 0.2 * i, -0.05 * i);
  const std::vector<Vec3> p_gt = transformed(knownSim3(1.0), p_est);
  const auto S_gt_est = alignPoints(p_est, p_gt, AlignmentKind::kRigid);
  ASSERT_TRUE(S_gt_est.ok()) << S_gt_est.error();
  EXPECT_LT(rmsResidual(*S_gt_est, p_est, p_gt), 1e-9);
}

TEST(Alignment, RejectsTooFewPoints) {
  const std::vector<Vec3> p = randomPoints(2, 5);
  const auto S = alignPoints(p, p, AlignmentKind::kRigid);
  ASSERT_FALSE(S.ok());
  EXPECT_NE(S.error().find("at least 3"), std::string::npos) << S.error();
}

TEST(Alignment, RejectsMismatchedSizes) {
  EXPECT_FALSE(alignPoints(randomPoints(4, 6), randomPoints(5, 6), AlignmentKind::kRigid).ok());
}

TEST(Alignment, RejectsCoincidentPoints) {
  const std::vector<Vec3> same(5, Vec3(1.0, 2.0, 3.0));
  const std::vector<Vec3> spread = randomPoints(5, 7);
  const auto coincident_source = alignPoints(same, spread, AlignmentKind::kSimilarity);
  ASSERT_FALSE(coincident_source.ok());
  EXPECT_NE(coincident_source.error().find("degenerate"), std::string::npos);
  EXPECT_FALSE(alignPoints(spread, same, AlignmentKind::kRigid).ok());
}

}  // namespace
}  // namespace rgbdslam
