#pragma once
// Synthetic RGB-D sequences with exact ground truth: a textured room, a long corridor
// (weak texture, glass cabinets, black surfaces, a room in the middle) and a flight (a
// micro aerial vehicle's tours through three rooms joined in a loop by corridors: 2 m/s
// stretches, 90 deg/s spins, hovering, height changes, rooms entered again through other
// doors, a figure of eight; plain walls, glass, a dark corner, a hall beyond the depth
// range; the floor plan is in lib/src/synth/flight.cpp), rendered by
// analytic ray casting against axis-aligned boxes, with the Kinect error model of the paper
// (sigma(d) = a d^2, range limits, disparity quantisation, holes) and, behind their own keys,
// the truer sensor of SensorEffects (motion blur, auto exposure, vignetting, shot noise,
// Nguyen depth noise, depth holes at edges, in IR shadows, on dark and shiny surfaces).
//
// Why: the SLAM pipeline is checked end to end against exact poses; the capture process
// publishes these frames like a device would.
//
// Frames: the world is z-up; T_w_c maps camera coordinates (x right, y down, z forward) into
// the world. Depth is the camera-frame z of the surface point [m], stored raw in units of
// 1/depth_factor m (5000 per metre). Times are host-clock microseconds from a fixed epoch.
//
// Determinism: everything random (textures, trajectory phases, noise) derives from
// options.seed through std::mt19937_64 seeded per purpose and per frame, so the same
// options give bit-identical frames in any order and on every call. The geometry, textures
// and trajectory depend only on (scene, seed, length, rate_hz), never on the noise
// options: two scenes differing only in noise see the same surfaces. The flight's floor
// plan does not depend on the length, and a short flight is the start of a long one.
//
// Call order: parseSyntheticSpec() (or fill SyntheticOptions), construct SyntheticScene
// (builds and bakes textures, ~0.1-0.5 s), then render(i) in any order; render() is const
// and may be called from several threads.
#include <array>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <string>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/geometry/se3.h"
#include "rgbdslam/image/rgbd_frame.h"
#include "rgbdslam/io/frame_source.h"
#include "rgbdslam/io/trajectory_io.h"
#include "rgbdslam/util/expected.h"

namespace rgbdslam {

enum class SyntheticSceneKind { kRoom, kCorridor, kFlight, kOffice, kTwins };

// What a pixel sees (the optional label image of SyntheticScene::renderPose).
enum class SyntheticSurface : uint8_t {
  kNothing = 0,  // no surface (does not happen in the closed scenes)
  kDiffuse = 1,  // textured surface that returns depth
  kGlass = 2,    // glass: colour but no depth
  kBlack = 3,    // black, light-absorbing: dark colour and no depth
  kShiny = 4,    // glossy (whiteboard, screen, lacquered desk): depth unless shiny_holes drops it
};

// The Kinect error model (paper eq. 17 and the sensor's disparity quantisation). Applied in
// this order to the exact depth z of a surface that returns depth:
//   1. noise:      z_n = z + sigma(z) * N(0,1),   sigma(z) = sigma_coefficient * z^2;
//   2. quantise:   z_q = f b / (s * round(f b / (s z_n))), i.e. disparity f b / z rounded to
//                  steps of s = disparity_step_px (f = disparity_focal_px, b = baseline_m), so
//                  the output lies on the sensor's depth grid like real Kinect data;
//   3. range:      no reading unless min_range_m <= z_q <= max_range_m;
//   4. sparsity:   each reading kept with probability depth_fraction;
//   5. storage:    raw = round(z_q * depth_factor) (uint16).
// Noise comes before quantisation (as in the sensor, where the disparity is what is noisy
// and then quantised); with quantise off the error is exactly Gaussian with sigma(z).
struct KinectNoiseOptions {
  double sigma_coefficient = 3.331e-3;  // a in sigma(d) = a * d^2 [1/m]
  double min_range_m = 0.5;             // no reading closer than this [m]
  double max_range_m = 4.5;             // no reading farther than this [m]
  bool quantise = true;                 // quantise depth in disparity (formula above)
  double disparity_focal_px = 580.0;    // f of the IR camera for quantisation [px]
  double baseline_m = 0.075;            // b, projector-camera baseline [m]
  double disparity_step_px = 0.125;     // s, disparity resolution (1/8 px) [px]
  double depth_fraction = 1.0;          // fraction of readings kept, in (0, 1] (sparse depth)
  bool depth_enabled = true;            // false: no depth at all (all zero)
  int depth_frames = -1;                // only frames 0..N-1 have depth (-1: all; 1: first only)
  double image_noise_sigma = 2.0;       // Gaussian noise on each colour channel [grey levels]
};

// The truer sensor (issue 12): effects that make synthetic runs fail where real ones do. Each
// is off at its default value (0 / false), so a spec without these keys renders bit-identical
// frames to the renderer without them; "effects=all" sets every one to the values of
// SensorEffects::all(), "effects=none" turns all off. Models (docs/design.md, "The renderer's
// sensor models"):
//  - exposure_ms: motion blur. The colour image is the mean of kBlurSubFrames = 5 renders at
//    t_i + exposure * ((k + 0.5) / 5 - 0.5), k = 0..4, along the continuous trajectory (the
//    middle one is the frame's own pose and gives depth and labels). Costs 5 ray casts.
//  - auto_exposure_s: a global gain g_i applied to the colour image (clamped at 255), a
//    first-order lag with this time constant of the gain the metering asks for,
//    target_grey / (mean grey of the clean image), limited to [1/4, 4]: log g_i is the
//    exp(-dt/tau)-weighted mean of the log target gains of frames i, i-1, ... over 4 tau
//    (frames before 0 count as frame 0), so any frame is rendered on its own.
//  - vignetting: corner darkening, colour *= 1 - vignetting * (1 - cos^4 alpha), alpha the
//    angle of the pixel's ray to the optical axis (1: the natural cos^4 law).
//  - shot_noise: signal-dependent image noise, sigma^2 = noise_sigma^2 + shot_noise * I
//    [grey levels^2], I the noise-free grey level (noise_sigma is then the read noise).
//  - nguyen_depth: depth noise of Nguyen, Izadi and Lovell (2012) instead of sigma = a z^2:
//    axial sigma_z = 1.2 mm + 1.9 mm (z - 0.4 m)^2 + 0.1 mm / sqrt(z) theta^2 / (pi/2 -
//    theta)^2 (z in m, theta the angle between the ray and the surface normal, capped at
//    88 deg), and lateral noise: the reading is taken from a pixel displaced by
//    N(0, sigma_L^2) in u and v, sigma_L = 0.8 + 0.035 theta / (pi/2 - theta) [px]; then
//    the disparity quantisation as before.
//  - edge_holes_px: no reading within this many pixels of a depth discontinuity (a jump of
//    more than 5 % of the depth between 4-neighbours).
//  - ir_shadow: no reading where the projector, baseline_m to the right (+x) of the IR
//    camera, cannot see the surface: a per-row occlusion test in projector coordinates
//    (rows are epipolar lines), so bands f b (1/z_near - 1/z_far) px wide appear left of
//    nearer edges.
//  - dark_holes: a weak IR return is lost. Signal s = (grey / 255) cos(theta) / z^2 (1 for
//    a white matte wall facing the sensor at 1 m); the reading is kept with probability
//    clamp((s - dark_holes) / dark_holes, 0, 1), so s < dark_holes always loses it.
//  - shiny_holes: kShiny surfaces lose depth at near-normal incidence (theta < 12 deg: the
//    projector's pattern saturates in the specular highlight) and at grazing incidence
//    (theta > 65 deg: the pattern is mirrored away). Off: they return depth like kDiffuse.
struct SensorEffects {
  double exposure_ms = 0;      // exposure time for motion blur [ms], 0: no blur; <= 1000 / rate
  double auto_exposure_s = 0;  // auto-exposure lag time constant [s], 0: fixed gain 1; <= 10
  double vignetting = 0;       // strength of the cos^4 falloff, in [0, 1]
  double shot_noise = 0;       // shot-noise variance per grey level [grey levels], in [0, 10]
  bool nguyen_depth = false;   // Nguyen et al. axial and lateral depth noise
  int edge_holes_px = 0;       // band without depth beside depth edges [px], in [0, 10]
  bool ir_shadow = false;      // no depth where the projector is occluded
  double dark_holes = 0;       // IR signal threshold (see above), in [0, 1], 0: off
  bool shiny_holes = false;    // kShiny surfaces lose depth at near-normal and grazing incidence

  // Every effect on: 20 ms exposure (indoor light), 0.5 s lag, vignetting 0.5 (corners at
  // ~70 %), shot noise 0.05 (sigma ~3.8 at grey 200 with read noise 2), Nguyen depth, a 1 px
  // edge band, IR shadows, dark_holes 0.01 (an 11 % grey surface facing the sensor keeps
  // every reading within 2.3 m and none beyond 3.3 m; a 43 % grey floor seen at 3 m from
  // 1.3 m height keeps them, at 4 m it has none), shiny holes.
  static SensorEffects all();
  bool any() const { return *this != SensorEffects{}; }
  bool anyDepth() const {
    return nguyen_depth || edge_holes_px > 0 || ir_shadow || dark_holes > 0 || shiny_holes;
  }
  bool operator==(const SensorEffects& o) const;
  bool operator!=(const SensorEffects& o) const { return !(*this == o); }
};

struct SyntheticOptions {
  SyntheticSceneKind scene = SyntheticSceneKind::kRoom;
  uint64_t seed = 1;     // everything random derives from it
  int num_frames = 0;    // 0: from minutes, else the scene's default length (room 600,
                         // corridor 3300, flight 18000, office 1240 frames: 20 s, 110 s,
                         // 10 min, 41 s)
  double minutes = 0;    // length in minutes (0: see num_frames; not with num_frames)
  double rate_hz = 30.0; // frame rate [Hz]
  // Frames drop_first..drop_last (indices, inclusive) are left out by the FrameSource, as if
  // the camera or the link lost them: the frames around keep their indices and timestamps,
  // so a gap in time appears (drop=120-149 at 30 Hz: 1 s). -1: nothing dropped. The scene
  // itself (render, groundTruth) is unaffected.
  int drop_first = -1;
  int drop_last = -1;
  // Only every every-th frame reaches the FrameSource (frames 0, K, 2K, ...; every=2: every
  // other frame, so the camera moves twice as far between frames). 1: all frames.
  int every = 1;
  // Frames cover_first..cover_last (inclusive) are delivered as with a hand over the lens:
  // a dark, noisy image (grey level ~8 + image noise) and no depth reading at all. The
  // trajectory goes on behind the hand. -1: nothing covered.
  int cover_first = -1;
  int cover_last = -1;
  // Lens distortion of the rendered images, k1 k2 p1 p2 k3 (OpenCV order, as in the camera
  // files): the camera() carries it and the frames are rendered through it, so the lens
  // model is exercised end to end (e.g. the TUM fr1 Kinect's 0.2624 -0.9531 -0.0054 0.0026
  // 1.1633). All zero: none.
  std::array<double, 5> distortion{};
  // Other cameras: image size [px] and fx fy cx cy [px] of the rendered frames (default: the
  // Kinect-like 640x480, 525 525 319.5 239.5 of config/cameras/synthetic.yaml).
  int width = 640, height = 480;
  std::array<double, 4> intrinsics{525.0, 525.0, 319.5, 239.5};
  KinectNoiseOptions noise;
  // Off by default; parseSyntheticSpec gives the office SensorEffects::all() (see
  // defaultEffects).
  SensorEffects effects;

  // True if the FrameSource leaves frame i out.
  bool dropped(size_t i) const {
    const bool in_gap = drop_first >= 0 && i >= static_cast<size_t>(drop_first) &&
                        i <= static_cast<size_t>(drop_last);
    return in_gap || (every > 1 && i % static_cast<size_t>(every) != 0);
  }
  // True if frame i is rendered covered.
  bool covered(size_t i) const {
    return cover_first >= 0 && i >= static_cast<size_t>(cover_first) &&
           i <= static_cast<size_t>(cover_last);
  }
};

// The effects a spec of this scene starts from: none, except for the office.
// Decision: the office has every effect on by default. It is new (no published figure
// depends on its frames) and it exists to show where trackers fail on real sensors: plain
// walls with noisy, holed depth. "office,effects=none" renders it clean.
SensorEffects defaultEffects(SyntheticSceneKind scene);

// "room", "corridor", "flight" or "office" followed by optional ",key=value" pairs: seed,
// frames, minutes, rate,
// depth_fraction, depth (on|off|first), depth_frames, min_range, max_range, noise_sigma
// (image noise), depth_sigma (a), quantise (0|1), drop (FIRST-LAST frame indices, inclusive,
// or one index N; see SyntheticOptions::drop_first), every (K >= 1), cover (FIRST-LAST or N,
// like drop), distortion (K1:K2:P1:P2[:K3], colon-separated), size (WxH), intrinsics
// (FX:FY:CX:CY); the sensor effects (SensorEffects, all off by default except in the
// office): effects (all|none), exposure [ms], auto_exposure [s], vignetting, shot_noise,
// depth_noise (kinect|nguyen), edge_holes [px], ir_shadow (0|1), dark_holes, shiny_holes
// (0|1). Later keys override earlier ones ("effects=all,exposure=0"). E.g.
// "room,seed=3,depth_fraction=0.3", "flight,minutes=2", "room,frames=300,drop=120-149", "room,every=2",
// "room,cover=120-149", "room,distortion=0.2624:-0.9531:-0.0054:0.0026:1.1633".
// An unknown key or bad value is an Error naming it.
Expected<SyntheticOptions> parseSyntheticSpec(const std::string& spec);
// The spec string of 'options' (round-trips through parseSyntheticSpec), for logs.
std::string formatSyntheticSpec(const SyntheticOptions& options);
// Checks ranges (rate > 0, 0 < min_range < max_range <= 13 m, depth_fraction in (0,1],
// 0 <= drop_first <= drop_last or both -1, the same for cover, every >= 1, a distortion
// that is invertible over the image, the effects' ranges in SensorEffects, ...).
Status validateSyntheticOptions(const SyntheticOptions& options);

namespace synthetic {
struct World;  // boxes, baked textures and the trajectory (lib/src/synth/world.h)
struct LensResampling;  // pinhole canvas -> distorted image (lib/src/synth/world.h)
}

class SyntheticScene {
 public:
  // Options must pass validateSyntheticOptions (asserted).
  explicit SyntheticScene(const SyntheticOptions& options);
  ~SyntheticScene();
  SyntheticScene(const SyntheticScene&) = default;  // cheap: the baked world is shared
  SyntheticScene& operator=(const SyntheticScene&) = default;

  const SyntheticOptions& options() const { return options_; }
  // By default 640x480, fx = fy = 525, cx = 319.5, cy = 239.5, no distortion,
  // depth_factor 5000, name "synthetic" (= config/cameras/synthetic.yaml); the options' size,
  // intrinsics and distortion where given.
  const PinholeCamera& camera() const { return camera_; }
  size_t numFrames() const { return num_frames_; }
  // 1700000000 s + i / rate_hz, in microseconds.
  int64_t frameUtime(size_t i) const;
  // T_w_c of frame i, exact (the pose render(i) uses).
  SE3 groundTruthPose(size_t i) const;
  // All frames, t = frameUtime(i) * 1e-6 s.
  Trajectory groundTruth() const;
  // Colour CV_8UC3 BGR, depth CV_16UC1 raw (0 = none), depth_scale 5000, camera_name
  // "synthetic", seq = i, utime = frameUtime(i).
  RgbdFrame render(size_t i) const;
  // As render(i) but from an arbitrary pose (noise and depth schedule of frame i). If
  // 'surfaces' is given it receives a CV_8UC1 image of SyntheticSurface values.
  RgbdFrame renderPose(const SE3& T_w_c, size_t i, cv::Mat* surfaces = nullptr) const;
  // The truth a depth image approximates: camera-frame depth z [m] of the first surface each
  // pixel's ray hits at T_w_c, glass and black surfaces included and at any range, NaN where
  // the ray hits nothing; no noise, no sensor effect. For measuring what a method placed
  // where (bench_epipolar).
  cv::Mat trueDepth(const SE3& T_w_c) const;
  // The auto-exposure gain of frame i (1 without auto exposure), and the gain its metering
  // asks for (target grey / mean grey of the clean image of frame i, within [1/4, 4]).
  double exposureGain(size_t i) const;
  double meteredGain(size_t i) const;
  // Writes rgb/, depth/ (16-bit PNG), rgb.txt, depth.txt and groundtruth.txt in the TUM
  // layout (file names are the timestamps in seconds with 6 decimals).
  Status writeTumDirectory(const std::string& dir) const;

 private:
  SyntheticOptions options_;
  PinholeCamera camera_;
  size_t num_frames_ = 0;
  std::shared_ptr<const synthetic::World> world_;
  // With distortion: frames are ray-cast through an ideal pinhole camera onto a canvas that
  // covers the lens' field of view, then resampled into the distorted image.
  std::shared_ptr<const synthetic::LensResampling> lens_;

  void addImageNoise(size_t i, cv::Mat* colour) const;
  void blurColour(const PinholeCamera& cast_camera, const SE3& T_w_c, size_t i,
                  cv::Mat* colour) const;
};

// A FrameSource that renders the frames on the fly, in order, leaving out the dropped ones
// (size() counts only the frames it will deliver).
std::unique_ptr<FrameSource> makeSyntheticSource(const SyntheticOptions& options);

}  // namespace rgbdslam
