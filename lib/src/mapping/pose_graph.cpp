#include "rgbdslam/mapping/pose_graph.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <array>

#include <chrono>
#include <cmath>
#include <memory>
#include <numeric>
#include <unordered_map>

#include "rgbdslam/mapping/bundle_adjuster.h"

namespace rgbdslam {

void PoseGraphOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "loop_loss", &loop_loss,
          {{"cauchy", LoopLoss::kCauchy}, {"huber", LoopLoss::kHuber}, {"none", LoopLoss::kNone}},
          "robust loss on loop edges");
  r->bind(s, "loop_loss_scale", &loop_loss_scale, 1e-3, 1e3, "sigmas",
          "where the loop edges' loss leaves the quadratic");
  r->bind(s, "disagree_sigmas", &disagree_sigmas, 1e-3, 1e6, "sigmas",
          "an edge whose residual after the solve exceeds this disagrees with the graph");
  r->bind(s, "max_iterations", &max_iterations, 1, 10000, "iterations",
          "Levenberg-Marquardt iterations");
  r->bind(s, "function_tolerance", &function_tolerance, 0.0, 1.0, "-",
          "stop when the relative cost change is below this");
  r->bind(s, "gradient_tolerance", &gradient_tolerance, 0.0, 1.0, "-",
          "stop when the largest gradient entry is below this");
  r->bind(s, "parameter_tolerance", &parameter_tolerance, 0.0, 1.0, "-",
          "stop when the relative step is below this");
  r->bind(s, "num_threads", &num_threads, 1, 64, "threads", "Ceres threads");
}

const char* toString(PoseGraphEdgeKind kind) {
  switch (kind) {
    case PoseGraphEdgeKind::kOdometry: return "odometry";
    case PoseGraphEdgeKind::kCovisible: return "covisible";
    case PoseGraphEdgeKind::kLoop: return "loop";
  }
  return "?";
}

const char* toString(PoseGraphStatus status) {
  switch (status) {
    case PoseGraphStatus::kConverged: return "converged";
    case PoseGraphStatus::kMaxIterations: return "max-iterations";
    case PoseGraphStatus::kNoEdges: return "no-edges";
    case PoseGraphStatus::kEmptyGraph: return "empty-graph";
    case PoseGraphStatus::kDuplicateNode: return "duplicate-node";
    case PoseGraphStatus::kUnknownNode: return "unknown-node";
    case PoseGraphStatus::kBadEdge: return "bad-edge";
    case PoseGraphStatus::kUnanchored: return "unanchored";
    case PoseGraphStatus::kSolverFailed: return "solver-failed";
  }
  return "?";
}

namespace {

// The unwhitened residual of an edge (translation, then 2 x the rotation's vector part), for
// doubles and Ceres' jets alike.
// Whitened residual of one edge on two pose blocks (ba_ceres layout: q then t, T_w_k), with
// the Jacobians in the bundle adjuster's lifted form: 6 tangent columns, then a zero column
// (ba_ceres::PoseManifold::PlusJacobian is [I6; 0]).
class RelativePoseCost final
    : public ceres::SizedCostFunction<6, ba_ceres::kPoseBlockSize, ba_ceres::kPoseBlockSize> {
 public:
  explicit RelativePoseCost(const PoseGraphEdge& edge) : edge_(edge) {
    inv_sigma_ << edge.sigma_t.cwiseInverse(), edge.sigma_r.cwiseInverse();
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    using LiftedJacobian =
        Eigen::Matrix<double, 6, ba_ceres::kPoseBlockSize, Eigen::RowMajor>;
    const bool want = jacobians != nullptr && (jacobians[0] != nullptr || jacobians[1] != nullptr);
    Mat6 d_e_d_a, d_e_d_b;
    const Vec6 e = poseGraphEdgeError(edge_, ba_ceres::poseFromBlock(parameters[0]),
                                      ba_ceres::poseFromBlock(parameters[1]),
                                      want ? &d_e_d_a : nullptr, want ? &d_e_d_b : nullptr);
    Eigen::Map<Vec6> residual(residuals);
    residual = inv_sigma_.asDiagonal() * e;
    for (int i = 0; want && i < 2; ++i) {
      if (jacobians[i] == nullptr) continue;
      Eigen::Map<LiftedJacobian> J(jacobians[i]);
      J.leftCols<6>() = inv_sigma_.asDiagonal() * (i == 0 ? d_e_d_a : d_e_d_b);
      J.rightCols<1>().setZero();
    }
    return true;
  }

 private:
  PoseGraphEdge edge_;
  Vec6 inv_sigma_;
};

int findRoot(std::vector<int>* parent, int i) {
  while ((*parent)[i] != i) i = (*parent)[i] = (*parent)[(*parent)[i]];
  return i;
}

// The checks that need no solver; on success fills index (keyframe id -> node index).
PoseGraphStatus checkGraph(const PoseGraph& graph, std::unordered_map<KeyframeId, int>* index,
                           std::string* message) {
  if (graph.nodes.empty()) {
    *message = "the pose graph has no nodes";
    return PoseGraphStatus::kEmptyGraph;
  }
  for (size_t i = 0; i < graph.nodes.size(); ++i) {
    if (!index->emplace(graph.nodes[i].id, static_cast<int>(i)).second) {
      *message = "keyframe " + std::to_string(graph.nodes[i].id) + " is a node twice";
      return PoseGraphStatus::kDuplicateNode;
    }
  }
  std::vector<int> parent(graph.nodes.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (size_t e = 0; e < graph.edges.size(); ++e) {
    const PoseGraphEdge& edge = graph.edges[e];
    const std::string name = "edge " + std::to_string(e) + " (" + toString(edge.kind) + ", " +
                             std::to_string(edge.from) + " -> " + std::to_string(edge.to) + ")";
    if (!index->count(edge.from) || !index->count(edge.to)) {
      *message = name + " names keyframe " +
                 std::to_string(index->count(edge.from) ? edge.to : edge.from) +
                 ", which is not a node";
      return PoseGraphStatus::kUnknownNode;
    }
    if (edge.from == edge.to || !(edge.sigma_t.minCoeff() > 0.0) ||
        !(edge.sigma_r.minCoeff() > 0.0)) {
      *message = name + (edge.from == edge.to ? " joins a node to itself"
                                              : " has a sigma that is not > 0");
      return PoseGraphStatus::kBadEdge;
    }
    parent[findRoot(&parent, index->at(edge.from))] = findRoot(&parent, index->at(edge.to));
  }
  if (graph.edges.empty()) {
    *message = "the pose graph has no edges: nothing to optimise";
    return PoseGraphStatus::kNoEdges;
  }
  std::vector<bool> anchored(graph.nodes.size(), false);
  for (size_t i = 0; i < graph.nodes.size(); ++i) {
    if (graph.nodes[i].fixed) anchored[findRoot(&parent, static_cast<int>(i))] = true;
  }
  for (size_t i = 0; i < graph.nodes.size(); ++i) {
    if (!anchored[findRoot(&parent, static_cast<int>(i))]) {
      *message = "keyframe " + std::to_string(graph.nodes[i].id) +
                 " is in a part of the graph with no fixed keyframe (its pose is free)";
      return PoseGraphStatus::kUnanchored;
    }
  }
  return PoseGraphStatus::kConverged;
}

ceres::LossFunction* makeLoopLoss(const PoseGraphOptions& options) {
  switch (options.loop_loss) {
    case PoseGraphOptions::LoopLoss::kCauchy: return new ceres::CauchyLoss(options.loop_loss_scale);
    case PoseGraphOptions::LoopLoss::kHuber: return new ceres::HuberLoss(options.loop_loss_scale);
    case PoseGraphOptions::LoopLoss::kNone: return nullptr;
  }
  return nullptr;
}

ceres::Solver::Options poseGraphSolverOptions(const PoseGraphOptions& options) {
  ceres::Solver::Options o;
  o.minimizer_type = ceres::TRUST_REGION;
  o.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  o.max_num_iterations = options.max_iterations;
  o.function_tolerance = options.function_tolerance;
  o.gradient_tolerance = options.gradient_tolerance;
  o.parameter_tolerance = options.parameter_tolerance;
  o.num_threads = options.num_threads;
  o.logging_type = ceres::SILENT;
  o.minimizer_progress_to_stdout = false;
  if (ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE)) {
    o.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    o.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  } else if (ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::EIGEN_SPARSE)) {
    o.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    o.sparse_linear_algebra_library_type = ceres::EIGEN_SPARSE;
  } else {
    o.linear_solver_type = ceres::CGNR;
  }
  return o;
}


}  // namespace

Vec6 poseGraphEdgeError(const PoseGraphEdge& edge, const SE3& T_w_a, const SE3& T_w_b,
                        Mat6* d_e_d_a, Mat6* d_e_d_b) {
  const Mat3 R_a_w = T_w_a.rotationMatrix().transpose();
  const Vec3 t_w_b = T_w_b.translation();
  const Eigen::Quaterniond M_q = edge.T_a_b.rotation() * T_w_b.rotation().conjugate();
  const Eigen::Quaterniond dq = M_q * T_w_a.rotation();  // q_a_b (q_w_a^-1 q_w_b)^-1
  Vec6 e;
  e.head<3>() = R_a_w * (t_w_b - T_w_a.translation()) - edge.T_a_b.translation();
  e.tail<3>() = 2.0 * dq.vec();
  if (d_e_d_a != nullptr && d_e_d_b != nullptr) {
    // Left perturbations T <- exp(delta) T, delta = (v, w): t <- t + v - [t]x w,
    // q <- exp(w) q. The rotation part: dq <- [1, M w / 2] dq for a (M = R_a_b R_w_b^T),
    // the same with -w for b, and d vec([1, u/2] dq) / du = (dq_w I - [dq_vec]x) / 2.
    const Mat3 d_er_d_u = dq.w() * Mat3::Identity() - skew(dq.vec());
    const Mat3 d_er_d_wa = d_er_d_u * M_q.toRotationMatrix();
    d_e_d_a->setZero();
    d_e_d_a->block<3, 3>(0, 0) = -R_a_w;
    d_e_d_a->block<3, 3>(0, 3) = R_a_w * skew(t_w_b);
    d_e_d_a->block<3, 3>(3, 3) = d_er_d_wa;
    d_e_d_b->setZero();
    d_e_d_b->block<3, 3>(0, 0) = R_a_w;
    d_e_d_b->block<3, 3>(0, 3) = -R_a_w * skew(t_w_b);
    d_e_d_b->block<3, 3>(3, 3) = -d_er_d_wa;
  }
  return e;
}

PoseGraphEdgeResidual poseGraphEdgeResidual(const PoseGraphEdge& edge, const SE3& T_w_a,
                                            const SE3& T_w_b, double disagree_sigmas) {
  const Vec6 e = poseGraphEdgeError(edge, T_w_a, T_w_b, nullptr, nullptr);
  const Vec6 whitened = e.cwiseQuotient((Vec6() << edge.sigma_t, edge.sigma_r).finished());
  PoseGraphEdgeResidual r;
  r.whitened_norm = whitened.norm();
  r.translation_m = e.head<3>().norm();
  // |2 vec(dq)| = 2 sin(angle / 2): back to the angle (sign of w irrelevant).
  r.rotation_deg = 2.0 * std::asin(std::min(1.0, 0.5 * e.tail<3>().norm())) * 180.0 / M_PI;
  r.disagrees = r.whitened_norm > disagree_sigmas;
  return r;
}

PoseGraphResult optimisePoseGraph(const PoseGraph& graph, const PoseGraphOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  PoseGraphResult result;
  for (const PoseGraphNode& node : graph.nodes) result.poses.push_back({node.id, node.T_w_k});
  std::unordered_map<KeyframeId, int> index;
  result.status = checkGraph(graph, &index, &result.message);
  const auto finish = [&]() -> PoseGraphResult {
    for (const PoseGraphEdge& edge : graph.edges) {
      if (!index.count(edge.from) || !index.count(edge.to)) break;
      result.edges.push_back(poseGraphEdgeResidual(edge, result.poses[index[edge.from]].T_w_c,
                                                   result.poses[index[edge.to]].T_w_c,
                                                   options.disagree_sigmas));
      if (edge.kind == PoseGraphEdgeKind::kLoop && result.edges.back().disagrees) {
        ++result.loop_edges_disagreeing;
      }
    }
    result.time_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return result;
  };
  if (result.status != PoseGraphStatus::kConverged) {
    if (result.status != PoseGraphStatus::kNoEdges) result.edges.clear();
    return result.status == PoseGraphStatus::kNoEdges ? finish() : result;
  }

  // One block per node: T_w_k as ba_ceres lays a pose out (q x, y, z, w, then t).
  std::vector<std::array<double, ba_ceres::kPoseBlockSize>> blocks(graph.nodes.size());
  for (size_t i = 0; i < graph.nodes.size(); ++i) {
    ba_ceres::poseToBlock(graph.nodes[i].T_w_k, blocks[i].data());
  }
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  ba_ceres::PoseManifold pose_manifold;  // T <- exp(delta) T
  for (const PoseGraphEdge& edge : graph.edges) {
    ceres::LossFunction* loss = edge.kind == PoseGraphEdgeKind::kLoop ? makeLoopLoss(options)
                                                                       : nullptr;
    problem.AddResidualBlock(new RelativePoseCost(edge), loss, blocks[index[edge.from]].data(),
                             blocks[index[edge.to]].data());
  }
  for (size_t i = 0; i < graph.nodes.size(); ++i) {
    if (!problem.HasParameterBlock(blocks[i].data())) continue;  // a node without edges
    problem.SetManifold(blocks[i].data(), &pose_manifold);
    if (graph.nodes[i].fixed) problem.SetParameterBlockConstant(blocks[i].data());
  }

  ceres::Solver::Summary summary;
  ceres::Solve(poseGraphSolverOptions(options), &problem, &summary);
  result.initial_cost = summary.initial_cost;
  result.final_cost = summary.final_cost;
  result.iterations = static_cast<int>(summary.iterations.size()) - 1;  // 0 = the start
  if (summary.termination_type == ceres::FAILURE || !summary.IsSolutionUsable()) {
    result.status = PoseGraphStatus::kSolverFailed;
    result.message = "Ceres: " + summary.message;
    return finish();
  }
  result.status = summary.termination_type == ceres::NO_CONVERGENCE
                      ? PoseGraphStatus::kMaxIterations
                      : PoseGraphStatus::kConverged;
  for (size_t i = 0; i < graph.nodes.size(); ++i) {
    result.poses[i].T_w_c = ba_ceres::poseFromBlock(blocks[i].data());
  }
  return finish();
}

int movePointsWithKeyframes(const std::vector<KeyframePose>& before,
                            const std::vector<KeyframePose>& after,
                            std::vector<MapPointData>* points) {
  std::unordered_map<KeyframeId, SE3> old_pose, correction;
  for (const KeyframePose& k : before) old_pose[k.id] = k.T_w_c;
  for (const KeyframePose& k : after) {
    const auto it = old_pose.find(k.id);
    if (it != old_pose.end()) correction[k.id] = k.T_w_c * it->second.inverse();
  }
  int moved = 0;
  for (MapPointData& point : *points) {
    const auto it = correction.find(point.source_keyframe);
    if (it == correction.end()) continue;
    point.p_w = it->second * point.p_w;
    ++moved;
  }
  return moved;
}

}  // namespace rgbdslam
