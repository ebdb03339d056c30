// The image effects of SensorEffects (scene.h): motion blur sub-frame times, auto-exposure
// metering, exposure gain with vignetting, and signal-dependent (shot + read) noise.
// Order in SyntheticScene::renderPose: blur (mean of sub-frame renders), gain and
// vignetting, lens resampling, noise; the noise comes last because the sensor adds it to
// the signal it reads out.
#include <algorithm>
#include <cmath>

#include "world.h"

namespace rgbdslam::synthetic {
namespace {

constexpr double kMeteringTargetGrey = 118.0;  // AE aims the mean grey at this [grey level]
constexpr double kMinExposureGain = 0.25, kMaxExposureGain = 4.0;
constexpr int kMeteringDownscale = 16;  // the metering image is 1/16 of the frame per side

}  // namespace

std::array<double, kBlurSubFrames> blurOffsets(double exposure_ms) {
  std::array<double, kBlurSubFrames> offsets;
  for (int k = 0; k < kBlurSubFrames; ++k) {
    offsets[k] = 1e-3 * exposure_ms * ((k + 0.5) / kBlurSubFrames - 0.5);
  }
  return offsets;
}

double meteredGainOf(const cv::Mat& clean_colour) {
  const cv::Scalar mean = cv::mean(clean_colour);
  const double grey = (mean[0] + mean[1] + mean[2]) / 3.0;
  return std::clamp(kMeteringTargetGrey / std::max(grey, 1.0), kMinExposureGain,
                    kMaxExposureGain);
}

PinholeCamera meteringCamera(const PinholeCamera& camera) {
  PinholeCamera small = camera;
  small.k1 = small.k2 = small.p1 = small.p2 = small.k3 = 0;
  const double s = 1.0 / kMeteringDownscale;
  small.width = std::max(1, camera.width / kMeteringDownscale);
  small.height = std::max(1, camera.height / kMeteringDownscale);
  small.fx *= s, small.fy *= s;
  small.cx = (camera.cx + 0.5) * s - 0.5, small.cy = (camera.cy + 0.5) * s - 0.5;
  return small;
}

void applyExposureAndVignetting(const SensorEffects& effects, const PinholeCamera& camera,
                                double gain, cv::Mat* colour) {
  if (gain == 1.0 && effects.vignetting <= 0) return;
  const float g = static_cast<float>(gain), strength = static_cast<float>(effects.vignetting);
  const float inv_fx2 = static_cast<float>(1.0 / (camera.fx * camera.fx));
  const float inv_fy2 = static_cast<float>(1.0 / (camera.fy * camera.fy));
  for (int v = 0; v < colour->rows; ++v) {
    uint8_t* row = colour->ptr<uint8_t>(v);
    const float dv2 = static_cast<float>((v - camera.cy) * (v - camera.cy)) * inv_fy2;
    for (int u = 0; u < colour->cols; ++u) {
      // cos^2(alpha) = 1 / (1 + tan^2(alpha)) for the pixel's ray.
      const float du2 = static_cast<float>((u - camera.cx) * (u - camera.cx)) * inv_fx2;
      const float cos2 = 1.f / (1.f + du2 + dv2);
      const float factor = g * (1.f - strength * (1.f - cos2 * cos2));
      for (int c = 0; c < 3; ++c) {
        row[3 * u + c] = static_cast<uint8_t>(std::min(255.f, row[3 * u + c] * factor + 0.5f));
      }
    }
  }
}

void addSignalDependentNoise(const KinectNoiseOptions& noise, const SensorEffects& effects,
                             uint64_t seed, size_t index, cv::Mat* colour) {
  std::array<float, 256> sigma;  // per noise-free grey level
  for (int i = 0; i < 256; ++i) {
    sigma[i] = static_cast<float>(std::sqrt(noise.image_noise_sigma * noise.image_noise_sigma +
                                            effects.shot_noise * i));
  }
  Bits16 bits(makeEngine(seed, kImageNoiseStream, index));
  const int values_per_row = colour->cols * colour->channels();
  for (int v = 0; v < colour->rows; ++v) {
    uint8_t* row = colour->ptr<uint8_t>(v);
    for (int k = 0; k < values_per_row; ++k) {
      const float noisy = row[k] + sigma[row[k]] * normalFrom(bits.next());
      row[k] = static_cast<uint8_t>(std::clamp(std::lround(noisy), 0L, 255L));
    }
  }
}

}  // namespace rgbdslam::synthetic
