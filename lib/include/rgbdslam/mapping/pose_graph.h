#pragma once
// Pose-graph optimisation over keyframes (issue 11, item 2; the loop closer's,
// loop_closer.h). Closes loops: the keyframe poses T_w_k are moved so that the
// relative-pose edges (odometry between consecutive keyframes, covisible pairs) and the loop
// edges (place recognition's T_k_q) agree as well as their uncertainties allow.
//
// Model: for an edge a -> b with measurement T_a_b and 1-sigma noise (sigma_t [m] per axis,
// sigma_r [rad] per axis, both in frame a), the residual is
//   e = W * [ R_w_a^T (t_w_b - t_w_a) - t_a_b ;  2 vec(q_a_b * (q_w_a^-1 q_w_b)^-1) ]
// (translation first, then rotation, as SE3's tangent), W = diag(1 / sigma), with analytic
// Jacobians. Odometry and covisibility edges are quadratic; loop edges go through a Cauchy
// loss of scale loop_loss_scale sigmas, so a wrong loop pulls with a bounded force and the
// map moves by about c^2 sigma_chain^2 / D (D the loop's disagreement). The same choice
// leaves a correct loop open when its disagreement exceeds about c sigma_chain^2 /
// (2 sigma_loop): odometry sigmas must cover the drift (docs/design.md "Pose graph").
// Solved by Levenberg-Marquardt (Ceres, sparse normal Cholesky), each pose a block and
// manifold as in bundle adjustment (ba_ceres::PoseManifold: T_w_k <- exp(delta) T_w_k).
//
// Call order: fill a PoseGraph (nodes with their current T_w_k, at least one fixed; edges
// naming nodes by keyframe id), call optimisePoseGraph(), check the status, read the new
// poses and every edge's residual from the result; reject loop edges marked 'disagrees' and,
// if any, optimise again without them. Then move the points with movePointsWithKeyframes().
//
// Cost: memory and time grow with the number of keyframes and edges (a sparse system of
// 6 x keyframes unknowns); measured in bench/bench_pose_graph.cpp. No state between calls.
#include <string>
#include <vector>

#include "rgbdslam/geometry/se3.h"
#include "rgbdslam/map/map_types.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

struct PoseGraphOptions {
  enum class LoopLoss {
    kCauchy,  // rho(s) = c^2 log(1 + s / c^2): a far-off loop edge pulls ever less (default)
    kHuber,   // linear beyond c: bounded pull, but it never fades (a wrong edge still bends)
    kNone,    // quadratic: trust every loop edge (tests and comparisons only)
  };
  LoopLoss loop_loss = LoopLoss::kCauchy;  // the robust loss on loop edges
  double loop_loss_scale = 1.0;  // c, where the loss leaves the quadratic [sigmas]; > 0
  double disagree_sigmas = 5.0;  // after the solve, an edge whose whitened residual norm
                                 // exceeds this disagrees with the graph [sigmas]; > 0
  int max_iterations = 100;      // Levenberg-Marquardt iterations; >= 1
  double function_tolerance = 1e-6;  // stop when |cost change| / cost < this [-]; 1e-8
                                     // takes 1.7x the time for < 0.1 mm (bench_pose_graph)
  double gradient_tolerance = 1e-10; // stop when max |gradient| < this (Ceres' scaling)
  double parameter_tolerance = 1e-8; // stop when |step| / (|x| + tol) < this [-]
  int num_threads = 1;           // Ceres threads (the mapper runs beside the tracker)

  // Every field, as section.<field name>.
  void bind(OptionRegistry* registry, const std::string& section = "pose_graph");
};

struct PoseGraphNode {
  KeyframeId id = -1;  // the map's keyframe id; unique in the graph
  SE3 T_w_k;           // the keyframe's pose in the world (its initial value) [m]
  bool fixed = false;  // held where it is (the gauge: at least one per connected part)
};

enum class PoseGraphEdgeKind {
  kOdometry,    // consecutive keyframes (from the map after bundle adjustment)
  kCovisible,   // keyframes that share points
  kLoop,        // from place recognition (PlaceVerification::T_k_q, sigma): robust loss
};
const char* toString(PoseGraphEdgeKind kind);

struct PoseGraphEdge {
  KeyframeId from = -1;            // a
  KeyframeId to = -1;              // b
  SE3 T_a_b;                       // measured pose of b in a's frame [m]
  Vec3 sigma_t = Vec3::Constant(0.01);   // 1-sigma noise of the translation, in a [m]; > 0
  Vec3 sigma_r = Vec3::Constant(0.005);  // 1-sigma noise of the rotation, per axis [rad]; > 0
  PoseGraphEdgeKind kind = PoseGraphEdgeKind::kOdometry;
};

struct PoseGraph {
  std::vector<PoseGraphNode> nodes;
  std::vector<PoseGraphEdge> edges;
};

enum class PoseGraphStatus {
  kConverged,         // a solution (tolerances met)
  kMaxIterations,     // a usable solution, but the iteration limit stopped it
  kNoEdges,           // nodes but nothing relating them: poses returned unchanged
  kEmptyGraph,        // no nodes
  kDuplicateNode,     // two nodes with one keyframe id
  kUnknownNode,       // an edge names a keyframe that is not a node
  kBadEdge,           // an edge from a node to itself, or a sigma that is not > 0
  kUnanchored,        // a connected part of the graph has no fixed node (gauge free)
  kSolverFailed,      // Ceres reported a failure; poses returned unchanged
};
const char* toString(PoseGraphStatus status);

struct PoseGraphEdgeResidual {
  double whitened_norm = 0.0;  // |e| in sigmas, before the robust loss [-]
  double translation_m = 0.0;  // |translation part| of the disagreement [m]
  double rotation_deg = 0.0;   // angle of the rotation part [deg]
  bool disagrees = false;      // whitened_norm > disagree_sigmas
};

struct PoseGraphResult {
  PoseGraphStatus status = PoseGraphStatus::kEmptyGraph;
  std::string message;                       // what went wrong, naming the node or edge
  std::vector<KeyframePose> poses;           // the new T_w_k, in the order of the nodes
  std::vector<PoseGraphEdgeResidual> edges;  // after the solve, in the order of the edges
  double initial_cost = 0.0;                 // Ceres' cost (1/2 sum rho(|e|^2)) before
  double final_cost = 0.0;                   // ...and after
  int iterations = 0;                        // Levenberg-Marquardt iterations
  double time_ms = 0.0;                      // wall time of the whole call [ms]
  int loop_edges_disagreeing = 0;            // loop edges with disagrees set
  bool ok() const {
    return status == PoseGraphStatus::kConverged || status == PoseGraphStatus::kMaxIterations;
  }
};

// Checks the graph, builds the problem, solves it. Never throws on a bad graph: the status
// says what is wrong and the poses are the input ones.
PoseGraphResult optimisePoseGraph(const PoseGraph& graph, const PoseGraphOptions& options);

// The unwhitened error e of an edge (the model above) and, when both pointers are given, its
// Jacobians with respect to left perturbations T <- exp(delta) T of T_w_a and T_w_b (delta
// = (v, w) as SE3::exp, in the world frame). Checked numerically in the tests.
using Mat6 = Eigen::Matrix<double, 6, 6>;
Vec6 poseGraphEdgeError(const PoseGraphEdge& edge, const SE3& T_w_a, const SE3& T_w_b,
                        Mat6* d_e_d_a, Mat6* d_e_d_b);

// The residual of one edge for the given poses (used by the result).
PoseGraphEdgeResidual poseGraphEdgeResidual(const PoseGraphEdge& edge, const SE3& T_w_a,
                                            const SE3& T_w_b, double disagree_sigmas);

// Moves each point rigidly with its source keyframe: p_w' = T_w_k' * T_w_k^-1 * p_w, with
// T_w_k the keyframe's pose before and T_w_k' after the optimisation. Points whose source
// keyframe is not in both lists are left where they are; returns how many moved.
int movePointsWithKeyframes(const std::vector<KeyframePose>& before,
                            const std::vector<KeyframePose>& after,
                            std::vector<MapPointData>* points);

}  // namespace rgbdslam
