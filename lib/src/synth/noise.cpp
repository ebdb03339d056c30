// Sensor noise on a clean synthetic frame: Gaussian image noise and the Kinect depth model
// (see KinectNoiseOptions). Each purpose has its own random stream per frame, drawn once per
// pixel in raster order whether or not the pixel has a reading, so e.g. a sparse frame holds
// exactly the readings of the dense one at the pixels it keeps.
#include <algorithm>
#include <cmath>

#include "world.h"

namespace rgbdslam::synthetic {

bool depthActive(const KinectNoiseOptions& noise, size_t index) {
  return noise.depth_enabled &&
         (noise.depth_frames < 0 || index < static_cast<size_t>(noise.depth_frames));
}

void addImageNoise(const KinectNoiseOptions& noise, uint64_t seed, size_t index,
                   cv::Mat* colour) {
  if (noise.image_noise_sigma <= 0) return;
  const auto& table = normalTable();
  std::array<int, 4096> offsets;  // grey-level offsets, rounded once per frame
  for (size_t k = 0; k < table.size(); ++k) {
    offsets[k] = static_cast<int>(std::lround(noise.image_noise_sigma * table[k]));
  }
  std::mt19937_64 rng = makeEngine(seed, kImageNoiseStream, index);
  const int values_per_row = colour->cols * colour->channels();
  for (int v = 0; v < colour->rows; ++v) {
    uint8_t* row = colour->ptr<uint8_t>(v);
    for (int k = 0; k < values_per_row; k += 4) {  // four 16-bit draws per 64-bit word
      uint64_t word = rng();
      for (int j = k; j < std::min(k + 4, values_per_row); ++j, word >>= 16) {
        const int noisy = row[j] + offsets[(word & 0xffff) >> 4];
        row[j] = static_cast<uint8_t>(std::clamp(noisy, 0, 255));
      }
    }
  }
}

cv::Mat kinectDepth(const KinectNoiseOptions& noise, uint64_t seed, size_t index,
                    const cv::Mat& depth_m, double depth_factor) {
  cv::Mat raw(depth_m.size(), CV_16UC1, cv::Scalar(0));
  if (!depthActive(noise, index)) return raw;
  Bits16 noise_bits(makeEngine(seed, kDepthNoiseStream, index));
  Bits16 keep_bits(makeEngine(seed, kDepthKeepStream, index));
  const bool sparse = noise.depth_fraction < 1.0;
  const uint32_t keep_below = static_cast<uint32_t>(std::lround(noise.depth_fraction * 65536.0));
  // Disparity in quantisation steps is fbs / z.
  const double fbs = noise.disparity_focal_px * noise.baseline_m / noise.disparity_step_px;
  for (int v = 0; v < depth_m.rows; ++v) {
    const float* in = depth_m.ptr<float>(v);
    uint16_t* out = raw.ptr<uint16_t>(v);
    for (int u = 0; u < depth_m.cols; ++u) {
      const float n = normalFrom(noise_bits.next());
      const bool keep = !sparse || keep_bits.next() < keep_below;
      const double z = in[u];
      if (z <= 0 || !keep) continue;
      out[u] = rawReading(noise, fbs, z + noise.sigma_coefficient * z * z * n, depth_factor);
    }
  }
  return raw;
}

uint16_t rawReading(const KinectNoiseOptions& noise, double fbs, double z_measured,
                    double depth_factor) {
  if (noise.quantise) {
    // Rounded to the nearest step (a cast: std::round is a library call here).
    const int64_t steps = static_cast<int64_t>(fbs / z_measured + 0.5);
    if (steps < 1) return 0;  // beyond the last disparity step (or negative)
    z_measured = fbs / static_cast<double>(steps);
  }
  if (!(z_measured >= noise.min_range_m && z_measured <= noise.max_range_m)) return 0;
  return static_cast<uint16_t>(std::min(65535.0, z_measured * depth_factor + 0.5));
}

}  // namespace rgbdslam::synthetic
