// Applying a map version to the tracker's replica (MapReplica::apply), the work the tracking
// thread does between frames (issue 10, item 6: a frame must not wait long behind it). The
// replica is built as after a long flight: 'keyframes' keyframes of which 40 are hot (the
// local map; the others cold, their points without slots) and 120 points each (36 000 at
// 300 keyframes: the end of the 10-minute flight), all acknowledged.
//   BM_ApplyCull: a delta as the mapper sends after a bundle adjustment step and a cull: 40
//   keyframe poses, 2000 points moved, one keyframe culled (a cold one, as most culls are;
//   a different one each iteration: the map loses 120 points an iteration, at most 100).
//   BM_ApplyMoveAll: a delta moving every point and keyframe (a loop closure or a join).
// Counters: median and worst time of one apply. Target: well under a frame period (33 ms),
// and flat in the map's size for a cull.
// Run: taskset -c 0 build/bench/bench_map_replica
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <random>

#include <opencv2/imgproc.hpp>

#include "common/samples.h"
#include "rgbdslam/synth/scene.h"
#include "rgbdslam/tracking/map_replica.h"

namespace {

using namespace rgbdslam;

constexpr int kPointsPerKeyframe = 120;
constexpr int kHot = 40;

struct Built {
  std::unique_ptr<MapReplica> replica;
  int keyframes = 0;
};

const cv::Mat& image(PinholeCamera* camera) {
  static PinholeCamera cam;
  static const cv::Mat grey = [] {
    const SyntheticScene scene(*parseSyntheticSpec("room,frames=1"));
    cam = scene.camera();
    cv::Mat g;
    cv::cvtColor(scene.render(0).colour, g, cv::COLOR_BGR2GRAY);
    return g;
  }();
  *camera = cam;
  return grey;
}

Built build(int keyframes) {
  PinholeCamera camera;
  const cv::Mat& grey = image(&camera);
  Built b{std::make_unique<MapReplica>(camera), keyframes};
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(40.0, 600.0), v(40.0, 440.0), depth(1.0, 4.0);
  PointId next_point = 0;
  for (KeyframeId id = 0; id < keyframes; ++id) {
    KeyframeData data;
    data.id = id;
    data.T_w_c = SE3(Mat3::Identity(), Vec3(0.7 * static_cast<double>(id), 0, 0));
    data.grey = grey;
    b.replica->addKeyframe(makeKeyframe(data, KeyframeBuildOptions{}));
    for (int i = 0; i < kPointsPerKeyframe; ++i, ++next_point) {
      const Eigen::Vector2d uv(u(rng), v(rng));
      const Vec3 p_c = camera.unproject(uv, depth(rng));
      NewPoint point;
      point.point = MapPoint(MapPointData{next_point, data.T_w_c * p_c, id, uv, 0});
      point.measurement = Measurement{next_point, uv, 0, p_c.z()};
      b.replica->addProvisionalPoint(point);
    }
  }
  MapUpdate acked;
  acked.version = 1;
  acked.acked_below = keyframes;
  b.replica->apply(acked);
  std::vector<KeyframeId> window;
  for (KeyframeId id = keyframes - kHot; id < keyframes; ++id) window.push_back(id);
  b.replica->updateLocalMap(window, 0, keyframes, 90);
  return b;
}

double timedApply(MapReplica* replica, const MapUpdate& update) {
  const auto start = std::chrono::steady_clock::now();
  replica->apply(update);
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

void report(benchmark::State& state, const char* what, int keyframes, const RecentSamples& times) {
  state.counters["median_ms"] = times.quantile(0.5);
  state.counters["max_ms"] = times.quantile(1.0);
  std::printf("%s, %d keyframes (%d points, %d hot keyframes): %zu applies, median %.2f ms, max %.2f ms\n", what,
              keyframes, keyframes * kPointsPerKeyframe, kHot, times.size(), times.quantile(0.5), times.quantile(1.0));
}

void BM_ApplyCull(benchmark::State& state) {
  const int keyframes = static_cast<int>(state.range(0));
  Built b = build(keyframes);
  RecentSamples times(1 << 20);
  int64_t version = 2;
  KeyframeId culled = 1;
  std::mt19937 rng(11);
  std::uniform_int_distribution<PointId> any(0, static_cast<PointId>(keyframes) * kPointsPerKeyframe - 1);
  for (auto _ : state) {
    state.PauseTiming();
    MapUpdate delta;
    delta.version = version++;
    delta.acked_below = keyframes;
    for (KeyframeId id = keyframes - kHot; id < keyframes; ++id) {
      delta.keyframes.push_back({id, b.replica->map().keyframe(id)->T_w_c, 0});
    }
    while (delta.moved_points.size() < 2000) {
      const MapPoint* point = b.replica->map().point(any(rng));
      if (point) delta.moved_points.push_back(PointPosition{point->id, point->p_w + Vec3(0.001, 0, 0)});
    }
    delta.removed_keyframes = {culled++};
    state.ResumeTiming();
    times.add(timedApply(b.replica.get(), delta));
  }
  report(state, "a delta culling one keyframe, 2000 points moved", keyframes, times);
}

void BM_ApplyMoveAll(benchmark::State& state) {
  const int keyframes = static_cast<int>(state.range(0));
  Built b = build(keyframes);
  RecentSamples times(1 << 20);
  int64_t version = 2;
  for (auto _ : state) {
    state.PauseTiming();
    MapUpdate delta;
    delta.version = version++;
    delta.acked_below = keyframes;
    for (const auto& [id, keyframe] : b.replica->map().keyframes()) {
      delta.keyframes.push_back({id, SE3(Mat3::Identity(), Vec3(0, 0.001, 0)) * keyframe->T_w_c, 0});
    }
    for (const auto& [id, point] : b.replica->map().points()) {
      delta.moved_points.push_back(PointPosition{id, point.p_w + Vec3(0, 0.001, 0)});
    }
    state.ResumeTiming();
    times.add(timedApply(b.replica.get(), delta));
  }
  report(state, "a delta moving every keyframe and point", keyframes, times);
}

}  // namespace

BENCHMARK(BM_ApplyCull)->Arg(120)->Arg(300)->Unit(benchmark::kMillisecond)->Iterations(60);
BENCHMARK(BM_ApplyMoveAll)->Arg(120)->Arg(300)->Unit(benchmark::kMillisecond)->Iterations(10);
BENCHMARK_MAIN();
