// Pose-graph optimisation time against the number of keyframes (issue 11: 1000 keyframes
// within 200 ms). A flight of laps around a 12.5 m square, 100 keyframes per lap, 0.5 m
// apart; odometry edges between consecutive keyframes with Gaussian noise (1 cm, 0.06 deg
// per axis) and a yaw bias of 0.03 deg per step, weighted as 1 cm, 0.17 deg; loop edges
// (2 cm, 0.5 deg) from every 25th keyframe of laps after the first to the same place in
// the first lap, and from the last keyframe to keyframe 0; keyframe 0 fixed. Nodes start
// at the chained odometry.
// Counters: keyframes, edges, loop_edges, iterations, max_error_before / _after [m] (the
// largest keyframe position error against the truth), loops_disagreeing (loop edges over
// disagree_sigmas after the solve). Time = one optimisePoseGraph() call.
// Run: build/bench/bench_pose_graph
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "rgbdslam/mapping/pose_graph.h"

namespace {

using rgbdslam::KeyframePose;
using rgbdslam::PoseGraph;
using rgbdslam::PoseGraphEdge;
using rgbdslam::PoseGraphEdgeKind;
using rgbdslam::SE3;
using rgbdslam::Vec3;

constexpr int kLap = 100, kSide = 25;
constexpr double kStep = 0.5;           // [m]
constexpr double kYawBias = 0.0005;     // [rad per step]
constexpr double kOdomSigmaT = 0.01;    // [m]
constexpr double kOdomSigmaR = 0.003;   // [rad]
constexpr double kOdomNoiseR = 0.001;   // [rad]
constexpr double kLoopSigmaT = 0.02;    // [m]
constexpr double kLoopSigmaR = 0.0087;  // [rad]

SE3 lapPose(int k) {
  const int side = (k % kLap) / kSide, j = k % kSide;
  static const Vec3 corners[4] = {{0, 0, 0}, {12.5, 0, 0}, {12.5, 12.5, 0}, {0, 12.5, 0}};
  const rgbdslam::Mat3 R = rgbdslam::expSO3(Vec3(0, 0, side * M_PI / 2.0));
  return SE3(R, corners[side] + R * Vec3(j * kStep, 0, 0));
}

PoseGraphEdge edgeOf(int a, int b, const SE3& T_a_b, PoseGraphEdgeKind kind) {
  const bool loop = kind == PoseGraphEdgeKind::kLoop;
  PoseGraphEdge edge;
  edge.from = a;
  edge.to = b;
  edge.T_a_b = T_a_b;
  edge.kind = kind;
  edge.sigma_t = Vec3::Constant(loop ? kLoopSigmaT : kOdomSigmaT);
  edge.sigma_r = Vec3::Constant(loop ? kLoopSigmaR : kOdomSigmaR);
  return edge;
}

PoseGraph makeFlight(int num_keyframes, int* loop_edges) {
  std::mt19937 rng(7);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const auto noise = [&](double sigma) -> Vec3 {  // a Vec3, not an expression on a temporary
    return Vec3(gauss(rng), gauss(rng), gauss(rng)) * sigma;
  };
  PoseGraph graph;
  SE3 T_w_k = lapPose(0);
  graph.nodes.push_back({0, T_w_k, true});
  for (int k = 0; k + 1 < num_keyframes; ++k) {
    const SE3 error(rgbdslam::expSO3(noise(kOdomNoiseR) + Vec3(0, 0, kYawBias)),
                    noise(kOdomSigmaT));
    const SE3 T_k_next = lapPose(k).inverse() * lapPose(k + 1) * error;
    graph.edges.push_back(edgeOf(k, k + 1, T_k_next, PoseGraphEdgeKind::kOdometry));
    T_w_k = T_w_k * T_k_next;
    graph.nodes.push_back({k + 1, T_w_k, false});
  }
  *loop_edges = 0;
  for (int k = kLap; k < num_keyframes; k += kSide) {
    graph.edges.push_back(edgeOf(k, k % kLap, lapPose(k).inverse() * lapPose(k % kLap),
                                 PoseGraphEdgeKind::kLoop));
    ++*loop_edges;
  }
  const int last = num_keyframes - 1;
  graph.edges.push_back(
      edgeOf(last, 0, lapPose(last).inverse() * lapPose(0), PoseGraphEdgeKind::kLoop));
  ++*loop_edges;
  return graph;
}

double maxError(const std::vector<KeyframePose>& poses) {
  double worst = 0.0;
  for (const KeyframePose& p : poses) {
    const Vec3 truth = lapPose(static_cast<int>(p.id)).translation();
    worst = std::max(worst, (p.T_w_c.translation() - truth).norm());
  }
  return worst;
}

void runPoseGraph(benchmark::State& state, const rgbdslam::PoseGraphOptions& options) {
  int loop_edges = 0;
  const PoseGraph graph = makeFlight(static_cast<int>(state.range(0)), &loop_edges);
  std::vector<KeyframePose> before;
  for (const auto& node : graph.nodes) before.push_back({node.id, node.T_w_k});
  rgbdslam::PoseGraphResult result;
  for (auto _ : state) {
    result = optimisePoseGraph(graph, options);
    benchmark::DoNotOptimize(result.final_cost);
  }
  if (!result.ok()) state.SkipWithError(result.message.c_str());
  state.counters["keyframes"] = static_cast<double>(graph.nodes.size());
  state.counters["edges"] = static_cast<double>(graph.edges.size());
  state.counters["loop_edges"] = loop_edges;
  state.counters["iterations"] = result.iterations;
  state.counters["max_error_before"] = maxError(before);
  state.counters["max_error_after"] = maxError(result.poses);
  state.counters["loops_disagreeing"] = result.loop_edges_disagreeing;
}

// The default options (Cauchy on the loop edges).
void BM_PoseGraph(benchmark::State& state) { runPoseGraph(state, rgbdslam::PoseGraphOptions()); }

// For comparison: every loop edge trusted (quadratic), as when all loops are right.
void BM_PoseGraphQuadraticLoops(benchmark::State& state) {
  rgbdslam::PoseGraphOptions options;
  options.loop_loss = rgbdslam::PoseGraphOptions::LoopLoss::kNone;
  runPoseGraph(state, options);
}

}  // namespace

BENCHMARK(BM_PoseGraph)->Arg(100)->Arg(300)->Arg(1000)->Arg(3000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PoseGraphQuadraticLoops)->Arg(100)->Arg(1000)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
