#include "rgbdslam/mapping/pose_graph.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace rgbdslam {
namespace {

// A square loop, 25 keyframes per side 0.5 m apart (12.5 m sides, 100 keyframes), the
// heading turning 90 deg at each corner; keyframe 0 fixed.
constexpr int kPgSide = 25;
constexpr int kPgKeyframes = 4 * kPgSide;
constexpr double kPgStep = 0.5;  // [m]

std::vector<SE3> pgSquareTruth() {
  std::vector<SE3> truth;
  Vec3 position = Vec3::Zero();
  for (int side = 0; side < 4; ++side) {
    const double yaw = side * M_PI / 2.0;
    const Mat3 R = expSO3(Vec3(0.0, 0.0, yaw));
    for (int j = 0; j < kPgSide; ++j) {
      truth.emplace_back(R, position);
      position += R * Vec3(kPgStep, 0.0, 0.0);
    }
  }
  return truth;
}

PoseGraphEdge pgEdge(KeyframeId a, KeyframeId b, const SE3& T_a_b, PoseGraphEdgeKind kind) {
  PoseGraphEdge edge;
  edge.from = a;
  edge.to = b;
  edge.T_a_b = T_a_b;
  edge.kind = kind;
  if (kind == PoseGraphEdgeKind::kLoop) {  // place recognition's bound: 2 cm, 0.5 deg
    edge.sigma_t = Vec3::Constant(0.02);
    edge.sigma_r = Vec3::Constant(0.5 * M_PI / 180.0);
  } else {  // honest about the bias: 0.17 deg per step, 1.7 deg over the loop
    edge.sigma_t = Vec3::Constant(0.01);
    edge.sigma_r = Vec3::Constant(0.003);
  }
  return edge;
}

// Odometry edges from the truth with a yaw bias [rad] per step; nodes at the poses the
// biased odometry chains up to (keyframe 0 at the truth, fixed).
PoseGraph pgDriftedSquare(const std::vector<SE3>& truth, double yaw_bias) {
  PoseGraph graph;
  const SE3 bias(expSO3(Vec3(0.0, 0.0, yaw_bias)), Vec3::Zero());
  SE3 T_w_k = truth[0];
  graph.nodes.push_back({0, T_w_k, true});
  for (int k = 0; k + 1 < kPgKeyframes; ++k) {
    const SE3 T_k_next = truth[k].inverse() * truth[k + 1] * bias;
    graph.edges.push_back(pgEdge(k, k + 1, T_k_next, PoseGraphEdgeKind::kOdometry));
    T_w_k = T_w_k * T_k_next;
    graph.nodes.push_back({k + 1, T_w_k, false});
  }
  return graph;
}

double pgPositionError(const SE3& a, const SE3& b) {
  return (a.translation() - b.translation()).norm();
}

double pgMaxError(const std::vector<KeyframePose>& poses, const std::vector<SE3>& truth) {
  double worst = 0.0;
  for (const KeyframePose& pose : poses) {
    worst = std::max(worst, pgPositionError(pose.T_w_c, truth[static_cast<size_t>(pose.id)]));
  }
  return worst;
}

std::vector<KeyframePose> pgNodePoses(const PoseGraph& graph) {
  std::vector<KeyframePose> poses;
  for (const PoseGraphNode& node : graph.nodes) poses.push_back({node.id, node.T_w_k});
  return poses;
}

TEST(PoseGraph, CorrectLoopEdgeRemovesYawDriftOfASquare) {
  const std::vector<SE3> truth = pgSquareTruth();
  PoseGraph graph = pgDriftedSquare(truth, 0.0005);  // 0.03 deg per step, 2.9 deg in all
  const KeyframeId last = kPgKeyframes - 1;
  graph.edges.push_back(
      pgEdge(last, 0, truth[last].inverse() * truth[0], PoseGraphEdgeKind::kLoop));
  const double end_before = pgPositionError(graph.nodes.back().T_w_k, truth.back());
  const double max_before = pgMaxError(pgNodePoses(graph), truth);
  ASSERT_GT(end_before, 0.3);  // the drift is worth closing

  const PoseGraphResult result = optimisePoseGraph(graph, PoseGraphOptions());
  ASSERT_TRUE(result.ok()) << result.message;
  ASSERT_EQ(result.poses.size(), graph.nodes.size());
  ASSERT_EQ(result.edges.size(), graph.edges.size());
  const double end_after = pgPositionError(result.poses.back().T_w_c, truth.back());
  const double max_after = pgMaxError(result.poses, truth);
  EXPECT_LT(end_after * 10.0, end_before) << end_before << " m -> " << end_after << " m";
  EXPECT_LT(max_after * 10.0, max_before) << max_before << " m -> " << max_after << " m";
  EXPECT_LT(result.final_cost, result.initial_cost);
  EXPECT_GT(result.iterations, 0);
  EXPECT_GT(result.time_ms, 0.0);
  EXPECT_FALSE(result.edges.back().disagrees) << result.edges.back().whitened_norm;
  EXPECT_EQ(result.loop_edges_disagreeing, 0);
  // The fixed keyframe has not moved at all.
  EXPECT_EQ(result.poses[0].T_w_c.translation(), graph.nodes[0].T_w_k.translation());
  EXPECT_LT(result.poses[0].T_w_c.rotation().angularDistance(graph.nodes[0].T_w_k.rotation()),
            1e-12);
}

// A loop edge 3 m off on an exact square: with the Cauchy loss the map stays within a few
// cm, and the edge's residual says it disagrees; with a quadratic loss the map bends.
TEST(PoseGraph, WrongLoopEdgeIsOutvotedAndFlagged) {
  const std::vector<SE3> truth = pgSquareTruth();
  PoseGraph graph = pgDriftedSquare(truth, 0.0);
  const KeyframeId last = kPgKeyframes - 1;
  const SE3 wrong = truth[last].inverse() * truth[0] * SE3(Mat3::Identity(), Vec3(3.0, 0, 0));
  graph.edges.push_back(pgEdge(last, 0, wrong, PoseGraphEdgeKind::kLoop));

  const PoseGraphResult robust = optimisePoseGraph(graph, PoseGraphOptions());
  ASSERT_TRUE(robust.ok()) << robust.message;
  EXPECT_LT(pgMaxError(robust.poses, truth), 0.04);  // 2.5 cm when measured
  EXPECT_TRUE(robust.edges.back().disagrees);
  EXPECT_GT(robust.edges.back().translation_m, 2.9);
  EXPECT_EQ(robust.loop_edges_disagreeing, 1);
  for (size_t e = 0; e + 1 < robust.edges.size(); ++e) EXPECT_FALSE(robust.edges[e].disagrees);

  PoseGraphOptions quadratic;
  quadratic.loop_loss = PoseGraphOptions::LoopLoss::kNone;
  const PoseGraphResult trusting = optimisePoseGraph(graph, quadratic);
  ASSERT_TRUE(trusting.ok()) << trusting.message;
  EXPECT_GT(pgMaxError(trusting.poses, truth), 0.5);
}

TEST(PoseGraph, FixedKeyframeInTheMiddleStaysPut) {
  const std::vector<SE3> truth = pgSquareTruth();
  PoseGraph graph = pgDriftedSquare(truth, 0.0005);
  graph.nodes[0].fixed = false;
  graph.nodes[50].fixed = true;
  graph.edges.push_back(pgEdge(kPgKeyframes - 1, 0, truth.back().inverse() * truth[0],
                               PoseGraphEdgeKind::kLoop));
  const PoseGraphResult result = optimisePoseGraph(graph, PoseGraphOptions());
  ASSERT_TRUE(result.ok()) << result.message;
  EXPECT_EQ(result.poses[50].T_w_c.translation(), graph.nodes[50].T_w_k.translation());
  EXPECT_LT(result.poses[50].T_w_c.rotation().angularDistance(graph.nodes[50].T_w_k.rotation()),
            1e-12);
  EXPECT_GT(pgPositionError(result.poses[0].T_w_c, graph.nodes[0].T_w_k), 0.01);
}

TEST(PoseGraph, PointsMoveWithTheirSourceKeyframe) {
  const SE3 before_1(expSO3(Vec3(0.0, 0.0, 0.3)), Vec3(1.0, 0.0, 0.0));
  const SE3 after_1(expSO3(Vec3(0.1, 0.0, -0.2)), Vec3(1.2, -0.5, 0.1));
  const std::vector<KeyframePose> before = {{0, SE3()}, {1, before_1}};
  const std::vector<KeyframePose> after = {{0, SE3()}, {1, after_1}};
  std::vector<MapPointData> points(3);
  points[0].source_keyframe = 0;
  points[0].p_w = Vec3(1.0, 2.0, 3.0);
  points[1].source_keyframe = 1;
  points[1].p_w = Vec3(2.0, 1.0, 4.0);
  points[2].source_keyframe = 7;  // not in the graph: left alone
  points[2].p_w = Vec3(-1.0, 0.5, 2.0);
  const Vec3 p_k1 = before_1.inverse() * points[1].p_w;

  EXPECT_EQ(movePointsWithKeyframes(before, after, &points), 2);
  EXPECT_LT((points[0].p_w - Vec3(1.0, 2.0, 3.0)).norm(), 1e-12);
  EXPECT_LT((after_1.inverse() * points[1].p_w - p_k1).norm(), 1e-12);  // same in its keyframe
  EXPECT_EQ(points[2].p_w, Vec3(-1.0, 0.5, 2.0));
}

TEST(PoseGraph, BadGraphsGiveAClearStatus) {
  const PoseGraphOptions options;
  PoseGraph empty;
  PoseGraphResult r = optimisePoseGraph(empty, options);
  EXPECT_EQ(r.status, PoseGraphStatus::kEmptyGraph);
  EXPECT_FALSE(r.ok());
  EXPECT_FALSE(r.message.empty());

  PoseGraph single;
  single.nodes.push_back({4, SE3(Mat3::Identity(), Vec3(1, 2, 3)), true});
  r = optimisePoseGraph(single, options);
  EXPECT_EQ(r.status, PoseGraphStatus::kNoEdges) << toString(r.status);
  ASSERT_EQ(r.poses.size(), 1u);
  EXPECT_EQ(r.poses[0].T_w_c.translation(), Vec3(1, 2, 3));

  PoseGraph missing = single;
  missing.edges.push_back(pgEdge(4, 9, SE3(), PoseGraphEdgeKind::kLoop));
  r = optimisePoseGraph(missing, options);
  EXPECT_EQ(r.status, PoseGraphStatus::kUnknownNode);
  EXPECT_NE(r.message.find("keyframe 9"), std::string::npos) << r.message;

  PoseGraph self = single;
  self.edges.push_back(pgEdge(4, 4, SE3(), PoseGraphEdgeKind::kOdometry));
  EXPECT_EQ(optimisePoseGraph(self, options).status, PoseGraphStatus::kBadEdge);

  PoseGraph pair = single;
  pair.nodes.push_back({5, SE3(), false});
  pair.edges.push_back(pgEdge(4, 5, SE3(), PoseGraphEdgeKind::kOdometry));
  PoseGraph zero_sigma = pair;
  zero_sigma.edges[0].sigma_r.z() = 0.0;
  EXPECT_EQ(optimisePoseGraph(zero_sigma, options).status, PoseGraphStatus::kBadEdge);

  PoseGraph duplicate = pair;
  duplicate.nodes.push_back({5, SE3(), false});
  EXPECT_EQ(optimisePoseGraph(duplicate, options).status, PoseGraphStatus::kDuplicateNode);

  PoseGraph unanchored = pair;
  unanchored.nodes.push_back({6, SE3(), false});
  unanchored.nodes.push_back({7, SE3(), false});
  unanchored.edges.push_back(pgEdge(6, 7, SE3(), PoseGraphEdgeKind::kOdometry));
  r = optimisePoseGraph(unanchored, options);
  EXPECT_EQ(r.status, PoseGraphStatus::kUnanchored);
  EXPECT_NE(r.message.find("keyframe 6"), std::string::npos) << r.message;

  r = optimisePoseGraph(pair, options);  // the good one: node 5 pulled onto node 4
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_LT(pgPositionError(r.poses[1].T_w_c, single.nodes[0].T_w_k), 1e-6);
}

TEST(PoseGraph, EdgeResidualMeasuresTheDisagreement) {
  PoseGraphEdge edge = pgEdge(0, 1, SE3(Mat3::Identity(), Vec3(1, 0, 0)),
                              PoseGraphEdgeKind::kOdometry);
  const SE3 T_w_b(expSO3(Vec3(0.0, 0.0, 2.0 * M_PI / 180.0)), Vec3(1.0, 0.03, 0.0));
  const PoseGraphEdgeResidual r = poseGraphEdgeResidual(edge, SE3(), T_w_b, 5.0);
  EXPECT_NEAR(r.translation_m, 0.03, 1e-12);
  EXPECT_NEAR(r.rotation_deg, 2.0, 1e-9);
  EXPECT_TRUE(r.disagrees);
  EXPECT_GT(r.whitened_norm, 3.0);
}

// Analytic Jacobians against central differences of left perturbations, far from the
// solution (an edge 20 deg and 0.5 m off), so that no small-error shortcut can pass.
TEST(PoseGraph, EdgeJacobiansMatchNumericDifferentiation) {
  PoseGraphEdge edge = pgEdge(0, 1, SE3(expSO3(Vec3(0.1, -0.2, 0.3)), Vec3(0.5, -1.0, 0.2)),
                              PoseGraphEdgeKind::kLoop);
  const SE3 T_w_a(expSO3(Vec3(0.4, 0.1, -0.7)), Vec3(1.0, 2.0, -0.5));
  const SE3 T_w_b(expSO3(Vec3(-0.2, 0.5, 0.9)), Vec3(2.5, 1.0, 0.3));
  Mat6 d_e_d_a, d_e_d_b;
  poseGraphEdgeError(edge, T_w_a, T_w_b, &d_e_d_a, &d_e_d_b);
  constexpr double kH = 1e-6;
  Mat6 numeric_a, numeric_b;
  for (int i = 0; i < 6; ++i) {
    const Vec6 step = Vec6::Unit(i) * kH;
    numeric_a.col(i) =
        (poseGraphEdgeError(edge, SE3::exp(step) * T_w_a, T_w_b, nullptr, nullptr) -
         poseGraphEdgeError(edge, SE3::exp(-step) * T_w_a, T_w_b, nullptr, nullptr)) / (2 * kH);
    numeric_b.col(i) =
        (poseGraphEdgeError(edge, T_w_a, SE3::exp(step) * T_w_b, nullptr, nullptr) -
         poseGraphEdgeError(edge, T_w_a, SE3::exp(-step) * T_w_b, nullptr, nullptr)) / (2 * kH);
  }
  EXPECT_LT((d_e_d_a - numeric_a).cwiseAbs().maxCoeff(), 1e-7) << d_e_d_a << "\n\n" << numeric_a;
  EXPECT_LT((d_e_d_b - numeric_b).cwiseAbs().maxCoeff(), 1e-7) << d_e_d_b << "\n\n" << numeric_b;
}

}  // namespace
}  // namespace rgbdslam
