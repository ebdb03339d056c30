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
//   standard deviation from the fit) is lost too, and so is one whose pose the image or the
//   depth image contradicts (photometric_integrity.h, depth_integrity.h; after retries from
//   the prediction and the last pose);
//   where the points found are too few to fix the pose, the depth image joins the fit
//   (point-to-plane against the nearest keyframes' surfaces, depth_alignment.h) and the
//   frame is dodgy if that fixes it, lost if not;
//   when lost, the relocaliser compares the
//   small blurry image with every keyframe's and tries the best; with depth, the best few
//   keyframes' ORB features are matched to the frame's and give a pose by 3-D RANSAC
//   (feature_relocaliser.h), from wherever the camera is in their view. Finally the keyframe
//   decision (also when few points were found and depth can bring new ones); a new keyframe
//   gets provisional points from measured depth at once and is returned for the mapper.
//   Lost for long where nothing relocalises (new_part_after_failures), a frame with depth
//   starts a new part of the map, as the first frame started the map.
//   load(map, add_keyframes): before the first frame, start from a map file's content
//   (map_file.h) instead of initialising a new map: the replica gets its keyframes (pyramids
//   and small blurry images rebuilt, all acknowledged) and points, and the state is lost, so
//   the relocaliser finds the pose in the loaded map on the first frames (trying first the
//   saved session's start, keyframe 0's pose). New keyframe ids continue after the loaded
//   ones; with add_keyframes false (localising only) the tracker adds none.
//   applyMap(update): a map version's content goes into the replica (map_replica.h); which
//   versions apply, in which order, is the map protocol's business (sync/tracker_sync.h).
// Frames: T_w_c camera to world; pixels at level 0; depth in metres.
#include <cmath>
#include <memory>
#include <optional>
#include <string>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/image/rgbd_frame.h"
#include "rgbdslam/map/map.h"
#include "rgbdslam/map/map_file.h"
#include "rgbdslam/model/point_creation.h"
#include "rgbdslam/model/slam_mode.h"
#include "rgbdslam/tracking/depth_alignment.h"
#include "rgbdslam/tracking/depth_integrity.h"
#include "rgbdslam/tracking/photometric_integrity.h"
#include "rgbdslam/tracking/feature_relocaliser.h"
#include "rgbdslam/tracking/keyframe_policy.h"
#include "rgbdslam/tracking/map_replica.h"
#include "rgbdslam/tracking/motion_prior.h"
#include "rgbdslam/tracking/point_projection.h"
#include "rgbdslam/tracking/pose_estimate.h"
#include "rgbdslam/tracking/pose_optimizer.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

// The prediction of the next pose (PTAM's motion model).
struct MotionOptions {
  double velocity_damping = 0.9;  // fraction of last frame's velocity kept [0, 1]
  bool use_sbi_rotation = true;   // rotation pre-estimate from small blurry images
  // A poor result from the small blurry images' rotation is compared with one from the
  // damped velocity alone: plain walls and low-contrast floors mislead that rotation by a
  // degree, beyond the fine stage's reach where too few points lie at the coarse levels
  // (corridor C1 of the flight at 2 m/s), as they do depth-aided tracking's (below).
  bool retry_without_sbi = true;

  void bind(OptionRegistry* registry, const std::string& section);
};

// The coarse stage: few points found at high levels, searched with a wide radius.
struct CoarseStageOptions {
  int max_points = 60;   // points searched at most
  int min_level = 2;     // only points whose search level is at least this
  int radius_px = 10;    // search radius at the search level [px]
  int min_points = 10;   // fewer candidates: skip the stage
  // The stage runs only when the predicted image motion, the median displacement of the
  // visible points between the last pose and the start pose, is at least this [px at level
  // 0]. Like PTAM's Tracker.CoarseMinVelocity, but measured in the image: forward motion (a
  // corridor) moves the image little however fast the camera goes, and there a coarse stage
  // on a few dozen matches at coarse levels only pulls a good prediction off (measured:
  // 4-deg jumps that ended the corridor run).
  double min_motion_px = 4.0;
  // A result below quality_good after a coarse stage is compared with the fine stage alone
  // from the prediction; the one with the higher quality is kept.
  bool retry_without = true;
  // ...and so is a result whose quality fell below this fraction of the last frame's: the
  // view changes little from one frame to the next, so a sudden drop means the coarse stage
  // pulled the pose off, even when what is left still counts as good (measured on the
  // corridor's end wall: 0.81 -> 0.38 and a 5 cm jump, whose keyframe then triangulated the
  // wall at 40 % of its distance and ended the run; 0: off).
  double retry_quality_ratio = 0.6;
  // The other way round: a poor result (by the same two rules) from the fine stage alone,
  // where the predicted image motion looked too small for the coarse stage, is compared
  // with the coarse and fine stages from the prediction. The predicted motion is only a
  // prediction: a small-blurry-image rotation misled by plain walls, or forward motion
  // whose median point lies near the focus of expansion (corridor C1 at 2 m/s).
  bool retry_with = true;

  void bind(OptionRegistry* registry, const std::string& section);  // as coarse_*, retry_*
};

// The fine stage: many points, a narrow radius.
struct FineStageOptions {
  int max_points = 1000;  // points searched at most (a random subset beyond)
  int radius_px = 4;      // search radius at the search level [px]

  void bind(OptionRegistry* registry, const std::string& section);  // as fine_*
};

// Tracking quality: tracking, dodgy or lost.
struct QualityOptions {
  double good = 0.3;           // found / searched at least this: tracking
  // Below this: lost (between: dodgy). PTAM's 0.13 is for a monocular tracker, where the
  // ratio is the only sign of a wrong pose. Here the pose's sigma (below) and the depth and
  // photometric checks judge the pose too, and the ratio falls where the camera comes back
  // to a place from another side (patches made from far other views are not found): the
  // 2-minute flight's return into room A was lost at 0.13 from frame 3186 for 390 frames
  // (68 points found at 0.12; the frames before, 44-45 at 0.17-0.22 with a sigma of
  // 2.6 mm). Below 0.06 it is lost whatever the sigma. 0.06 (2026-11-28, the only other value
  // tried): 10-minute flight 16626 / 18000 posed, ATE 14.5 mm (13906, 17.5 mm at 0.13;
  // more frames dodgy, 4191 against 2655); room, gap room, teddy, flight 720, corridor 900
  // and full, mono corridor 900, twins and the office unchanged.
  double lost = 0.06;
  int min_points_tracked = 10;  // fewer found points: lost whatever the ratio
  // How well the found points fix the pose: lost when the pose's standard deviation, from
  // the fit's J^T W J with the measurement sigmas (pose_optimizer.h), exceeds these in the
  // worst direction. With depth residuals a few well-spread points fix all six degrees of
  // freedom; points in a line or all far away do not, whatever their number.
  double max_pose_sigma_m = 0.05;   // [m]
  double max_pose_sigma_deg = 1.0;  // [deg]
  // What a flight controller may follow without question: a frame is reported tracking
  // (good) only when the fit's uncertainty keeps its frame-to-frame step error within these
  // at 3 sigma, taking two frames' errors as independent (sigma <= step / (3 sqrt 2); for
  // 2 cm: 4.7 mm). Between this and max_pose_sigma_* the pose is published as dodgy. Only
  // the report: keyframes follow the found/searched rule as in PTAM. The translation limit
  // applies where the map is metric (not mono). 0: no limit.
  double good_step_m = 0.02;    // [m]
  double good_step_deg = 1.0;   // [deg]
  // A point searched at least this often and found in less than unreliable_found_ratio of
  // those frames is unreliable (fur, thin structures, wrong depth): still searched, but it
  // does not count in the quality, which should measure the view, not the map's bad points.
  int unreliable_after_searches = 10;   // [frames]
  double unreliable_found_ratio = 0.3;  // found / searched

  void bind(OptionRegistry* registry, const std::string& section);  // as quality_*, ...
};

// Options of the tracker, bound in section "tracker" (the noise model in section "noise").
// Each part binds its own keys; the defaults are the parts' in-class ones.
struct TrackerOptions {
  MotionOptions motion;
  MotionPriorOptions motion_prior;  // the fit held to the motion within the vehicle's acceleration
  CoarseStageOptions coarse;
  FineStageOptions fine;
  ProjectionOptions projection;  // which points are searched (image margin)
  PointSearchOptions search;     // patch acceptance, both stages
  PoseOptimizerOptions pose;     // the pose fit, both stages (use_depth: not in mono)
  QualityOptions quality;
  KeyframePolicyOptions keyframes;
  // PTAM adds keyframes only while tracking is good, because a monocular keyframe's points
  // need later views to be triangulated. A keyframe with depth brings its own points at once,
  // so while dodgy (the view drifting away from the mapped part) a keyframe is what restores
  // tracking: allowed whenever the mode creates points from depth.
  bool keyframes_while_dodgy = true;
  KeyframeBuildOptions keyframe_build;  // keyframe images; depth range of frames too
  DepthPointOptions depth_points;       // provisional points of new keyframes
  int init_min_points = 20;        // keyframe 0 needs this many points from depth, and they
                                   // must fix its pose (quality.max_pose_sigma_*)
  int relocalise_candidates = 2;   // best keyframes (by small-blurry-image error after alignment) tried
  // A lost frame's small blurry image is aligned to every keyframe's (0.23 ms each at full
  // resolution; coarse to fine, relocaliser.h, about a quarter of that), which outgrows a
  // frame's 33 ms on a long flight's map. Above this many keyframes (depth modes with
  // reloc_features) it is aligned only to a shortlist of this many: the keyframes nearest
  // the last pose (half) and the best by bag of words over all keyframes (the rest; the
  // lost frame's ORB features, binary_vocabulary.h), and the feature relocaliser's
  // candidates come from the bag too (it ranks views from other directions better:
  // place_recognition.h). Below it, and in mono, all keyframes by small blurry image.
  int relocalise_shortlist = 30;   // [keyframes]
  // A vehicle does not stop when its tracker loses it: at 2 m/s it is 0.3 m on after five
  // frames, beyond the fine stage's reach from the last pose. For this many frames after a
  // loss the tracker also tries the pose the velocity at the loss carried it to (the flight's
  // first 720 frames: ATE 10.5 mm instead of 0.63 m). 0: the last pose only.
  int relocalise_coast_frames = 30;  // [frames]
  // Where depth holds the lost frames, the tracker follows the camera through them by depth
  // alone (depth_dead_reckoning.h) and tries that pose instead of the coasted one (not with
  // relocalise_coast_frames 0), and a new part starts there. Depth modes with depth_align
  // and the motion prior on; false: the coast alone.
  bool relocalise_dead_reckoning = true;
  // ...where a direction counts as held by the surfaces when they fix it within these (1
  // sigma, from their information counted as DepthAlignmentOptions::effective_samples);
  // elsewhere it follows the velocity. Measured (2026-11-29): directions the surfaces do
  // not fix (a corridor's slide, a wall's that leaves the view) came out at 0.2-2 m, and
  // edge effects slid the pose along them when taken; the 2-minute flight's turn after
  // its loss at frame 2102 (1.6 deg a frame) was fixed at 9 cm in its weakest direction,
  // and at 5 cm / 1 deg (the tracker's own bar, quality.max_pose_sigma_*) the turn was
  // left to the velocity: the new part started 15.2 deg off; at 0.1 m / 2 deg, 1.9 deg
  // (3.1 deg once the guess coasts as far past the last frame held as the coast does).
  double relocalise_reckoning_sigma_m = 0.1;    // [m]
  double relocalise_reckoning_sigma_deg = 2.0;  // [deg]
  // A pose found from the last pose is accepted on normal tracking's bar (dodgy is enough):
  // right after a loss the camera is still near it, and where many points are hidden for a
  // stretch (glass cabinets close by) the quality stays below good although the pose is
  // right. Once the velocity at the loss has carried the camera farther than this from the
  // last pose, beyond the fine stage's reach (see above), tracking from there can only find
  // a lookalike nearby (a corridor 1 m back, after a 0.5 s cover at 2 m/s: quality 0.21,
  // 31 points found, and the map built on from there), so it must be good, as from a
  // keyframe's view. With no velocity known at the loss (lost right after a relocalisation)
  // the travel counts as 0. 0: always good; a large value: always dodgy enough.
  double relocalise_last_pose_reach_m = 0.3;  // [m]
  // Nor does it fly faster than it can: a relocalised pose must lie within this speed times
  // the time since the last pose (plus 1 m for that pose's own error) of the last pose, and
  // only keyframes within that reach plus the sensor's depth range are candidates. Without
  // it a lookalike place anywhere in the map is as good as the right one (synth:twins: after
  // a 1 s cover in the second room the tracker relocalised 14 m back into the first). A
  // camera carried elsewhere is found again once the time lost allows the distance. A frame
  // stamped before the last pose (a log replayed again) is not bounded.
  // 0: anywhere at once (a hand-held camera).
  double relocalise_max_speed_m_s = 3.0;  // [m/s]
  // A camera lost where the map has nothing to relocalise against (it flew on into unmapped
  // space: the 2-minute flight's world 2 was lost from frame 1053 to 3371 in corridors it
  // had never seen) stays lost. After this many relocalisations failed in a row, a frame
  // whose depth could start a map starts a new part of it instead, at the pose the camera
  // coasted to (relocalise_coast_frames), and the tracker tracks and maps from there; the
  // ground's loop closer joins the part to the rest when it recognises a place of it
  // (mapper.h, "Parts"). Not in mono (no depth to start from), nor localising only. Only
  // frames with depth and corners count (not a covered camera's). 60: two seconds of failed
  // attempts at 30 Hz in line (the relocaliser thread of rgbd-tracker tries fewer frames:
  // longer). A relocalisation into a mapped place can take a while: after the room's 5 s
  // cover (synth:room,frames=400,cover=100-249) the first 37 uncovered frames failed; the
  // 2 s gap relocalises at its first attempt. 0: never.
  int new_part_after_failures = 60;  // [relocalisations]
  // In a new part the tracker is not lost, so it would never relocalise back into the map it
  // left when the camera returns there; the ground's loop closer joins the parts only when it
  // recognises a place (on the 2-minute flight's world 2, 212 frames after the camera was
  // back). So while in a part it started, a round of tries starts this many tracked frames
  // (with depth) after the last round ended: frames are also relocalised against the
  // keyframes of the part the camera was lost in (where it was lost, in that part's frame,
  // is what bounds the return), after their pose is out (finishFrame), spread over frames so
  // that no frame waits for a whole search: by ORB features on the round's first frame, from
  // where it was lost on the next, then one frame each from the views of the
  // relocalise_candidates keyframes whose small blurry images were most like the first
  // frame's. Candidates are only keyframes of that part within the depth range of where the
  // camera can be (relocalise_max_speed_m_s from where it was lost, plus 1 m), on a large
  // part the relocaliser's shortlist of them; the pose found must lie within that reach.
  // Found, the tracker goes on in that
  // part (its pose moved there; the published pose takes the move in at correction_rate_*)
  // and stops trying; the part it left stays in the map until the ground's loop closer joins
  // it. 0: never.
  int rejoin_every_frames = 15;  // [frames]
  int random_seed = 1;             // seed of the point subset selection (deterministic)
  DepthIntegrityOptions integrity;  // every pose against the depth image (depth modes)
  OcclusionOptions occlusion;       // points behind a nearer surface not searched (depth modes)
  PhotometricIntegrityOptions photometric;  // every pose against the image (every mode)
  DepthAlignmentOptions depth_align;  // depth where the points are too few (depth modes)
  FeatureRelocaliserOptions reloc_features;  // relocalisation from anywhere (depth modes)
  LocalMapOptions local_map;        // which keyframes keep their pyramid (map_replica.h)
  // Map corrections (the mapper's adjustment, later loop closures) move the keyframes under
  // the tracker. The tracker follows at once (its pose moves with the keyframe nearest it);
  // the pose it publishes takes the correction in at most this fast, so that a flight
  // controller never sees the map's correction as a jump (TrackResult::correction_*).
  // 0: published pose = map pose at once.
  double correction_rate_m_s = 0.1;    // [m/s]
  double correction_rate_deg_s = 3.0;  // [deg/s]
  // true: the tracker's own pose (the next frame's start) moves with the anchor keyframe at
  // once. Off by default: teddy ATE over tracker.random_seed=1..5 was 5.95-7.36 mm (mean
  // 6.47) with it, 5.47-6.12 (mean 5.74) without; corridor full 34.3 against 31.9 mm; only
  // corridor 900 gained (10.5 against 18.9 mm). Without it the next frame's tracking finds
  // the corrected map from the old pose, and only the published pose is smoothed.
  bool follow_map_corrections = false;
  // A correction that joins the camera's part of the map to another (mapper.h, "Parts") is
  // followed at once whatever this says: it moves the part by what its start was guessed
  // wrong, metres, and from the old pose the next frame would find the map beyond the fine
  // stage's reach. The published pose still takes it in at correction_rate_*.

  void bind(OptionRegistry* registry, const std::string& section = "tracker");
};

// Whether a frame tracked to 'quality' is tracked again from the prediction with the other
// choice of coarse stage: without it after one (coarse.retry_without), with it after none
// (coarse.retry_with); poor is below quality.good or below coarse.retry_quality_ratio of
// 'last_quality', the last accepted frame's quality (0 when there is none).
bool coarseRetryWanted(const TrackerOptions& options, double quality, double last_quality, bool did_coarse = true);

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
  std::optional<KeyframeData> new_keyframe;  // made in this call: for the mapper, with provisional points
  // This frame makes a keyframe: after trackPose(), finishFrame() makes it (track() has).
  bool keyframe_due = false;
  std::string error;                         // for kBadFrame
  std::string lost_reason;                   // for kLost: why ("4 points found", "depth ...")
  // The depth image contradicted this frame's first pose (DepthIntegrityOptions): tracked
  // again from the prediction and the last pose; lost if no attempt agreed with depth.
  bool inconsistent = false;
  // The points found were too few to fix the pose, and the depth image held it with them
  // (depth_alignment.h): the state is dodgy.
  bool depth_aided = false;
  // This frame started a new part of the map (TrackerOptions::new_part_after_failures): its
  // keyframe is new_keyframe, its pose (dodgy) where the camera coasted to since the loss,
  // or where depth followed it (then part_start_reckoned: relocalise_dead_reckoning).
  bool new_part = false;
  bool part_start_reckoned = false;
  // The pose fit's 1-sigma uncertainty (largest axis) of the camera centre and of the
  // orientation, from its measurements' noise models; infinite when the fit had none.
  double pose_sigma_m = INFINITY;    // [m]
  double pose_sigma_deg = INFINITY;  // [deg]
  // How far the published pose (pose.T_w_c) is from the pose in the map (pose.map_T_w_c):
  // the map's corrections not yet taken in (TrackerOptions::correction_rate_*).
  double correction_m = 0.0;    // [m]
  double correction_deg = 0.0;  // [deg]
  // The keyframe the pose rests on (the source of most points found, else the nearest in the
  // part) and pose.map_T_w_c relative to it: what re-expresses the pose in the map as it ends up
  // (rgbd-slam's final-map trajectory, as ORB-SLAM2 writes its own). -1: no pose, or none.
  KeyframeId anchor = -1;
  SE3 T_anchor_c;
  double track_ms = 0.0;                     // time spent in track() or trackPose() [ms]
};

class Tracker {
 public:
  Tracker(const PinholeCamera& camera, const TrackerOptions& options, SlamMode mode, int64_t map_id);
  ~Tracker();
  TrackResult track(const RgbdFrame& frame);
  // track() in two steps, for a process that publishes the pose before the work the pose
  // does not need (issue 10, item 6): trackPose() returns the pose (keyframe_due set when
  // the frame makes a keyframe); finishFrame() then makes the keyframe (pyramid, corners,
  // points from depth: about as long again as tracking the frame) and moves the local map
  // to the pose (JPEG coding and the store for keyframes going cold, pyramids for those
  // coming back), and returns the keyframe. Call it before anything else (applyMap, the
  // next frame); work left undone is done at the start of the next trackPose(), and a
  // keyframe made there comes in its new_keyframe, so none is lost. track() is the two in
  // one call, in the same order, with the same results. real_time (rgbd-tracker's frame
  // path): a new part's first try of a round to rejoin the part it left, which wants the
  // bag-of-words vocabulary, is left to a later frame while the vocabulary is being trained
  // (1.5-4.5 s, started at the loss) instead of waiting for it; false waits (the same
  // results whatever the timing: batch runs, the relocaliser thread).
  TrackResult trackPose(const RgbdFrame& frame);
  std::optional<KeyframeData> finishFrame(bool real_time = false);
  // While lost, a real-time caller that already holds a newer frame passes this one
  // instead of tracking it: no relocalisation is tried on it (the newer frame's is; a
  // relocalisation takes longer than a frame on a large map, and every frame queued behind
  // it would wait as long again), it is reported lost at once, and it counts as a frame
  // lost (where the tracker coasts to, TrackerOptions::relocalise_coast_frames). Not lost
  // (or no map yet): the same as trackPose().
  TrackResult passLost(const RgbdFrame& frame);
  // Frames a caller answered lost without handing them to the tracker (rgbd-tracker while
  // its relocaliser thread holds the tracker): counted as passLost() counts a frame; no
  // effect unless lost.
  void countPassedFrames(int frames);
  // A lost frame such a caller answered without the tracker, handed over later (before the
  // next frame it tracks, in time order): its depth alone steps the dead reckoning
  // (depth_dead_reckoning.h; TrackerOptions::relocalise_dead_reckoning), as a lost frame
  // tracked would; nothing else. It reads 'depth' (the camera's size, 16-bit), 'depth_scale'
  // and 'utime' only; a frame without usable depth, or not after the last pose, is ignored.
  // Not counted (countPassedFrames counts it); no effect unless lost. True when the dead
  // reckoning held the frame.
  bool followLost(const RgbdFrame& frame);
  bool lost() const;  // relocalising: the next frame would be relocalised, not tracked
  // Times a camera in a part it started went back into another part (rejoin_every_frames).
  long rejoins() const;
  // Frames on which it tried to go back (at most one try a frame).
  long rejoinTries() const;
  // Lost frames whose depth held the camera's dead reckoning (relocalise_dead_reckoning).
  long framesReckoned() const;
  // Why the tracker cannot use 'frame' (no colour image, wrong size); empty: usable. Reads
  // the camera only, so a thread may call it while another tracks.
  std::string frameError(const RgbdFrame& frame) const;

  // Returns false when entries named keyframes the replica lacks (they were skipped).
  // defer_cold: the work on cold keyframes' points is held back (MapReplica::apply) for
  // applyDeferredMap(), which does up to max_entries of it and returns whether any is left;
  // the next applyMap() does what is left first.
  bool applyMap(const MapUpdate& update, bool defer_cold = false);
  bool applyDeferredMap(size_t max_entries);
  bool hasDeferredMapWork() const;  // what applyDeferredMap() would return before its work
  void load(const LoadedMap& loaded, bool add_keyframes);

  const Map& map() const;  // its points are those in memory
  // The map's points in memory and on storage (MapReplica: a cold keyframe's points on the
  // keyframe store), and those on storage.
  size_t numPoints() const;
  size_t pointsOnStorage() const;
  int64_t pointsLostOnStorage() const;  // read back from a store that failed (its errors)
  void reset();  // forget the map; the next frame initialises a new one
  // The store of cold keyframes (TrackerOptions::local_map.store_dir), nullptr when there is
  // none; its status says why when one was asked for and could not be made (the processes
  // refuse to start then).
  const KeyframeStore* keyframeStore() const;
  const Status& keyframeStoreStatus() const;

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rgbdslam
