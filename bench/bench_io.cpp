// I/O benchmarks: reading TUM frames from disk, encoding/decoding frames for the wire (raw,
// JPEG colour, zlib depth), and publishing them through LCM's in-process provider (memq://,
// the full encode + publish path without a network). Uses ../shared/data/tum_fr3_teddy_200
// when present, else a synthetic room frame.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <lcm/lcm-cpp.hpp>

#include "common/lcm_conversions.h"
#include "rgbdslam/synth/scene.h"
#include "rgbdslam/io/tum_dataset.h"

using namespace rgbdslam;

namespace {

std::string teddyDir() {
  const char* shared = std::getenv("RGBDSLAM_SHARED_DIR");
  const std::string dir = std::string(shared ? shared : "../shared") + "/data/tum_fr3_teddy_200";
  return std::filesystem::exists(dir) ? dir : "";
}

const RgbdFrame& sampleFrame() {
  static const RgbdFrame frame = [] {
    const std::string dir = teddyDir();
    if (!dir.empty()) {
      PinholeCamera camera;
      auto source = openTumDataset(dir, camera);
      if (source) return (*source)->read(0).frame;
    }
    return SyntheticScene(*parseSyntheticSpec("room")).render(0);
  }();
  return frame;
}

void BM_TumReadFrame(benchmark::State& state) {
  const std::string dir = teddyDir();
  if (dir.empty()) return state.SkipWithError("../shared/data/tum_fr3_teddy_200 is missing");
  PinholeCamera camera;
  auto source = openTumDataset(dir, camera);
  size_t i = 0;
  for (auto _ : state) {
    FrameResult r = (*source)->read(i++ % (*source)->entries().size());
    benchmark::DoNotOptimize(r.frame.depth.data);
  }
  state.counters["frames_per_s"] = benchmark::Counter(state.iterations(), benchmark::Counter::kIsRate);
}

void BM_EncodeFrame(benchmark::State& state) {
  const FrameEncoding encoding{state.range(0) == 1, 90, state.range(1) == 1, 1};
  for (auto _ : state) benchmark::DoNotOptimize(toLcm(sampleFrame(), encoding));
  const auto msg = toLcm(sampleFrame(), encoding);
  state.counters["colour_kB"] = msg.colour.size() / 1024.0;
  state.counters["depth_kB"] = msg.depth.size() / 1024.0;
  state.SetLabel(std::string(encoding.jpeg_colour ? "jpeg" : "raw") + " colour, " +
                 (encoding.zlib_depth ? "zlib" : "raw") + " depth");
}

void BM_DecodeFrame(benchmark::State& state) {
  const FrameEncoding encoding{state.range(0) == 1, 90, state.range(1) == 1, 1};
  const auto msg = toLcm(sampleFrame(), encoding);
  for (auto _ : state) benchmark::DoNotOptimize(fromLcm(msg));
  state.SetLabel(std::string(encoding.jpeg_colour ? "jpeg" : "raw") + " colour, " +
                 (encoding.zlib_depth ? "zlib" : "raw") + " depth");
}

void BM_ReadAndPublishTum(benchmark::State& state) {
  const std::string dir = teddyDir();
  if (dir.empty()) return state.SkipWithError("../shared/data/tum_fr3_teddy_200 is missing");
  PinholeCamera camera;
  auto source = openTumDataset(dir, camera);
  lcm::LCM lcm("memq://");
  size_t i = 0;
  for (auto _ : state) {
    FrameResult r = (*source)->read(i++ % (*source)->entries().size());
    const auto msg = toLcm(r.frame, FrameEncoding{});
    lcm.publish("RGBD_FRAME", &msg);
  }
  state.counters["frames_per_s"] = benchmark::Counter(state.iterations(), benchmark::Counter::kIsRate);
}

}  // namespace

BENCHMARK(BM_TumReadFrame)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EncodeFrame)->Args({0, 0})->Args({0, 1})->Args({1, 0})->Args({1, 1})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DecodeFrame)->Args({0, 0})->Args({0, 1})->Args({1, 0})->Args({1, 1})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadAndPublishTum)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
