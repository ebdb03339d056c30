#pragma once
// PTAM's tracker with depth (paper II-A, III). One call per frame:
//   track(frame): build pyramid, corners and small blurry image; on the first frame create
//   the initial map from depth (keyframe 0); otherwise predict the pose (damped constant
//   velocity, rotation pre-estimate from small blurry images), project the visible map
//   points, warp their patches, search among FAST corners by ZMSSD, refine to sub-pixel,
//   and update the pose by Gauss-Newton with Tukey weights (coarse stage: few points at high
//   levels with a wide search, only when the image is predicted to move more than the fine
//   search covers; fine stage: many points). Tracking quality (fraction found) gives
//   tracking / dodgy / lost, and a frame whose found points do not fix the pose (its
//   standard deviation from the fit) is lost too; when lost, the relocaliser compares the
//   small blurry image with every keyframe's and tries the best. Finally the keyframe
//   decision (also when few points were found and depth can bring new ones); a new keyframe
//   gets provisional points from measured depth at once and is returned for the mapper.
//   applyMapUpdate(update): the mapper's newer map versions replace the replica's poses and
//   points; older or foreign versions are ignored (the return value says why).
// Frames: T_w_c camera to world; pixels at level 0; depth in metres.
#include <memory>
#include <optional>
#include <string>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/image/rgbd_frame.h"
#include "rgbdslam/map/map.h"
#include "rgbdslam/model/point_creation.h"
#include "rgbdslam/model/slam_mode.h"
#include "rgbdslam/tracking/pose_estimate.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

struct TrackerOptions {
  // Motion model
  double velocity_damping = 0.9;        // fraction of last frame's velocity kept [0, 1]
  bool use_sbi_rotation = true;         // rotation pre-estimate from small blurry images
  // Point search
  int coarse_max_points = 60;           // points searched in the coarse stage
  int coarse_min_level = 2;             // coarse stage uses points found at this level or above
  int coarse_radius_px = 10;            // coarse search radius at the search level [px]
  int fine_max_points = 1000;           // points searched in the fine stage
  int fine_radius_px = 4;               // fine search radius at the search level [px]
  int max_zmssd_per_pixel = 400;        // patch acceptance: ZMSSD / 64 below this [grey^2]
  // ...or ZMSSD below this times the template's zero-mean energy (PointSearchOptions)
  double max_zmssd_energy_ratio = 0.5;
  // ...and always below this times that energy: a weak template is not accepted on a
  // textureless patch (PointSearchOptions::max_zmssd_flat_ratio; 0: off)
  double max_zmssd_flat_ratio = 0.7;
  bool search_dense_fallback = true;    // test every pixel in the radius when no corner matches
  int coarse_min_points = 10;           // fewer coarse candidates: skip the coarse stage
  // The coarse stage runs only when the predicted image motion, the median displacement of
  // the visible points between the last pose and the start pose, is at least this [px at
  // level 0]. Like PTAM's Tracker.CoarseMinVelocity, but measured in the image: forward
  // motion (a corridor) moves the image little however fast the camera goes, and there a
  // coarse stage on a few dozen matches at coarse levels only pulls a good prediction off
  // (measured: 4-deg jumps that ended the corridor run).
  double coarse_min_motion_px = 4.0;
  // A result below quality_good after a coarse stage is compared with the fine stage alone
  // from the prediction; the one with the higher quality is kept.
  bool retry_without_coarse = true;
  // ...and so is a result whose quality fell below this fraction of the last frame's: the
  // view changes little from one frame to the next, so a sudden drop means the coarse stage
  // pulled the pose off, even when what is left still counts as good (measured on the
  // corridor's end wall: 0.81 -> 0.38 and a 5 cm jump, whose keyframe then triangulated the
  // wall at 40 % of its distance and ended the run; 0: off).
  double retry_quality_ratio = 0.6;
  int image_margin_px = 8;              // projected points this close to the border are skipped [px]
  double patch_cache_tolerance = 0.05;  // re-warp a cached patch when an entry of A changes more
  int gauss_newton_iterations = 10;     // pose iterations per stage
  double tukey_c = 4.6851;              // Tukey cut-off in robust sigmas
  double min_robust_sigma = 0.4;        // floor of the robust sigma [measurement sigmas]
  double max_robust_sigma = 1.0;        // cap of the robust sigma after the free iterations
  int free_scale_iterations = 5;        // pose iterations with the uncapped median scale
  bool use_depth_in_pose = true;        // add depth residuals of tracked corners to the pose
  double depth_sigma_coefficient = 3.331e-3;  // a in sigma_d = a d^2 for depth residuals [1/m]
  int random_seed = 1;                  // seed of the point subset selection (deterministic)
  // Quality
  double quality_good = 0.3;            // found / searched at least this: tracking
  double quality_lost = 0.13;           // below this: lost (between: dodgy)
  int min_points_tracked = 10;          // fewer found points: lost whatever the ratio
  // How well the found points fix the pose: lost when the pose's standard deviation, from
  // the fit's J^T W J with the measurement sigmas (pose_optimizer.h), exceeds these in the
  // worst direction. With depth residuals a few well-spread points fix all six degrees of
  // freedom; points in a line or all far away do not, whatever their number.
  double max_pose_sigma_m = 0.05;       // [m]
  double max_pose_sigma_deg = 1.0;      // [deg]
  // A point searched at least this often and found in less than unreliable_found_ratio of
  // those frames is unreliable (fur, thin structures, wrong depth): still searched, but it
  // does not count in the quality, which should measure the view, not the map's bad points.
  int unreliable_after_searches = 10;   // [frames]
  double unreliable_found_ratio = 0.3;  // found / searched
  // Initialisation and relocalisation
  int init_min_points = 20;             // keyframe 0 needs this many points from depth,
                                        // and they must fix its pose (max_pose_sigma_*)
  int relocalise_candidates = 2;        // best keyframes (by small-blurry-image ZMSSD) tried
  // Keyframes
  int min_frames_between_keyframes = 10;      // frames since the last keyframe
  double keyframe_distance_ratio = 0.1;       // min distance to nearest keyframe / median scene depth
  double keyframe_angle_deg = 15.0;           // or this much rotation from the nearest keyframe [deg]
  // With depth for new points, a frame that found fewer points than this gets a keyframe
  // after keyframe_few_points_min_frames, wherever it is (keyframe_policy.h; 0: off).
  int keyframe_few_points = 60;               // [points]
  int keyframe_few_points_min_frames = 3;     // [frames]
  // The same in mono, where a keyframe gets its points only from the mapper's epipolar
  // search against an earlier keyframe (0: off). Measured on the synthetic corridor (900
  // frames, final position error) with one epipolar partner: 80 points with a wait of 2, 3
  // or 4 frames 0.16, 0.05, 0.12 %; 100 and 3: 0.11 %; 60 and 2-4: 0.4-0.8 %, but 60 and 5
  // or 40 and 3 let the points run short and the scale collapsed (50-70 %), 60 and 8 lost
  // tracking. With two partners (mapper.epipolar_partners_mono) 60 and 5: 0.18 %, 40 and
  // 3: 0.09 %.
  int keyframe_few_points_mono = 80;          // [points]
  int keyframe_few_points_mono_min_frames = 3;  // [frames]
  // PTAM adds keyframes only while tracking is good, because a monocular keyframe's points
  // need later views to be triangulated. A keyframe with depth brings its own points at once,
  // so while dodgy (the view drifting away from the mapped part) a keyframe is what restores
  // tracking: allowed whenever the mode creates points from depth.
  bool keyframes_while_dodgy = true;
  // Keyframe images and provisional points
  KeyframeBuildOptions keyframe_build;
  DepthPointOptions depth_points;

  void bind(OptionRegistry* registry);  // section "tracker"
};

// Whether a frame tracked with a coarse stage, to 'quality', is tracked again from the
// prediction without it (retry_without_coarse, quality_good, retry_quality_ratio);
// 'last_quality' is the last accepted frame's quality (0 when there is none).
bool coarseRetryWanted(const TrackerOptions& options, double quality, double last_quality);

struct TrackResult {
  enum class Status {
    kInitialised,   // this frame became keyframe 0 of a new map
    kTracked,       // pose found (state tracking or dodgy)
    kLost,          // no pose; relocalising
    kRelocalised,   // recovered from loss with this frame
    kBadFrame,      // unusable input (no colour, wrong size); 'error' says why
    kNotInitialised,  // no map yet and this frame cannot start one (too few corners with
                      // depth); not an input error: the next frames are tried
  };
  Status status = Status::kBadFrame;
  PoseEstimate pose;
  std::optional<KeyframeData> new_keyframe;  // for the mapper, with provisional points
  std::string error;                         // for kBadFrame
  double track_ms = 0.0;                     // time spent in track() [ms]
};

class Tracker {
 public:
  Tracker(const PinholeCamera& camera, const TrackerOptions& options, SlamMode mode, int64_t map_id);
  ~Tracker();
  TrackResult track(const RgbdFrame& frame);

  // kApplied: applied. kStale: version <= mapVersion(), ignored. kForeignMap: another
  // map_id, ignored. kUnknownKeyframe: applied, but it named keyframes (poses or point
  // sources) the replica does not have; those entries were skipped. kMissingDelta: a delta
  // whose version is not mapVersion() + 1 (an update in between was lost); ignored, because
  // applying it would leave the replica a mix of versions -- the next snapshot repairs it.
  enum class UpdateStatus { kApplied, kStale, kForeignMap, kUnknownKeyframe, kMissingDelta };
  UpdateStatus applyMapUpdate(const MapUpdate& update);

  const Map& map() const;
  int64_t mapVersion() const;
  void reset();  // forget the map; the next frame initialises a new one

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rgbdslam
