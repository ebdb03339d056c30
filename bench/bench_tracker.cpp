// Tracker time per frame (the whole Tracker::track(): grey conversion, pyramid, corners,
// small blurry image, projection, coarse + fine search, pose Gauss-Newton, keyframe
// decision and, on keyframes, point creation) on one core, from a decoded frame in memory to
// its pose. Sequences: the synthetic room (300 frames) and, if present, TUM fr3/teddy
// ($RGBDSLAM_SHARED_DIR/data/tum_fr3_teddy_200, default /work/shared). The tracker runs
// alone (no mapper). Each iteration tracks the whole sequence; the counters are the median
// and 95th percentile of the per-frame TrackResult::track_ms over all iterations, and the
// share of frames with a pose. Target: median <= 4 ms per 640x480 frame. Each sequence runs
// with the integrity checks (depth and photometric) on (argument 1, the default) and off (0):
// their cost is the difference of the medians (target: at most 0.5 ms). The 99th percentile and the
// worst frame are printed too: on a flight computer they matter as much as the median.
// BM_RelocaliseAfterGap: a tracker that has tracked the room's frames 0-99 loses them (a
// black frame without depth), then gets a frame 40-80 frames on (1.3-2.7 s later, 0.3-0.6 m
// and 20-40 deg away: beyond PTAM's relocaliser, so the features with depth must find it).
// The time is that frame's whole track(), relocalisation included (target: 30 ms).
// Run: taskset -c 0 build/bench/bench_tracker
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "rgbdslam/camera/calibration_io.h"
#include "rgbdslam/synth/scene.h"
#include "rgbdslam/io/tum_dataset.h"
#include "rgbdslam/tracking/tracker.h"

namespace {

using namespace rgbdslam;

struct Sequence {
  PinholeCamera camera;
  std::vector<RgbdFrame> frames;
  std::string error;
};

const Sequence& room() {
  static const Sequence sequence = [] {
    Sequence s;
    const SyntheticScene scene(*parseSyntheticSpec("room,frames=300"));
    s.camera = scene.camera();
    for (size_t i = 0; i < scene.numFrames(); ++i) s.frames.push_back(scene.render(i));
    return s;
  }();
  return sequence;
}

const Sequence& teddy() {
  static const Sequence sequence = [] {
    Sequence s;
    const char* shared = std::getenv("RGBDSLAM_SHARED_DIR");
    const std::string dir = std::string(shared ? shared : "/work/shared") + "/data/tum_fr3_teddy_200";
    const std::string source_dir =
        std::filesystem::path(__FILE__).parent_path().parent_path().string();
    auto camera = loadCamera(source_dir + "/config/cameras/tum_fr3.yaml");
    if (!camera) {
      s.error = camera.error();
      return s;
    }
    s.camera = *camera;
    auto source = openTumDataset(dir, s.camera);
    if (!source) {
      s.error = source.error();
      return s;
    }
    for (;;) {
      FrameResult next = source.value()->next();
      if (next.status == FrameResult::Status::kEnd || next.status == FrameResult::Status::kFailed) break;
      if (next.status == FrameResult::Status::kFrame) s.frames.push_back(std::move(next.frame));
    }
    return s;
  }();
  return sequence;
}

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  const size_t k = std::min(values.size() - 1, static_cast<size_t>(p * (values.size() - 1) + 0.5));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

void trackSequence(benchmark::State& state, const Sequence& sequence, const char* name) {
  TrackerOptions options;
  options.integrity.enabled = options.photometric.enabled = state.range(0) != 0;
  if (!sequence.error.empty() || sequence.frames.empty()) {
    state.SkipWithError(sequence.error.empty() ? "no frames" : sequence.error.c_str());
    return;
  }
  std::vector<double> times;
  size_t with_pose = 0, frames = 0;
  for (auto _ : state) {
    Tracker tracker(sequence.camera, options, SlamMode::kDepthBa, 1);
    for (const RgbdFrame& frame : sequence.frames) {
      const TrackResult result = tracker.track(frame);
      times.push_back(result.track_ms);
      ++frames;
      with_pose += result.status == TrackResult::Status::kTracked ||
                   result.status == TrackResult::Status::kInitialised ||
                   result.status == TrackResult::Status::kRelocalised;
    }
  }
  const double median = percentile(times, 0.5), p95 = percentile(times, 0.95),
               p99 = percentile(times, 0.99), worst = percentile(times, 1.0);
  state.counters["median_ms"] = median;
  state.counters["p95_ms"] = p95;
  state.counters["p99_ms"] = p99;
  state.counters["max_ms"] = worst;
  state.counters["tracked"] = static_cast<double>(with_pose) / static_cast<double>(frames);
  state.SetItemsProcessed(static_cast<int64_t>(frames));
  std::printf("%s, integrity checks %s: %zu frames, time per frame median %.2f ms, p95 %.2f ms, "
              "p99 %.2f ms, max %.2f ms, %.1f%% with a pose\n", name, options.integrity.enabled ? "on" : "off",
              sequence.frames.size(), median, p95, p99, worst, 100.0 * with_pose / frames);
}

void BM_RelocaliseAfterGap(benchmark::State& state) {
  const Sequence& sequence = room();
  constexpr size_t kTracked = 100, kFirstAfter = 140, kLastAfter = 180, kStep = 5;
  RgbdFrame dark = sequence.frames[kTracked];
  dark.colour.setTo(cv::Scalar::all(0));
  dark.depth.setTo(cv::Scalar::all(0));
  std::vector<double> times;
  size_t recovered = 0, tries = 0, next = kFirstAfter;
  for (auto _ : state) {
    state.PauseTiming();
    Tracker tracker(sequence.camera, TrackerOptions{}, SlamMode::kDepthBa, 1);
    for (size_t i = 0; i < kTracked; ++i) tracker.track(sequence.frames[i]);
    const bool lost = tracker.track(dark).status == TrackResult::Status::kLost;
    state.ResumeTiming();
    const TrackResult result = tracker.track(sequence.frames[next]);
    state.PauseTiming();
    if (!lost) state.SkipWithError("the dark frame did not lose the tracker");
    times.push_back(result.track_ms);
    recovered += result.status == TrackResult::Status::kRelocalised;
    ++tries;
    next = next + kStep > kLastAfter ? kFirstAfter : next + kStep;
    state.ResumeTiming();
  }
  state.counters["median_ms"] = percentile(times, 0.5);
  state.counters["max_ms"] = percentile(times, 1.0);
  state.counters["recovered"] = static_cast<double>(recovered) / static_cast<double>(std::max<size_t>(tries, 1));
  std::printf("room, relocalisation after a gap (frames %zu-%zu after tracking 0-%zu): %zu tries, "
              "%zu recovered, time of the frame median %.1f ms, max %.1f ms\n",
              kFirstAfter, kLastAfter, kTracked - 1, tries, recovered, percentile(times, 0.5),
              percentile(times, 1.0));
}

void BM_TrackSyntheticRoom(benchmark::State& state) { trackSequence(state, room(), "room"); }
void BM_TrackTumTeddy(benchmark::State& state) { trackSequence(state, teddy(), "fr3/teddy"); }

}  // namespace

BENCHMARK(BM_TrackSyntheticRoom)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_TrackTumTeddy)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_RelocaliseAfterGap)->Unit(benchmark::kMillisecond)->Iterations(9);
BENCHMARK_MAIN();
