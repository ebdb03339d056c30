// Frames per second of the synthetic renderer at 640x480 on one core (render() includes ray
// casting, image noise and the Kinect depth model). Target: >= 30 frames/s for the room.
// Run: build/bench/bench_synthetic (items_per_second = frames/s).
#include <benchmark/benchmark.h>

#include "rgbdslam/synth/scene.h"

namespace {

void renderFrames(benchmark::State& state, const std::string& spec) {
  const auto options = rgbdslam::parseSyntheticSpec(spec);
  if (!options) {
    state.SkipWithError(options.error().c_str());
    return;
  }
  const rgbdslam::SyntheticScene scene(*options);
  size_t i = 0;
  for (auto _ : state) {
    rgbdslam::RgbdFrame frame = scene.render(i);
    benchmark::DoNotOptimize(frame.colour.data);
    benchmark::DoNotOptimize(frame.depth.data);
    i = (i + 7) % scene.numFrames();  // walk through the whole sequence
  }
  state.SetItemsProcessed(state.iterations());
  state.SetLabel(spec);
}

void BM_RenderRoom(benchmark::State& state) { renderFrames(state, "room"); }
void BM_RenderRoomSparse(benchmark::State& state) { renderFrames(state, "room,depth_fraction=0.3"); }
void BM_RenderCorridor(benchmark::State& state) { renderFrames(state, "corridor"); }

void BM_BuildCorridor(benchmark::State& state) {
  for (auto _ : state) {
    const rgbdslam::SyntheticScene scene(*rgbdslam::parseSyntheticSpec("corridor"));
    benchmark::DoNotOptimize(scene.numFrames());
  }
}

}  // namespace

BENCHMARK(BM_RenderRoom)->Unit(benchmark::kMillisecond)->MinTime(3.0);
BENCHMARK(BM_RenderRoomSparse)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_RenderCorridor)->Unit(benchmark::kMillisecond)->MinTime(3.0);
BENCHMARK(BM_BuildCorridor)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
