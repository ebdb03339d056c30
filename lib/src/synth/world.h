#pragma once
// Internals of the synthetic renderer (synth/scene.h), shared by its .cpp files:
//  - textures.cpp: procedural multi-scale textures baked per box face, with mips;
//  - layouts.cpp:  the room and corridor (boxes, styles) and their trajectories;
//  - floor_plan.h/.cpp: rooms and corridors with doors, and a scripted flight through them;
//  - flight.cpp:   the flight: rooms joined by corridors and doors, and a scripted flight;
//  - twins.cpp:    the lookalike rooms: two identical rooms, a flight through both;
//  - raycast.cpp:  exact ray casting of one pose into clean colour and depth;
//  - office.cpp:   the office: two rooms with plain walls and a hand-held walk through them;
//  - noise.cpp:    the Kinect error model and image noise on a clean frame;
//  - effects.cpp:  the image effects of SensorEffects (blur, auto exposure, vignetting, shot
//                  noise);
//  - depth_effects.cpp: the depth effects of SensorEffects (Nguyen noise, holes);
//  - scene.cpp:    the public API, spec parsing, TUM export, the FrameSource.
// World frame z-up, metres. Everything random takes an explicit engine seeded from the seed.
#include <array>
#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>
#include <random>
#include <vector>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/geometry/se3.h"
#include "rgbdslam/synth/scene.h"
#include "rgbdslam/util/expected.h"

namespace rgbdslam::synthetic {

// ---- random numbers (portable: no std::*_distribution, whose output is library-specific)
// An engine for one purpose ('stream') of one frame, from the scene seed.
std::mt19937_64 makeEngine(uint64_t seed, uint64_t stream, uint64_t index = 0);
inline double uniform01(std::mt19937_64& rng) { return (rng() >> 11) * 0x1.0p-53; }
inline double uniform(std::mt19937_64& rng, double lo, double hi) {
  return lo + (hi - lo) * uniform01(rng);
}
// Table of 4096 standard-normal quantiles (zero mean, unit variance), for fast noise.
const std::array<float, 4096>& normalTable();
// A standard normal sample from 16 random bits (the table's quantiles).
inline float normalFrom(uint32_t bits16) { return normalTable()[bits16 >> 4]; }
// 16-bit random numbers, four from each 64-bit draw.
class Bits16 {
 public:
  explicit Bits16(std::mt19937_64 rng) : rng_(std::move(rng)) {}
  uint32_t next() {
    if (left_ == 0) word_ = rng_(), left_ = 4;
    const uint32_t value = static_cast<uint32_t>(word_ & 0xffff);
    word_ >>= 16;
    --left_;
    return value;
  }

 private:
  std::mt19937_64 rng_;
  uint64_t word_ = 0;
  int left_ = 0;
};
// Random streams (makeEngine 'stream') of the sensor, one per purpose, drawn per frame; 1 and
// 2 are the world's textures and trajectory.
constexpr uint64_t kImageNoiseStream = 10;
constexpr uint64_t kDepthNoiseStream = 11;
constexpr uint64_t kDepthKeepStream = 12;
constexpr uint64_t kDepthLateralStream = 13;  // Nguyen lateral displacement (u, v)
constexpr uint64_t kDepthLossStream = 14;     // dark and shiny surfaces' lost readings

// ---- textures
struct NoiseOctave {
  double scale_m;    // feature size of this value-noise octave [m]
  double amplitude;  // peak amplitude [grey levels]
};
struct ShapeLayer {
  double density_per_m2;  // shapes per square metre of surface
  double min_size_m;      // shape size range [m]
  double max_size_m;
  double contrast;        // grey of a shape: base +- up to this [grey levels]
};
// How a surface looks; baked into a texture with the surface's own random draws.
struct TextureStyle {
  double base_grey = 128;    // mean albedo [grey levels]
  double base_spread = 0;    // per-surface random offset of the mean [grey levels]
  std::vector<NoiseOctave> octaves;
  std::vector<ShapeLayer> shapes;  // random rectangles, triangles and ellipses
  double tint_spread = 0.1;  // per-channel gain drawn in [1 - tint_spread, 1]
};

// Styles shared by the layouts (layouts.cpp).
TextureStyle richStyle();      // strongly textured: room surfaces, boxes, posters
TextureStyle weakWallStyle();  // corridor walls: low contrast, a few marks
TextureStyle floorStyle();     // speckled linoleum
TextureStyle ceilingStyle();
TextureStyle glassStyle();     // dark glass with objects behind it
TextureStyle blackStyle();
TextureStyle lampStyle();

// A face texture: level 0 at 'texel_m' per texel, then 2x smaller levels (pyrDown).
struct Texture {
  std::vector<cv::Mat> levels;  // CV_8UC1
  float inv_texel = 100.f;      // texels per metre at level 0
};
// Bakes a texture covering width_m x height_m.
Texture bakeTexture(double width_m, double height_m, double texel_m, const TextureStyle& style,
                    std::mt19937_64& rng);

// ---- geometry
// Faces of a box: index = 2 * axis + (0 for the lo face, 1 for the hi face); masks for
// WorldBuilder::add (bit = face index).
constexpr unsigned kAllFaces = 0x3f;
constexpr unsigned kFaceXLo = 1u << 0, kFaceXHi = 1u << 1, kFaceYLo = 1u << 2,
                   kFaceYHi = 1u << 3, kFaceZLo = 1u << 4, kFaceZHi = 1u << 5;
constexpr double kWallThickness = 0.2;  // walls, floors and ceilings of the layouts [m]
struct Face {
  int texture = 0;                        // index into World::textures (0: plain grey)
  std::array<float, 3> gain{1, 1, 1};    // BGR: tint * lambert shading
};
struct Box {
  Vec3 lo, hi;  // corners, lo < hi [m]
  SyntheticSurface surface = SyntheticSurface::kDiffuse;
  std::array<Face, 6> faces;
};

// Smooth motion: offset + slope * t + sum of sinusoids, one channel per degree of freedom.
struct Wave {
  double amplitude, omega, phase;  // [m or rad], [rad/s], [rad]
};
struct Channel {
  double offset = 0, slope = 0;
  std::vector<Wave> waves;
  double at(double t) const;
};
// Position (x, y, z) [m] and a yaw-pitch-roll camera orientation [rad]: yaw about world z
// (0 looks along +x), pitch up positive, roll about the optical axis.
struct PathState {
  double x = 0, y = 0, z = 0, yaw = 0, pitch = 0, roll = 0;
};
SE3 poseOf(const PathState& s);
// A path sampled every dt seconds from t = 0 (the flight's scripted path), interpolated
// linearly between samples (yaw unwrapped, so it interpolates the short way); held at the
// last sample after its end.
struct SampledPath {
  double dt = 0.01;  // [s]
  std::vector<PathState> samples;
  PathState at(double t) const;
};
// The channels, or the sampled path where it has samples.
struct TrajectoryModel {
  Channel x, y, z, yaw, pitch, roll;
  SampledPath path;
  SE3 pose(double t) const;
};

struct World {
  std::vector<Box> boxes;
  std::vector<Texture> textures;  // [0] is a plain grey texture for unseen faces
  TrajectoryModel trajectory;
};

// Adds boxes with a texture per visible face; faces outside 'face_mask' (bit = face index)
// get the plain texture.
class WorldBuilder {
 public:
  WorldBuilder(uint64_t seed, double texel_m);
  void add(const Vec3& lo, const Vec3& hi, SyntheticSurface surface, const TextureStyle& style,
           unsigned face_mask = 0x3f);
  std::mt19937_64& rng() { return rng_; }
  // Adds a copy of boxes [first, end) moved by 'shift', sharing their textures: a
  // twin of what they make, texel for texel (building it again would not be: a texture's
  // size, and so the random draws after it, follow the box's extent in floating point).
  void repeat(size_t first, const Vec3& shift);
  World build(const TrajectoryModel& trajectory);

 private:
  std::mt19937_64 rng_;
  double texel_m_;
  World world_;
};

// The scenes; 'duration_s' is the length of the trajectory (the corridor is built long
// enough for it).
World buildRoom(uint64_t seed, double duration_s);
World buildCorridor(uint64_t seed, double duration_s);
World buildFlight(uint64_t seed, double duration_s);
World buildOffice(uint64_t seed, double duration_s);
World buildTwins(uint64_t seed, double duration_s);

// ---- rendering
// Exact images of one pose: colour without noise, camera-frame depth z [m] of surfaces that
// return depth (0 elsewhere), and the SyntheticSurface label of each pixel.
// Besides, for the depth effects: the depth of every hit (glass and black too) and the
// cosine of the angle between the ray and the surface normal.
struct CleanFrame {
  cv::Mat colour;         // CV_8UC3 BGR
  cv::Mat depth_m;        // CV_32FC1
  cv::Mat surfaces;       // CV_8UC1
  cv::Mat hit_z;          // CV_32FC1, camera-frame z of any surface hit [m], 0: none
  cv::Mat cos_incidence;  // CV_32FC1, cos(theta) in [0, 1], 0 where nothing is hit
};
void castRays(const World& world, const PinholeCamera& camera, const SE3& T_w_c,
              CleanFrame* out);

// ---- lens distortion (lib/src/synth/lens.cpp)
// A distorted camera is rendered by ray-casting an ideal pinhole 'canvas' camera (same focal
// lengths, large enough to hold everything the lens sees) and resampling: each pixel of the
// distorted image takes the canvas pixel its ray passes through.
struct LensResampling {
  PinholeCamera canvas;  // no distortion
  cv::Mat map_u, map_v;  // CV_32FC1, the distorted image's size: canvas coordinates [px]
};
// Error when the distortion cannot be inverted over the image (checked on a grid of pixels
// and along the border) or would need a canvas over 4x the image on a side.
Status checkLens(const PinholeCamera& distorted);
// Needs checkLens(distorted) to pass.
LensResampling makeLensResampling(const PinholeCamera& distorted);
// Colour bilinear; depth and surface labels from the nearest canvas pixel (never blended
// across an edge).
void resampleThroughLens(const LensResampling& lens, CleanFrame* frame);

// Image noise on 'colour' (in place) and the Kinect model from clean depth to raw depth.
// Frame 'index' selects the random streams, so each frame's noise is fixed.
void addImageNoise(const KinectNoiseOptions& noise, uint64_t seed, size_t index,
                   cv::Mat* colour);
cv::Mat kinectDepth(const KinectNoiseOptions& noise, uint64_t seed, size_t index,
                    const cv::Mat& depth_m, double depth_factor);
// Steps 2, 3 and 5 of the Kinect model on a noisy depth [m]: quantisation (fbs = f b / s),
// range, storage; 0: no reading.
uint16_t rawReading(const KinectNoiseOptions& noise, double fbs, double z_measured,
                    double depth_factor);
// True if frame 'index' has depth at all (depth on, within depth_frames).
bool depthActive(const KinectNoiseOptions& noise, size_t index);

// ---- sensor effects (SensorEffects; effects.cpp and depth_effects.cpp)
constexpr int kBlurSubFrames = 5;  // renders averaged per blurred frame (odd: the middle one is
                                   // the frame's own pose)
// Time offsets [s] of the sub-frames from the frame's time.
std::array<double, kBlurSubFrames> blurOffsets(double exposure_ms);
// The metering's target gain of a clean colour image, and the lagged gain of frame 'index'
// given the target gain of any frame (clamped to frame 0 before it).
double meteredGainOf(const cv::Mat& clean_colour);
template <typename TargetOf>
double laggedGain(size_t index, double rate_hz, double lag_s, const TargetOf& target_of);
// A small camera (1/16 of the size, same field of view) for metering.
PinholeCamera meteringCamera(const PinholeCamera& camera);
// Exposure gain (clamped at 255), vignetting (for 'camera', the undistorted image geometry
// the colour is in) and signal-dependent noise, in place.
void applyExposureAndVignetting(const SensorEffects& effects, const PinholeCamera& camera,
                                double gain, cv::Mat* colour);
void addSignalDependentNoise(const KinectNoiseOptions& noise, const SensorEffects& effects,
                             uint64_t seed, size_t index, cv::Mat* colour);
// Geometric holes on a clean frame, before lens resampling (the projector's epipolar lines
// are the rows of the ideal image): the edge band and IR shadows, by zeroing depth_m.
void removeGeometricDepth(const SensorEffects& effects, const KinectNoiseOptions& noise,
                          double fx, CleanFrame* frame);
// The Kinect model with the depth effects: material losses, Nguyen noise, then as
// kinectDepth (quantisation, range, sparsity, storage).
cv::Mat kinectDepthWithEffects(const KinectNoiseOptions& noise, const SensorEffects& effects,
                               uint64_t seed, size_t index, const CleanFrame& clean,
                               double depth_factor);

template <typename TargetOf>
double laggedGain(size_t index, double rate_hz, double lag_s, const TargetOf& target_of) {
  // exp(-dt/tau)-weighted mean of log targets over 4 tau: a first-order lag, truncated.
  const double decay = std::exp(-1.0 / (rate_hz * lag_s));
  const size_t window = static_cast<size_t>(std::ceil(4.0 * lag_s * rate_hz));
  double weight = 1, sum_w = 0, sum = 0;
  for (size_t k = 0; k <= window; ++k, weight *= decay) {
    const size_t frame = index >= k ? index - k : 0;
    sum += weight * std::log(target_of(frame));
    sum_w += weight;
  }
  return std::exp(sum / sum_w);
}

}  // namespace rgbdslam::synthetic
