// Frames per second of the synthetic renderer at 640x480 on one core (render() includes ray
// casting, image noise and the Kinect depth model, and with the sensor effects). Target:
// >= 30 frames/s for the room.
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
// The sensor effects (SensorEffects): all of them, then the blur alone (5 ray casts per
// frame), the auto exposure alone (61 metering casts at 1/16 size) and the depth effects.
void BM_RenderRoomAllEffects(benchmark::State& state) { renderFrames(state, "room,effects=all"); }
void BM_RenderRoomBlur(benchmark::State& state) { renderFrames(state, "room,exposure=20"); }
void BM_RenderRoomAutoExposure(benchmark::State& state) {
  renderFrames(state, "room,auto_exposure=0.5");
}
void BM_RenderRoomDepthEffects(benchmark::State& state) {
  renderFrames(state, "room,depth_noise=nguyen,edge_holes=1,ir_shadow=1,dark_holes=0.01");
}
void BM_RenderCorridorAllEffects(benchmark::State& state) {
  renderFrames(state, "corridor,effects=all");
}
void BM_RenderOffice(benchmark::State& state) { renderFrames(state, "office"); }

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
BENCHMARK(BM_RenderRoomAllEffects)->Unit(benchmark::kMillisecond)->MinTime(3.0);
BENCHMARK(BM_RenderRoomBlur)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_RenderRoomAutoExposure)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_RenderRoomDepthEffects)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_RenderCorridorAllEffects)->Unit(benchmark::kMillisecond)->MinTime(3.0);
BENCHMARK(BM_RenderOffice)->Unit(benchmark::kMillisecond)->MinTime(3.0);
BENCHMARK(BM_BuildCorridor)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
