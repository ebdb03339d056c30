#pragma once
// Synthetic RGB-D sequences with exact ground truth: a textured room, a long corridor
// (weak texture, glass cabinets, black surfaces, a room in the middle) and a flight (a
// micro aerial vehicle's tours through three rooms joined in a loop by corridors: 2 m/s
// stretches, 90 deg/s spins, hovering, height changes, rooms entered again through other
// doors, a figure of eight; plain walls, glass, a dark corner, a hall beyond the depth
// range; the floor plan is in lib/src/synth/flight.cpp), rendered by
// analytic ray casting against axis-aligned boxes, with the Kinect error model of the paper
// (sigma(d) = a d^2, range limits, disparity quantisation, holes).
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

enum class SyntheticSceneKind { kRoom, kCorridor, kFlight };

// What a pixel sees (the optional label image of SyntheticScene::renderPose).
enum class SyntheticSurface : uint8_t {
  kNothing = 0,  // no surface (does not happen in the closed scenes)
  kDiffuse = 1,  // textured surface that returns depth
  kGlass = 2,    // glass: colour but no depth
  kBlack = 3,    // black, light-absorbing: dark colour and no depth
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

struct SyntheticOptions {
  SyntheticSceneKind scene = SyntheticSceneKind::kRoom;
  uint64_t seed = 1;     // everything random derives from it
  int num_frames = 0;    // 0: from minutes, else the scene's default length (room 600,
                         // corridor 3300, flight 18000 frames: 20 s, 110 s, 10 min)
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

// "room", "corridor" or "flight" followed by optional ",key=value" pairs: seed, frames,
// minutes, rate,
// depth_fraction, depth (on|off|first), depth_frames, min_range, max_range, noise_sigma
// (image noise), depth_sigma (a), quantise (0|1), drop (FIRST-LAST frame indices, inclusive,
// or one index N; see SyntheticOptions::drop_first), every (K >= 1), cover (FIRST-LAST or N,
// like drop), distortion (K1:K2:P1:P2[:K3], colon-separated), size (WxH), intrinsics
// (FX:FY:CX:CY). E.g.
// "room,seed=3,depth_fraction=0.3", "flight,minutes=2", "room,frames=300,drop=120-149", "room,every=2",
// "room,cover=120-149", "room,distortion=0.2624:-0.9531:-0.0054:0.0026:1.1633".
// An unknown key or bad value is an Error naming it.
Expected<SyntheticOptions> parseSyntheticSpec(const std::string& spec);
// The spec string of 'options' (round-trips through parseSyntheticSpec), for logs.
std::string formatSyntheticSpec(const SyntheticOptions& options);
// Checks ranges (rate > 0, 0 < min_range < max_range <= 13 m, depth_fraction in (0,1],
// 0 <= drop_first <= drop_last or both -1, the same for cover, every >= 1, a distortion
// that is invertible over the image, ...).
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
};

// A FrameSource that renders the frames on the fly, in order, leaving out the dropped ones
// (size() counts only the frames it will deliver).
std::unique_ptr<FrameSource> makeSyntheticSource(const SyntheticOptions& options);

}  // namespace rgbdslam
