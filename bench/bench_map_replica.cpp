// Applying a map version to the tracker's replica (MapReplica::apply), the work the tracking
// thread does between frames (issue 10, item 6: a frame must not wait long behind it). The
// replica is built as after a long flight: 'keyframes' keyframes of which 40 are hot (the
// local map; the others cold, their points without slots) and 120 points each (36 000 at
// 300 keyframes: the end of the 10-minute flight), all acknowledged.
//   BM_ApplyCull: a delta as the mapper sends after a bundle adjustment step and a cull: 40
//   keyframe poses, 2000 points moved, one keyframe culled (a cold one, as most culls are;
//   a different one each iteration: the map loses 120 points an iteration, at most 100).
//   BM_ApplyMoveAll: a delta moving every point and keyframe (a loop closure or a join).
//   BM_ApplySnapshot: the whole map, every point nudged (after a lost delta, or the
//   mapper's fallback).
//   BM_ApplyBulkCull: 100 cold keyframes culled in one delta, half their points re-described
//   by keyframes that stay (as after a join where two parts overlap).
// Each whole (second argument 0), and as rgbd-tracker applies (1): the work on cold
// keyframes' points held back, then done in steps between frames; with the cold keyframes'
// points in memory (third argument 0) or on the keyframe store (1: tracker.local_map_store_points,
// the default since session 41).
// Counters: median and worst time of the block of work done at once, worst step. Target:
// both well under a frame period (33 ms), and flat in the map's size for a cull.
// Run: taskset -c 0 build/bench/bench_map_replica
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <random>
#include <string>

#include <opencv2/imgproc.hpp>

#include "common/samples.h"
#include "rgbdslam/synth/scene.h"
#include "rgbdslam/tracking/map_replica.h"

namespace {

using namespace rgbdslam;

constexpr int kPointsPerKeyframe = 120;
constexpr int kHot = 40;

struct Built {
  std::unique_ptr<KeyframeStore> store;  // cold keyframes' images, as on the flight computer
  std::unique_ptr<MapReplica> replica;
  int keyframes = 0;
  std::map<PointId, MapPointData> points;  // the map's points, as the mapper would have them
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

Built build(int keyframes, bool points_on_storage) {
  PinholeCamera camera;
  const cv::Mat& grey = image(&camera);
  Built b{nullptr, std::make_unique<MapReplica>(camera), keyframes, {}};
  if (auto store = KeyframeStore::open("/var/tmp")) {
    b.store = std::move(*store);
    b.replica->setStore(b.store.get(), points_on_storage);
  }
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(40.0, 600.0), v(40.0, 440.0), depth(1.0, 4.0);
  for (KeyframeId id = 0; id < keyframes; ++id) {
    KeyframeData data;
    data.id = id;
    data.T_w_c = SE3(Mat3::Identity(), Vec3(0.7 * static_cast<double>(id), 0, 0));
    data.grey = grey;
    b.replica->addKeyframe(makeKeyframe(data, KeyframeBuildOptions{}));
    for (int i = 0; i < kPointsPerKeyframe; ++i) {
      const Eigen::Vector2d uv(u(rng), v(rng));
      const Vec3 p_c = camera.unproject(uv, depth(rng));
      const PointId pid = provisionalPointId(id, i);
      NewPoint point;
      point.point = MapPoint(MapPointData{pid, data.T_w_c * p_c, id, uv, 0});
      point.measurement = Measurement{pid, uv, 0, p_c.z()};
      b.replica->addProvisionalPoint(point);
      b.points[pid] = point.point.data();
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

// With 'defer' (the second argument 1), as rgbd-tracker applies: the version's work on cold
// keyframes' points held back, then done kDeferredEntries at a time (its kDeferredMapEntries):
// 'at once' is the block between two frames, each step another.
constexpr size_t kDeferredEntries = 200;

struct Times {
  RecentSamples at_once{1 << 20}, steps{1 << 20};
};

double msSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

void timedApply(MapReplica* replica, const MapUpdate& update, bool defer, Times* times) {
  auto start = std::chrono::steady_clock::now();
  replica->apply(update, defer);
  times->at_once.add(msSince(start));
  for (size_t left = 1; left > 0;) {
    start = std::chrono::steady_clock::now();
    left = replica->applyDeferred(kDeferredEntries);
    if (defer) times->steps.add(msSince(start));
  }
}

void report(benchmark::State& state, const std::string& what, int keyframes, bool defer, bool on_storage,
            const Times& times) {
  state.counters["median_ms"] = times.at_once.quantile(0.5);
  state.counters["max_ms"] = times.at_once.quantile(1.0);
  state.counters["step_max_ms"] = times.steps.quantile(1.0);
  std::printf("%s, %d keyframes (%d points, %d hot keyframes; cold points %s), %s: %zu applies, median %.2f ms, max %.2f ms",
              what.c_str(), keyframes, keyframes * kPointsPerKeyframe, kHot, on_storage ? "on storage" : "in memory",
              defer ? "cold work held back" : "whole",
              times.at_once.size(), times.at_once.quantile(0.5), times.at_once.quantile(1.0));
  if (defer) {
    std::printf("; then %.1f steps of %zu entries an apply, median %.3f ms, max %.3f ms", 
                static_cast<double>(times.steps.size()) / static_cast<double>(std::max<size_t>(times.at_once.size(), 1)),
                kDeferredEntries, times.steps.quantile(0.5), times.steps.quantile(1.0));
  }
  std::printf("\n");
}

void BM_ApplyCull(benchmark::State& state) {
  const int keyframes = static_cast<int>(state.range(0));
  Built b = build(keyframes, state.range(2) != 0);
  Times times;
  const bool defer = state.range(1) != 0;
  int64_t version = 2;
  KeyframeId culled = 1;
  std::mt19937 rng(11);
  for (auto _ : state) {
    state.PauseTiming();
    MapUpdate delta;
    delta.version = version++;
    delta.acked_below = keyframes;
    for (KeyframeId id = keyframes - kHot; id < keyframes; ++id) {
      delta.keyframes.push_back({id, b.replica->map().keyframe(id)->T_w_c, 0});
    }
    std::vector<PointId> ids;
    for (const auto& [id, point] : b.points) ids.push_back(id);
    std::uniform_int_distribution<size_t> any(0, ids.size() - 1);
    while (delta.moved_points.size() < 2000) {
      MapPointData& point = b.points[ids[any(rng)]];
      point.p_w += Vec3(0.001, 0, 0);
      delta.moved_points.push_back(PointPosition{point.id, point.p_w});
    }
    delta.removed_keyframes = {culled};
    b.points.erase(b.points.lower_bound(provisionalPointId(culled, 0)), b.points.lower_bound(provisionalPointId(culled + 1, 0)));
    ++culled;
    state.ResumeTiming();
    timedApply(b.replica.get(), delta, defer, &times);
  }
  report(state, "a delta culling one keyframe, 2000 points moved", keyframes, defer, state.range(2) != 0, times);
}

// Every keyframe and point of the map nudged 1 mm along y: as moves in a delta (a loop
// closure or a join), or in full in a snapshot (in id order, as the mapper sends it).
MapUpdate everything(Built* b, int64_t version, bool snapshot) {
  MapUpdate update;
  update.version = version;
  update.is_snapshot = snapshot;
  update.acked_below = b->replica->map().keyframes().rbegin()->first + 1;
  const Vec3 nudge(0, 0.001, 0);
  for (const auto& [id, keyframe] : b->replica->map().keyframes()) {
    update.keyframes.push_back({id, SE3(Mat3::Identity(), nudge) * keyframe->T_w_c, 0});
  }
  for (auto& [id, point] : b->points) {
    point.p_w += nudge;
    if (snapshot) {
      update.points.push_back(point);
    } else {
      update.moved_points.push_back(PointPosition{id, point.p_w});
    }
  }
  return update;
}

void applyEverything(benchmark::State& state, bool snapshot) {
  const int keyframes = static_cast<int>(state.range(0));
  Built b = build(keyframes, state.range(2) != 0);
  Times times;
  const bool defer = state.range(1) != 0;
  int64_t version = 2;
  for (auto _ : state) {
    state.PauseTiming();
    const MapUpdate update = everything(&b, version++, snapshot);
    state.ResumeTiming();
    timedApply(b.replica.get(), update, defer, &times);
  }
  report(state, snapshot ? "a snapshot" : "a delta moving every keyframe and point", keyframes, defer, state.range(2) != 0,
         times);
}

void BM_ApplyMoveAll(benchmark::State& state) { applyEverything(state, false); }
// The mapper's whole map (after a lost delta, or its fallback every 30 s).
void BM_ApplySnapshot(benchmark::State& state) { applyEverything(state, true); }

// Many keyframes culled in one delta, as after a join where two parts overlap: 'culled' cold
// keyframes, half of each one's points re-described by a keyframe that stays (the mapper
// keeps points measured elsewhere), the other half removed. Once per built map.
void BM_ApplyBulkCull(benchmark::State& state) {
  const int keyframes = static_cast<int>(state.range(0)), culled = static_cast<int>(state.range(1));
  Times times;
  const bool defer = state.range(2) != 0;
  for (auto _ : state) {
    state.PauseTiming();
    Built b = build(keyframes, state.range(3) != 0);
    MapUpdate delta;
    delta.version = 2;
    delta.acked_below = keyframes;
    for (KeyframeId id = 1; id <= culled; ++id) {
      delta.removed_keyframes.push_back(id);
      const KeyframeId keeper = culled + 1 + id % (keyframes - culled - 1);
      bool keep = true;
      for (auto it = b.points.lower_bound(provisionalPointId(id, 0)); it != b.points.lower_bound(provisionalPointId(id + 1, 0)); ++it) {
        if (keep) {
          delta.points.push_back(MapPointData{it->first, it->second.p_w, keeper, it->second.uv, 0});
        } else {
          delta.removed_points.push_back(it->first);
        }
        keep = !keep;
      }
    }
    state.ResumeTiming();
    timedApply(b.replica.get(), delta, defer, &times);
    state.PauseTiming();
    b = Built{};
    state.ResumeTiming();
  }
  report(state, "a delta culling " + std::to_string(culled) + " keyframes", keyframes, defer, state.range(3) != 0, times);
}

}  // namespace

BENCHMARK(BM_ApplyCull)->ArgsProduct({{120, 300}, {0, 1}, {0, 1}})->Unit(benchmark::kMillisecond)->Iterations(60);
BENCHMARK(BM_ApplyMoveAll)->ArgsProduct({{120, 300}, {0, 1}, {0, 1}})->Unit(benchmark::kMillisecond)->Iterations(10);
BENCHMARK(BM_ApplySnapshot)->ArgsProduct({{120, 300}, {0, 1}, {0, 1}})->Unit(benchmark::kMillisecond)->Iterations(10);
BENCHMARK(BM_ApplyBulkCull)->ArgsProduct({{300}, {100}, {0, 1}, {0, 1}})->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK_MAIN();
