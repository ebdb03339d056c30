// Per-call cost of the tracker's image layer on one core at 640x480 (lib/image): pyramid,
// FAST corners on all levels, patch warp, ZMSSD search, sub-pixel refinement and the small
// blurry image. Budget: a whole tracker frame <= 4 ms median, of which pyramid + corners
// should stay well under 1.5 ms and one patch search + refinement a few microseconds.
// Input: the first image of $RGBDSLAM_SHARED_DIR/data/tum_fr3_teddy_200/rgb (default
// /work/shared), or a synthetic texture when it is missing (said on stderr).
// Run: build/bench/bench_image
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "rgbdslam/image/corners.h"
#include "rgbdslam/image/patch.h"
#include "rgbdslam/image/pyramid.h"
#include "rgbdslam/image/small_blurry_image.h"

namespace rgbdslam {
namespace {

constexpr int kWidth = 640, kHeight = 480;  // [px]
constexpr int kPatchCount = 512;            // patches cycled through per benchmark
constexpr int kSearchRadius = 10;           // [px]
constexpr int kMaxZmssd = 64 * 30 * 30;     // PTAM-like: 30 grey levels rms per pixel
constexpr double kPi = 3.14159265358979323846;

// The first TUM image (sorted by name), grey; empty if there is none.
cv::Mat loadTumImage(int index) {
  const char* env = std::getenv("RGBDSLAM_SHARED_DIR");
  const std::filesystem::path dir =
      std::filesystem::path(env ? env : "/work/shared") / "data/tum_fr3_teddy_200/rgb";
  std::error_code error;
  if (!std::filesystem::is_directory(dir, error)) return cv::Mat();
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() == ".png") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  if (static_cast<int>(files.size()) <= index) return cv::Mat();
  return cv::imread(files[index].string(), cv::IMREAD_GRAYSCALE);
}

cv::Mat syntheticImage() {
  cv::Mat image(kHeight, kWidth, CV_8UC1);
  cv::RNG rng(1);
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(image, image, cv::Size(0, 0), 2.0);
  cv::normalize(image, image, 0, 255, cv::NORM_MINMAX);
  return image;
}

// Moves the content by (dx, dy) [px] and rotates it by angle [rad] about the centre.
cv::Mat moved(const cv::Mat& image, double dx, double dy, double angle) {
  const double c_x = 0.5 * (image.cols - 1), c_y = 0.5 * (image.rows - 1);
  const double cs = std::cos(angle), sn = std::sin(angle);
  const cv::Mat M = (cv::Mat_<double>(2, 3) << cs, -sn, c_x - cs * c_x + sn * c_y + dx, sn, cs,
                     c_y - sn * c_x - cs * c_y + dy);
  cv::Mat out;
  cv::warpAffine(image, out, M, image.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  return out;
}

// Everything the benchmarks share, built once.
struct Fixture {
  cv::Mat grey;
  cv::Mat grey_moved;  // moved by (0.3, -0.4) px: refinement needs a few iterations
  ImagePyramid pyramid;
  std::vector<LevelCorners> corners;
  std::vector<cv::Point2i> points;  // level-0 corners used as patch centres
  std::vector<Patch> patches;       // unwarped patches at 'points'

  Fixture() {
    grey = loadTumImage(0);
    if (grey.empty()) {
      std::cerr << "bench_image: no TUM image under $RGBDSLAM_SHARED_DIR/data/"
                   "tum_fr3_teddy_200/rgb; using a synthetic texture\n";
      grey = syntheticImage();
    }
    cv::resize(grey, grey, cv::Size(kWidth, kHeight));
    grey_moved = moved(grey, 0.3, -0.4, 0.0);
    buildPyramid(grey, kMaxLevels, &pyramid);
    detectPyramidCorners(pyramid, CornerOptions{}, true, &corners);
    // Evenly spread maxima with some texture, away from the edge.
    const std::vector<cv::Point2i>& maxima = corners[0].maxima;
    const size_t step = std::max<size_t>(1, maxima.size() / kPatchCount);
    for (size_t i = 0; i < maxima.size() && points.size() < kPatchCount; i += step) {
      const cv::Point2i p = maxima[i];
      if (p.x < 20 || p.y < 20 || p.x >= kWidth - 20 || p.y >= kHeight - 20) continue;
      Patch patch;
      if (!extractPatch(grey, p, &patch)) continue;
      points.push_back(p);
      patches.push_back(patch);
    }
  }
};

const Fixture& fixture() {
  static const Fixture instance;
  return instance;
}

void countCorners(benchmark::State& state, const std::vector<LevelCorners>& corners) {
  for (int level = 0; level < static_cast<int>(corners.size()); ++level) {
    state.counters["corners_L" + std::to_string(level)] =
        static_cast<double>(corners[level].all.size());
  }
}

void BM_BuildPyramid(benchmark::State& state) {
  const Fixture& f = fixture();
  ImagePyramid pyramid;
  for (auto _ : state) {
    buildPyramid(f.grey, kMaxLevels, &pyramid);
    benchmark::DoNotOptimize(pyramid.levels.back().data);
  }
}
BENCHMARK(BM_BuildPyramid)->Unit(benchmark::kMicrosecond);

void BM_FastCornersAllLevels(benchmark::State& state) {
  const Fixture& f = fixture();
  std::vector<LevelCorners> corners;
  for (auto _ : state) {
    detectPyramidCorners(f.pyramid, CornerOptions{}, false, &corners);
    benchmark::DoNotOptimize(corners.data());
  }
  countCorners(state, corners);
}
BENCHMARK(BM_FastCornersAllLevels)->Unit(benchmark::kMicrosecond);

// The per-frame cost of the tracker's front end: pyramid + FAST on every level.
void BM_PyramidAndCorners(benchmark::State& state) {
  const Fixture& f = fixture();
  ImagePyramid pyramid;
  std::vector<LevelCorners> corners;
  for (auto _ : state) {
    buildPyramid(f.grey, kMaxLevels, &pyramid);
    detectPyramidCorners(pyramid, CornerOptions{}, false, &corners);
    benchmark::DoNotOptimize(corners.data());
  }
  countCorners(state, corners);
}
BENCHMARK(BM_PyramidAndCorners)->Unit(benchmark::kMicrosecond);

// The extra cost for a keyframe: FAST scores and non-maximum suppression on every level.
void BM_MaximaAllLevels(benchmark::State& state) {
  const Fixture& f = fixture();
  std::vector<LevelCorners> corners = f.corners;
  for (auto _ : state) {
    for (int level = 0; level < kMaxLevels; ++level) {
      computeMaxima(f.pyramid.levels[level], &corners[level]);
    }
    benchmark::DoNotOptimize(corners.data());
  }
  state.counters["maxima_L0"] = static_cast<double>(corners[0].maxima.size());
}
BENCHMARK(BM_MaximaAllLevels)->Unit(benchmark::kMicrosecond);

void BM_WarpPatch(benchmark::State& state) {
  const Fixture& f = fixture();
  // 10 degrees of rotation and 10 % zoom.
  const double angle = 10.0 * kPi / 180.0, zoom = 1.1;
  Eigen::Matrix2d A;
  A << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle);
  A *= zoom;
  Patch patch;
  size_t i = 0;
  for (auto _ : state) {
    const cv::Point2i& p = f.points[i++ % f.points.size()];
    benchmark::DoNotOptimize(
        warpPatch(f.pyramid.levels[0], 0, Eigen::Vector2d(p.x, p.y), A, 0, &patch));
  }
}
BENCHMARK(BM_WarpPatch);

void BM_ZmssdAt(benchmark::State& state) {
  const Fixture& f = fixture();
  size_t i = 0;
  for (auto _ : state) {
    const size_t k = i++ % f.points.size();
    benchmark::DoNotOptimize(zmssdAt(f.patches[k], f.grey, f.points[k]));
  }
}
BENCHMARK(BM_ZmssdAt);

void BM_SearchPatchRadius10(benchmark::State& state) {
  const Fixture& f = fixture();
  size_t i = 0, candidates = 0;
  for (auto _ : state) {
    const size_t k = i++ % f.points.size();
    const Eigen::Vector2d predicted(f.points[k].x + 2.3, f.points[k].y - 1.7);
    benchmark::DoNotOptimize(searchPatch(f.patches[k], f.grey, f.corners[0], predicted,
                                         kSearchRadius, kMaxZmssd));
  }
  // Mean number of corners inside the search window (what the search pays for).
  for (const cv::Point2i& p : f.points) {
    for (int y = p.y - kSearchRadius; y <= p.y + kSearchRadius; ++y) {
      for (int j = f.corners[0].row_start[y]; j < f.corners[0].row_start[y + 1]; ++j) {
        const cv::Point2i d = f.corners[0].all[j] - p;
        candidates += d.x * d.x + d.y * d.y <= kSearchRadius * kSearchRadius;
      }
    }
  }
  state.counters["corners_in_window"] =
      static_cast<double>(candidates) / static_cast<double>(f.points.size());
}
BENCHMARK(BM_SearchPatchRadius10);

void BM_RefineSubpixel(benchmark::State& state) {
  const Fixture& f = fixture();
  size_t i = 0, converged = 0, calls = 0;
  for (auto _ : state) {
    const size_t k = i++ % f.points.size();
    Eigen::Vector2d position(f.points[k].x, f.points[k].y);
    converged += refineSubpixel(f.patches[k], f.grey_moved, &position);
    ++calls;
  }
  state.counters["converged_fraction"] = static_cast<double>(converged) / std::max<size_t>(1, calls);
}
BENCHMARK(BM_RefineSubpixel);

void BM_ShiTomasiScore(benchmark::State& state) {
  const Fixture& f = fixture();
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(shiTomasiScore(f.grey, f.points[i++ % f.points.size()]));
  }
}
BENCHMARK(BM_ShiTomasiScore);

void BM_MakeSmallBlurryImage(benchmark::State& state) {
  const Fixture& f = fixture();
  SmallBlurryImage sbi;
  for (auto _ : state) {
    makeSmallBlurryImage(f.pyramid, &sbi);
    benchmark::DoNotOptimize(sbi.image.data);
  }
}
BENCHMARK(BM_MakeSmallBlurryImage)->Unit(benchmark::kMicrosecond);

void BM_AlignSmallBlurryImages(benchmark::State& state) {
  const Fixture& f = fixture();
  const SmallBlurryImage from = makeSmallBlurryImage(f.pyramid);
  // 3 degrees of roll and a 20 px shift: a brisk inter-frame motion.
  const SmallBlurryImage to =
      makeSmallBlurryImage(buildPyramid(moved(f.grey, 20.0, -10.0, 3.0 * kPi / 180.0)));
  Se2 se2;
  for (auto _ : state) {
    se2 = alignSmallBlurryImages(from, to);
    benchmark::DoNotOptimize(se2);
  }
  state.counters["theta_deg"] = se2.theta * 180.0 / kPi;
  state.counters["tx_sbi_px"] = se2.tx;
}
BENCHMARK(BM_AlignSmallBlurryImages)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace rgbdslam

int main(int argc, char** argv) {
  cv::setNumThreads(0);  // one core: OpenCV runs everything sequentially
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
