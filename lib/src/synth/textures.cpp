// Procedural textures for the synthetic scenes: value noise at several scales plus random
// rectangles, triangles and ellipses, baked per face so that no pattern repeats (patch
// matching must not be fooled) and FAST finds corners at every pyramid level.
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "world.h"

namespace rgbdslam::synthetic {
namespace {

// Lambert shading with one fixed light plus ambient light.
constexpr double kAmbient = 0.55;
constexpr double kDiffuse = 0.45;
const Vec3 kLightDirection = Vec3(0.4, 0.25, 1.0).normalized();  // towards the light
// Octaves at least this coarse go below the shapes; finer ones are grain over everything.
constexpr double kUnderShapeScaleM = 0.1;
constexpr int kMaxMipLevels = 8;
constexpr int kMinMipSize = 4;   // [texels]
constexpr int kDrawShift = 4;    // sub-texel bits for cv::fillConvexPoly
constexpr double kOutlineFraction = 0.2;  // share of shapes drawn as outlines

uint64_t splitmix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// Acklam's rational approximation of the inverse standard normal CDF (|rel. error| < 1.2e-9).
double inverseNormalCdf(double p) {
  static const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02,
                             -2.759285104469687e+02, 1.383577518672690e+02,
                             -3.066479806614716e+01, 2.506628277459239e+00};
  static const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02,
                             -1.556989798598866e+02, 6.680131188771972e+01,
                             -1.328068155288572e+01};
  static const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01,
                             -2.400758277161838e+00, -2.549732539343734e+00,
                             4.374664141464968e+00,  2.938163982698783e+00};
  static const double d[] = {7.784695709041462e-03, 3.224671290700398e-01,
                             2.445134137142996e+00, 3.754408661907416e+00};
  const double p_low = 0.02425;
  if (p < p_low) {
    const double q = std::sqrt(-2 * std::log(p));
    return (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
           ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
  }
  if (p > 1 - p_low) return -inverseNormalCdf(1 - p);
  const double q = p - 0.5;
  const double r = q * q;
  return (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
         (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1);
}

std::array<float, 4096> makeNormalTable() {
  std::array<double, 4096> quantiles;
  double sum_sq = 0;
  for (size_t k = 0; k < quantiles.size(); ++k) {
    quantiles[k] = inverseNormalCdf((k + 0.5) / quantiles.size());
    sum_sq += quantiles[k] * quantiles[k];
  }
  // Symmetric, so the mean is zero; rescale to exactly unit variance.
  const double scale = 1.0 / std::sqrt(sum_sq / quantiles.size());
  std::array<float, 4096> table;
  for (size_t k = 0; k < table.size(); ++k) table[k] = static_cast<float>(quantiles[k] * scale);
  return table;
}

void addValueNoise(const NoiseOctave& octave, double texel_m, std::mt19937_64& rng,
                   cv::Mat* albedo) {
  const double cells_per_texel = texel_m / octave.scale_m;
  const int gw = std::max(2, static_cast<int>(std::ceil(albedo->cols * cells_per_texel)) + 1);
  const int gh = std::max(2, static_cast<int>(std::ceil(albedo->rows * cells_per_texel)) + 1);
  cv::Mat grid(gh, gw, CV_32FC1);
  for (int r = 0; r < gh; ++r) {
    float* row = grid.ptr<float>(r);
    for (int c = 0; c < gw; ++c) {
      row[c] = static_cast<float>(uniform(rng, -octave.amplitude, octave.amplitude));
    }
  }
  cv::Mat smooth;
  cv::resize(grid, smooth, albedo->size(), 0, 0, cv::INTER_CUBIC);
  *albedo += smooth;
}

cv::Point toFixed(double x, double y) {
  return cv::Point(static_cast<int>(std::lround(x * (1 << kDrawShift))),
                   static_cast<int>(std::lround(y * (1 << kDrawShift))));
}

// One random shape of 'layer' (sizes in texels) on 'albedo'.
void drawShape(const ShapeLayer& layer, double base, double texel_m, std::mt19937_64& rng,
               cv::Mat* albedo) {
  const double size = std::exp(uniform(rng, std::log(layer.min_size_m),
                                       std::log(layer.max_size_m))) / texel_m;
  const double cx = uniform(rng, 0, albedo->cols), cy = uniform(rng, 0, albedo->rows);
  const double angle = uniform(rng, 0, 2 * M_PI);
  const double aspect = uniform(rng, 0.35, 1.0);
  const cv::Scalar grey(base + uniform(rng, -layer.contrast, layer.contrast));
  const bool outline = uniform01(rng) < kOutlineFraction;
  const int thickness = outline ? std::max(1, static_cast<int>(size / 8)) : cv::FILLED;
  const int kind = static_cast<int>(rng() % 3);
  const double ca = std::cos(angle), sa = std::sin(angle);
  const double hx = 0.5 * size, hy = 0.5 * size * aspect;
  if (kind == 2) {
    cv::ellipse(*albedo, toFixed(cx, cy), cv::Size(toFixed(hx, hy)), angle * 180 / M_PI, 0, 360,
                grey, thickness, cv::LINE_8, kDrawShift);
    return;
  }
  std::vector<cv::Point> corners;
  const double local[4][2] = {{-hx, -hy}, {hx, -hy}, {hx, hy}, {-hx, hy}};
  const int count = kind == 0 ? 4 : 3;  // rectangle or triangle
  for (int k = 0; k < count; ++k) {
    const double lx = local[k][0], ly = local[k][1];
    corners.push_back(toFixed(cx + ca * lx - sa * ly, cy + sa * lx + ca * ly));
  }
  if (outline) {
    cv::polylines(*albedo, corners, true, grey, thickness, cv::LINE_8, kDrawShift);
  } else {
    cv::fillConvexPoly(*albedo, corners, grey, cv::LINE_8, kDrawShift);
  }
}

void drawShapes(const ShapeLayer& layer, double base, double texel_m, std::mt19937_64& rng,
                cv::Mat* albedo) {
  const double area_m2 = albedo->cols * albedo->rows * texel_m * texel_m;
  const double expected = layer.density_per_m2 * area_m2;
  // Integer part plus a random rounding of the fraction.
  const int count = static_cast<int>(expected) + (uniform01(rng) < expected - std::floor(expected));
  for (int k = 0; k < count; ++k) drawShape(layer, base, texel_m, rng, albedo);
}

std::vector<cv::Mat> buildMips(const cv::Mat& level0) {
  std::vector<cv::Mat> levels{level0};
  while (static_cast<int>(levels.size()) < kMaxMipLevels) {
    const cv::Mat& last = levels.back();
    if ((last.cols + 1) / 2 < kMinMipSize || (last.rows + 1) / 2 < kMinMipSize) break;
    cv::Mat down;
    cv::pyrDown(last, down);
    levels.push_back(down);
  }
  return levels;
}

}  // namespace

std::mt19937_64 makeEngine(uint64_t seed, uint64_t stream, uint64_t index) {
  const uint64_t a = splitmix64(seed), b = splitmix64(stream ^ 0x5ca1ab1eULL),
                 c = splitmix64(index + 0x1234567ULL);
  std::seed_seq seq{static_cast<uint32_t>(a), static_cast<uint32_t>(a >> 32),
                    static_cast<uint32_t>(b), static_cast<uint32_t>(b >> 32),
                    static_cast<uint32_t>(c), static_cast<uint32_t>(c >> 32)};
  return std::mt19937_64(seq);
}

const std::array<float, 4096>& normalTable() {
  static const std::array<float, 4096> table = makeNormalTable();
  return table;
}

Texture bakeTexture(double width_m, double height_m, double texel_m, const TextureStyle& style,
                    std::mt19937_64& rng) {
  const int width = std::max(2, static_cast<int>(std::ceil(width_m / texel_m)) + 1);
  const int height = std::max(2, static_cast<int>(std::ceil(height_m / texel_m)) + 1);
  const double base = style.base_grey + uniform(rng, -style.base_spread, style.base_spread);
  cv::Mat albedo(height, width, CV_32FC1, cv::Scalar(base));
  for (const NoiseOctave& octave : style.octaves) {
    if (octave.scale_m >= kUnderShapeScaleM) addValueNoise(octave, texel_m, rng, &albedo);
  }
  for (const ShapeLayer& layer : style.shapes) drawShapes(layer, base, texel_m, rng, &albedo);
  for (const NoiseOctave& octave : style.octaves) {
    if (octave.scale_m < kUnderShapeScaleM) addValueNoise(octave, texel_m, rng, &albedo);
  }
  cv::Mat level0;
  albedo.convertTo(level0, CV_8UC1);  // rounds and saturates to [0, 255]
  Texture texture;
  texture.levels = buildMips(level0);
  texture.inv_texel = static_cast<float>(1.0 / texel_m);
  return texture;
}

WorldBuilder::WorldBuilder(uint64_t seed, double texel_m)
    : rng_(makeEngine(seed, /*stream=*/1)), texel_m_(texel_m) {
  Texture plain;
  plain.levels = {cv::Mat(2, 2, CV_8UC1, cv::Scalar(128))};
  plain.inv_texel = static_cast<float>(1.0 / texel_m);
  world_.textures.push_back(plain);
}

void WorldBuilder::add(const Vec3& lo, const Vec3& hi, SyntheticSurface surface,
                       const TextureStyle& style, unsigned face_mask) {
  Box box;
  box.lo = lo.cwiseMin(hi);
  box.hi = lo.cwiseMax(hi);
  box.surface = surface;
  std::array<double, 3> tint;
  for (double& t : tint) t = 1.0 - uniform(rng_, 0, style.tint_spread);
  const Vec3 extent = box.hi - box.lo;
  for (int f = 0; f < 6; ++f) {
    const int axis = f / 2;
    Vec3 normal = Vec3::Zero();
    normal[axis] = (f % 2) ? 1.0 : -1.0;
    const double shade = kAmbient + kDiffuse * std::max(0.0, normal.dot(kLightDirection));
    Face& face = box.faces[f];
    for (int c = 0; c < 3; ++c) face.gain[c] = static_cast<float>(shade * tint[c]);
    if (!(face_mask & (1u << f))) continue;
    const int axis_u = axis == 0 ? 1 : 0, axis_v = axis == 2 ? 1 : 2;
    world_.textures.push_back(bakeTexture(extent[axis_u], extent[axis_v], texel_m_, style, rng_));
    face.texture = static_cast<int>(world_.textures.size()) - 1;
  }
  world_.boxes.push_back(box);
}

void WorldBuilder::repeat(size_t first, const Vec3& shift) {
  const size_t end = world_.boxes.size();
  for (size_t i = first; i < end; ++i) {
    Box box = world_.boxes[i];
    box.lo += shift, box.hi += shift;
    world_.boxes.push_back(box);
  }
}

World WorldBuilder::build(const TrajectoryModel& trajectory) {
  world_.trajectory = trajectory;
  return std::move(world_);
}

}  // namespace rgbdslam::synthetic
