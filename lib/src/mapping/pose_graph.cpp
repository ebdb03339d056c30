#include "rgbdslam/mapping/pose_graph.h"

#include <ceres/ceres.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <numeric>
#include <unordered_map>

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
template <typename T>
void poseGraphEdgeError(const T* t_w_a, const T* q_w_a, const T* t_w_b, const T* q_w_b,
                       const SE3& T_a_b, T* error) {
  using Quat = Eigen::Quaternion<T>;
  using V3 = Eigen::Matrix<T, 3, 1>;
  const Eigen::Map<const Quat> qa(q_w_a), qb(q_w_b);
  const Eigen::Map<const V3> ta(t_w_a), tb(t_w_b);
  const Quat q_a_w = qa.conjugate();
  const Quat q_a_b_est = q_a_w * qb;
  const V3 t_a_b_est = q_a_w * (tb - ta);
  const Quat dq = T_a_b.rotation().template cast<T>() * q_a_b_est.conjugate();
  Eigen::Map<Eigen::Matrix<T, 6, 1>> e(error);
  e.template head<3>() = t_a_b_est - T_a_b.translation().template cast<T>();
  e.template tail<3>() = T(2.0) * dq.vec();
}

class RelativePoseCost {
 public:
  explicit RelativePoseCost(const PoseGraphEdge& edge)
      : T_a_b_(edge.T_a_b),
        inv_sigma_((Vec6() << edge.sigma_t, edge.sigma_r).finished().cwiseInverse()) {}

  template <typename T>
  bool operator()(const T* t_w_a, const T* q_w_a, const T* t_w_b, const T* q_w_b,
                  T* residual) const {
    poseGraphEdgeError(t_w_a, q_w_a, t_w_b, q_w_b, T_a_b_, residual);
    for (int i = 0; i < 6; ++i) residual[i] *= T(inv_sigma_[i]);
    return true;
  }

 private:
  SE3 T_a_b_;
  Vec6 inv_sigma_;
};

struct NodeBlock {
  Eigen::Vector3d t;
  Eigen::Vector4d q;  // Eigen's coefficient order x, y, z, w (EigenQuaternionManifold)
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

SE3 poseOfNodeBlock(const NodeBlock& block) {
  return SE3(Eigen::Quaterniond(block.q), block.t);
}

}  // namespace

PoseGraphEdgeResidual poseGraphEdgeResidual(const PoseGraphEdge& edge, const SE3& T_w_a,
                                            const SE3& T_w_b, double disagree_sigmas) {
  const Vec3 ta = T_w_a.translation(), tb = T_w_b.translation();
  const Eigen::Vector4d qa = T_w_a.rotation().coeffs(), qb = T_w_b.rotation().coeffs();
  Vec6 e;
  poseGraphEdgeError(ta.data(), qa.data(), tb.data(), qb.data(), edge.T_a_b, e.data());
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

  std::vector<NodeBlock> blocks(graph.nodes.size());
  for (size_t i = 0; i < graph.nodes.size(); ++i) {
    blocks[i].t = graph.nodes[i].T_w_k.translation();
    blocks[i].q = graph.nodes[i].T_w_k.rotation().coeffs();
  }
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  ceres::EigenQuaternionManifold quaternion_manifold;
  for (const PoseGraphEdge& edge : graph.edges) {
    NodeBlock& a = blocks[index[edge.from]];
    NodeBlock& b = blocks[index[edge.to]];
    auto* cost = new ceres::AutoDiffCostFunction<RelativePoseCost, 6, 3, 4, 3, 4>(
        new RelativePoseCost(edge));
    ceres::LossFunction* loss = edge.kind == PoseGraphEdgeKind::kLoop ? makeLoopLoss(options)
                                                                       : nullptr;
    problem.AddResidualBlock(cost, loss, a.t.data(), a.q.data(), b.t.data(), b.q.data());
  }
  for (size_t i = 0; i < graph.nodes.size(); ++i) {
    if (!problem.HasParameterBlock(blocks[i].q.data())) continue;  // a node without edges
    problem.SetManifold(blocks[i].q.data(), &quaternion_manifold);
    if (graph.nodes[i].fixed) {
      problem.SetParameterBlockConstant(blocks[i].t.data());
      problem.SetParameterBlockConstant(blocks[i].q.data());
    }
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
    result.poses[i].T_w_c = poseOfNodeBlock(blocks[i]);
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
