#pragma once
// Internals of the synthetic renderer (synth/scene.h), shared by its .cpp files:
//  - textures.cpp: procedural multi-scale textures baked per box face, with mips;
//  - layouts.cpp:  the room and corridor (boxes, styles) and their trajectories;
//  - flight.cpp:   the flight: rooms joined by corridors and doors, and a scripted flight;
//  - raycast.cpp:  exact ray casting of one pose into clean colour and depth;
//  - noise.cpp:    the Kinect error model and image noise on a clean frame;
//  - scene.cpp:    the public API, spec parsing, TUM export, the FrameSource.
// World frame z-up, metres. Everything random takes an explicit engine seeded from the seed.
#include <array>
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

// ---- rendering
// Exact images of one pose: colour without noise, camera-frame depth z [m] of surfaces that
// return depth (0 elsewhere), and the SyntheticSurface label of each pixel.
struct CleanFrame {
  cv::Mat colour;    // CV_8UC3 BGR
  cv::Mat depth_m;   // CV_32FC1
  cv::Mat surfaces;  // CV_8UC1
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

}  // namespace rgbdslam::synthetic
