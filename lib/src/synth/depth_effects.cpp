// The depth effects of SensorEffects (scene.h): holes beside depth edges and in the
// projector's shadow (geometric, on the ideal image before lens resampling), and per pixel
// the Nguyen, Izadi and Lovell (2012) noise with lateral displacement and the losses on dark
// and shiny surfaces, then the Kinect model's quantisation, range and storage (noise.cpp).
// Random draws per pixel in raster order, each purpose from its own stream, whether or not
// the pixel has a reading (as in noise.cpp).
#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "world.h"

namespace rgbdslam::synthetic {
namespace {

constexpr float kEdgeJumpFraction = 0.05f;    // a depth edge: neighbours differ by > 5 % of z
constexpr float kShadowTolerancePx = 0.01f;  // projector-column slack of the shadow test
constexpr double kMaxIncidenceRad = 88.0 * M_PI / 180.0;   // caps theta / (pi/2 - theta)
constexpr double kShinyNormalRad = 12.0 * M_PI / 180.0;    // specular highlight below this
constexpr double kShinyGrazingRad = 65.0 * M_PI / 180.0;   // pattern mirrored away above this

// Pixels next to a depth discontinuity (either side), grown to 'band_px' pixels.
cv::Mat depthEdgeBand(const cv::Mat& hit_z, int band_px) {
  cv::Mat edge(hit_z.size(), CV_8UC1, cv::Scalar(0));
  auto jump = [](float a, float b) {
    return a > 0 && b > 0 && std::abs(a - b) > kEdgeJumpFraction * std::min(a, b);
  };
  for (int v = 0; v < hit_z.rows; ++v) {
    const float* row = hit_z.ptr<float>(v);
    const float* below = v + 1 < hit_z.rows ? hit_z.ptr<float>(v + 1) : nullptr;
    for (int u = 0; u < hit_z.cols; ++u) {
      if (u + 1 < hit_z.cols && jump(row[u], row[u + 1])) {
        edge.at<uint8_t>(v, u) = edge.at<uint8_t>(v, u + 1) = 1;
      }
      if (below && jump(row[u], below[u])) {
        edge.at<uint8_t>(v, u) = edge.at<uint8_t>(v + 1, u) = 1;
      }
    }
  }
  if (band_px > 1) {
    const int size = 2 * band_px - 1;
    cv::dilate(edge, edge, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(size, size)));
  }
  return edge;
}

// The projector sits f_b / fx metres to the right of the camera with the same orientation, so
// a surface at pixel u and depth z is at projector column u - f_b / z on the same row. Seen
// from the projector the column must grow with u; a pixel whose column is not left of every
// column to its right is hidden from the projector by a nearer surface (which lies on that
// row to its right in the camera image).
void removeProjectorShadows(double f_b, const cv::Mat& hit_z, cv::Mat* depth_m) {
  for (int v = 0; v < hit_z.rows; ++v) {
    const float* z = hit_z.ptr<float>(v);
    float* depth = depth_m->ptr<float>(v);
    float min_column = std::numeric_limits<float>::max();
    for (int u = hit_z.cols - 1; u >= 0; --u) {
      if (z[u] <= 0) continue;  // nothing hit: nothing to light or to cast a shadow
      const float column = static_cast<float>(u - f_b / z[u]);
      if (column > min_column + kShadowTolerancePx) depth[u] = 0.f;
      min_column = std::min(min_column, column);
    }
  }
}

// What the depth model needs of the incidence angle theta, tabulated over cos(theta) in
// kIncidenceBins steps (acos per pixel costs more than the rest of the model).
constexpr int kIncidenceBins = 4096;
struct IncidenceTerms {
  float axial_angle;  // Nguyen's angular term 0.1 mm * theta^2 / (pi/2 - theta)^2 [m] (at 1 m)
  float lateral_px;   // Nguyen's sigma_L = 0.8 + 0.035 theta / (pi/2 - theta) [px]
  bool shiny_lost;    // a shiny surface loses the reading at this incidence
};

const std::array<IncidenceTerms, kIncidenceBins + 1>& incidenceTable() {
  static const auto table = [] {
    std::array<IncidenceTerms, kIncidenceBins + 1> t;
    for (int k = 0; k <= kIncidenceBins; ++k) {
      const double theta = std::min(std::acos(static_cast<double>(k) / kIncidenceBins), kMaxIncidenceRad);
      const double ratio = theta / (M_PI / 2 - theta);
      t[k] = IncidenceTerms{static_cast<float>(0.0001 * ratio * ratio),
                            static_cast<float>(0.8 + 0.035 * ratio),
                            theta < kShinyNormalRad || theta > kShinyGrazingRad};
    }
    return t;
  }();
  return table;
}

inline const IncidenceTerms& incidenceTerms(float cos_theta) {
  const int k = static_cast<int>(std::clamp(cos_theta, 0.f, 1.f) * kIncidenceBins + 0.5f);
  return incidenceTable()[k];
}

// Nearest integer (std::lround is a library call; this runs twice per pixel).
inline int roundToInt(float x) { return static_cast<int>(std::floor(x + 0.5f)); }

// Nguyen et al. (2012) axial noise [m] at depth z [m].
inline double nguyenAxialSigma(double z, const IncidenceTerms& terms) {
  return 0.0012 + 0.0019 * (z - 0.4) * (z - 0.4) + terms.axial_angle / std::sqrt(z);
}

// Probability that a reading survives the material losses.
double keepProbability(const SensorEffects& effects, const CleanFrame& clean, int u, int v,
                       double z, float cos_theta) {
  const auto surface = static_cast<SyntheticSurface>(clean.surfaces.ptr<uint8_t>(v)[u]);
  if (effects.shiny_holes && surface == SyntheticSurface::kShiny &&
      incidenceTerms(cos_theta).shiny_lost) {
    return 0.0;
  }
  if (effects.dark_holes <= 0) return 1.0;
  const uint8_t* bgr = clean.colour.ptr<uint8_t>(v) + 3 * u;
  const double grey = (bgr[0] + bgr[1] + bgr[2]) / (3.0 * 255.0);
  const double signal = grey * cos_theta / (z * z);
  return std::clamp((signal - effects.dark_holes) / effects.dark_holes, 0.0, 1.0);
}

}  // namespace

void removeGeometricDepth(const SensorEffects& effects, const KinectNoiseOptions& noise,
                          double fx, CleanFrame* frame) {
  if (effects.edge_holes_px > 0) {
    frame->depth_m.setTo(cv::Scalar(0), depthEdgeBand(frame->hit_z, effects.edge_holes_px));
  }
  if (effects.ir_shadow) removeProjectorShadows(fx * noise.baseline_m, frame->hit_z, &frame->depth_m);
}

cv::Mat kinectDepthWithEffects(const KinectNoiseOptions& noise, const SensorEffects& effects,
                               uint64_t seed, size_t index, const CleanFrame& clean,
                               double depth_factor) {
  const cv::Mat& depth_m = clean.depth_m;
  cv::Mat raw(depth_m.size(), CV_16UC1, cv::Scalar(0));
  if (!depthActive(noise, index)) return raw;
  Bits16 noise_bits(makeEngine(seed, kDepthNoiseStream, index));
  Bits16 keep_bits(makeEngine(seed, kDepthKeepStream, index));
  Bits16 lateral_bits(makeEngine(seed, kDepthLateralStream, index));
  Bits16 loss_bits(makeEngine(seed, kDepthLossStream, index));
  const bool sparse = noise.depth_fraction < 1.0;
  const bool losses = effects.dark_holes > 0 || effects.shiny_holes;
  const uint32_t keep_below = static_cast<uint32_t>(std::lround(noise.depth_fraction * 65536.0));
  const double fbs = noise.disparity_focal_px * noise.baseline_m / noise.disparity_step_px;
  for (int v = 0; v < depth_m.rows; ++v) {
    uint16_t* out = raw.ptr<uint16_t>(v);
    for (int u = 0; u < depth_m.cols; ++u) {
      const float n = normalFrom(noise_bits.next());
      const bool keep = !sparse || keep_bits.next() < keep_below;
      int su = u, sv = v;  // the pixel the reading comes from (lateral noise)
      if (effects.nguyen_depth) {
        const float sigma_px = incidenceTerms(clean.cos_incidence.ptr<float>(v)[u]).lateral_px;
        su = std::clamp(u + roundToInt(sigma_px * normalFrom(lateral_bits.next())), 0,
                        depth_m.cols - 1);
        sv = std::clamp(v + roundToInt(sigma_px * normalFrom(lateral_bits.next())), 0,
                        depth_m.rows - 1);
      }
      const double loss_draw = losses ? loss_bits.next() / 65536.0 : 0.0;
      const double z = depth_m.ptr<float>(sv)[su];
      if (z <= 0 || !keep) continue;
      const float cos_theta = clean.cos_incidence.ptr<float>(sv)[su];
      if (losses && loss_draw >= keepProbability(effects, clean, su, sv, z, cos_theta)) continue;
      const double sigma = effects.nguyen_depth ? nguyenAxialSigma(z, incidenceTerms(cos_theta))
                                                : noise.sigma_coefficient * z * z;
      out[u] = rawReading(noise, fbs, z + sigma * n, depth_factor);
    }
  }
  return raw;
}

}  // namespace rgbdslam::synthetic
