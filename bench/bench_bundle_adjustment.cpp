// Bundle adjustment time against problem size (ARCHITECTURE.md: "BA time against problem
// size"). A synthetic corridor: keyframes 1 m apart along x looking sideways at a wall of
// points 2.5-4.5 m away, ~100-150 points visible per keyframe, each point seen by ~4
// keyframes, pixel noise 0.5 px and Kinect depth noise; poses and points perturbed by a few cm
// before every solve. Cases:
//   Global/N: all keyframes but the first free (depth BA, the default options).
//   Local/N:  PTAM-style local BA: the newest 5 keyframes free, the others fixed; only the
//             points seen by the free keyframes and only the keyframes that see them take part.
//   Global2d/N: global BA without the depth residuals.
// Counters: keyframes, free_keyframes, points, observations, iterations; time = one solve.
// Run: build-ba/bench/bench_bundle_adjustment
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <set>
#include <vector>

#include "rgbdslam/mapping/bundle_adjuster.h"

namespace {

using rgbdslam::BaKeyframe;
using rgbdslam::BaObservation;
using rgbdslam::BaOptions;
using rgbdslam::BaPoint;
using rgbdslam::BaProblem;
using rgbdslam::PinholeCamera;
using rgbdslam::SE3;
using rgbdslam::Vec3;

constexpr double kDepthNoiseA = 3.331e-3;  // [1/m]
constexpr double kPixelNoise = 0.5;        // [px]
constexpr double kPointsPerMetre = 32.0;   // along the corridor

const PinholeCamera& camera() {
  static const PinholeCamera c;  // 640x480, 525 px
  return c;
}

// Ground-truth corridor with measurements; poses and points at the truth.
BaProblem makeCorridor(int num_keyframes, std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0), uniform(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  BaProblem problem;
  problem.camera = &camera();
  for (int k = 0; k < num_keyframes; ++k) {
    const Vec3 w(0.03 * unit(rng), 0.1 * unit(rng), 0.03 * unit(rng));
    problem.keyframes.push_back(
        {k, SE3(rgbdslam::expSO3(w), Vec3(k * 1.0, 0.05 * unit(rng), 0)), false});
  }
  const int num_points = static_cast<int>(kPointsPerMetre * (num_keyframes + 4));
  for (int j = 0; j < num_points; ++j) {
    const Vec3 p_w(-2.0 + (num_keyframes + 4) * uniform(rng), 1.2 * unit(rng),
                   2.5 + 2.0 * uniform(rng));
    problem.points.push_back({j, p_w, false});
  }
  for (int k = 0; k < num_keyframes; ++k) {
    const SE3 T_c_w = problem.keyframes[k].T_w_c.inverse();
    for (int j = 0; j < num_points; ++j) {
      const Vec3 p_c = T_c_w * problem.points[j].p_w;
      const auto uv = camera().project(p_c);
      if (!uv || !camera().inImage(*uv, 8.0)) continue;
      BaObservation obs{k, j, *uv, uniform(rng) < 0.7 ? 0 : 1, 0.0};
      obs.uv += kPixelNoise * std::ldexp(1.0, obs.level) * Eigen::Vector2d(gauss(rng), gauss(rng));
      obs.depth = p_c.z() + kDepthNoiseA * p_c.z() * p_c.z() * gauss(rng);
      problem.observations.push_back(obs);
    }
  }
  return problem;
}

// Keeps the newest 'window' keyframes free, the points they see, and (fixed) every other
// keyframe that sees those points.
BaProblem localWindow(const BaProblem& global, int window) {
  const int n = static_cast<int>(global.keyframes.size());
  std::set<int> points;
  for (const BaObservation& obs : global.observations) {
    if (obs.keyframe_index >= n - window) points.insert(obs.point_index);
  }
  std::set<int> keyframes;
  for (const BaObservation& obs : global.observations) {
    if (points.count(obs.point_index)) keyframes.insert(obs.keyframe_index);
  }
  BaProblem local;
  local.camera = global.camera;
  std::vector<int> kf_map(n, -1), point_map(global.points.size(), -1);
  for (int k : keyframes) {
    kf_map[k] = static_cast<int>(local.keyframes.size());
    local.keyframes.push_back(global.keyframes[k]);
    local.keyframes.back().fixed = k < n - window || k == 0;
  }
  for (int j : points) {
    point_map[j] = static_cast<int>(local.points.size());
    local.points.push_back(global.points[j]);
  }
  for (const BaObservation& obs : global.observations) {
    if (point_map[obs.point_index] < 0) continue;
    local.observations.push_back(obs);
    local.observations.back().keyframe_index = kf_map[obs.keyframe_index];
    local.observations.back().point_index = point_map[obs.point_index];
  }
  return local;
}

void perturb(BaProblem* problem, std::mt19937& rng) {
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (BaKeyframe& kf : problem->keyframes) {
    if (kf.fixed) continue;
    const Vec3 dw(0.01 * gauss(rng), 0.01 * gauss(rng), 0.01 * gauss(rng));  // ~1 degree
    kf.T_w_c = SE3(rgbdslam::expSO3(dw) * kf.T_w_c.rotationMatrix(),
                   kf.T_w_c.translation() + 0.02 * Vec3(gauss(rng), gauss(rng), gauss(rng)));
  }
  for (BaPoint& p : problem->points) {
    if (!p.fixed) p.p_w += 0.03 * Vec3(gauss(rng), gauss(rng), gauss(rng));
  }
}

void runBa(benchmark::State& state, bool local, const BaOptions& options) {
  std::mt19937 rng(42);
  BaProblem truth = makeCorridor(static_cast<int>(state.range(0)), rng);
  truth.keyframes[0].fixed = true;
  if (local) truth = localWindow(truth, 5);
  const rgbdslam::BundleAdjuster adjuster(options);
  int iterations = 0, solves = 0, failures = 0;
  for (auto _ : state) {
    state.PauseTiming();
    BaProblem problem = truth;
    perturb(&problem, rng);
    state.ResumeTiming();
    const rgbdslam::BaResult result = adjuster.solve(&problem);
    iterations += result.iterations;
    ++solves;
    failures += result.status == rgbdslam::BaResult::Status::kFailed ||
                result.status == rgbdslam::BaResult::Status::kTooFewObservations;
  }
  int free_keyframes = 0;
  for (const BaKeyframe& kf : truth.keyframes) free_keyframes += !kf.fixed;
  state.counters["keyframes"] = static_cast<double>(truth.keyframes.size());
  state.counters["free_keyframes"] = free_keyframes;
  state.counters["points"] = static_cast<double>(truth.points.size());
  state.counters["observations"] = static_cast<double>(truth.observations.size());
  state.counters["iterations"] = solves > 0 ? double(iterations) / solves : 0.0;
  if (failures > 0) state.SkipWithError("a solve failed");
}

BaOptions withSolver(BaOptions::LinearSolver solver, bool use_depth = true) {
  BaOptions options;
  options.linear_solver = solver;
  options.use_depth = use_depth;
  return options;
}

void BM_GlobalBa(benchmark::State& state) { runBa(state, false, BaOptions{}); }
void BM_LocalBa(benchmark::State& state) { runBa(state, true, BaOptions{}); }
void BM_GlobalBa2d(benchmark::State& state) {
  runBa(state, false, withSolver(BaOptions::LinearSolver::kAuto, false));
}
void BM_GlobalBaDenseSchur(benchmark::State& state) {
  runBa(state, false, withSolver(BaOptions::LinearSolver::kDenseSchur));
}
void BM_GlobalBaSparseSchur(benchmark::State& state) {
  runBa(state, false, withSolver(BaOptions::LinearSolver::kSparseSchur));
}

}  // namespace

BENCHMARK(BM_GlobalBa)->Arg(5)->Arg(10)->Arg(20)->Arg(50)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LocalBa)->Arg(5)->Arg(10)->Arg(20)->Arg(50)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GlobalBa2d)->Arg(10)->Arg(50)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GlobalBaDenseSchur)
    ->Arg(10)
    ->Arg(20)
    ->Arg(50)
    ->Arg(100)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GlobalBaSparseSchur)
    ->Arg(10)
    ->Arg(20)
    ->Arg(50)
    ->Arg(100)
    ->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
