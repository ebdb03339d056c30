#include <climits>

#include "rgbdslam/tracking/tracker.h"

namespace rgbdslam {
namespace {

// Options that only make sense together; a contradiction leaves nothing to track.
void bindRules(TrackerOptions* o, OptionRegistry* r) {
  r->requireBelow("tracker", "keyframe_min_depth_m", "keyframe_max_depth_m");
  r->require("tracker.quality_lost must not exceed tracker.quality_good",
             [o] { return o->quality.lost <= o->quality.good; });
  r->require("tracker.min_points_tracked must not exceed tracker.fine_max_points (no frame could be tracked)",
             [o] { return o->quality.min_points_tracked <= o->fine.max_points; });
  r->require("tracker.init_min_points must not exceed kMaxLevels (4) times tracker.depth_points_per_level (the map could never start)",
             [o] { return o->init_min_points <= kMaxLevels * o->depth_points.max_points_per_level; });
  r->require("tracker.max_robust_sigma must be 0 (no cap) or at least tracker.min_robust_sigma",
             [o] { return o->pose.max_robust_sigma == 0 || o->pose.max_robust_sigma >= o->pose.min_robust_sigma; });
}

}  // namespace

void MotionOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "velocity_damping", &velocity_damping, 0.0, 1.0, "",
          "fraction of the last inter-frame motion kept in the prediction");
  r->bind(s, "use_sbi_rotation", &use_sbi_rotation,
          "predict the rotation by aligning the previous and current small blurry images");
  r->bind(s, "retry_without_sbi", &retry_without_sbi,
          "a frame tracked poorly (quality below quality_good or a sudden drop) from the small blurry "
          "images' rotation is tracked again from the damped velocity alone; the better is kept");
}

void CoarseStageOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "coarse_max_points", &max_points, 0, 10000, "points",
          "points searched in the coarse stage at most");
  r->bind(s, "coarse_min_level", &min_level, 0, kMaxLevels - 1, "level",
          "coarse stage uses points whose search level is at least this");
  r->bind(s, "coarse_radius_px", &radius_px, 1, 100, "px", "coarse search radius at the search level");
  r->bind(s, "coarse_min_points", &min_points, 3, 10000, "points",
          "fewer coarse candidates than this: skip the coarse stage");
  r->bind(s, "coarse_min_motion_px", &min_motion_px, 0.0, 1000.0, "px",
          "coarse stage only when the visible points move at least this much (median) between "
          "the last pose and the start pose (0: always)");
  r->bind(s, "retry_without_coarse", &retry_without,
          "a frame tracked below quality_good after a coarse stage is tracked again from the "
          "prediction without it; the better of the two is kept");
  r->bind(s, "retry_quality_ratio", &retry_quality_ratio, 0.0, 1.0, "",
          "...also when its quality is below this fraction of the last tracked frame's (a "
          "sudden drop: the coarse stage pulled the pose off; 0: off)");
  r->bind(s, "retry_with_coarse", &retry_with,
          "a frame tracked poorly (by the two rules above) without a coarse stage, the predicted "
          "image motion being small, is tracked again from the prediction with it; the better of "
          "the two is kept");
}

void FineStageOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "fine_max_points", &max_points, 10, 100000, "points",
          "points searched in the fine stage at most (random subset beyond)");
  r->bind(s, "fine_radius_px", &radius_px, 1, 50, "px", "fine search radius at the search level");
}

void QualityOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "quality_good", &good, 0.0, 1.0, "", "found / searched for state tracking");
  r->bind(s, "quality_lost", &lost, 0.0, 1.0, "", "found / searched below this: lost");
  r->bind(s, "min_points_tracked", &min_points_tracked, 3, 100000, "points",
          "fewer points found: lost whatever the ratio");
  r->bind(s, "max_pose_sigma_m", &max_pose_sigma_m, 0.0, 100.0, "m",
          "lost when the pose's translation standard deviation (from the fit, worst "
          "direction) exceeds this");
  r->bind(s, "max_pose_sigma_deg", &max_pose_sigma_deg, 0.0, 180.0, "deg",
          "lost when the pose's rotation standard deviation (worst axis) exceeds this");
  r->bind(s, "good_step_m", &good_step_m, 0.0, 100.0, "m",
          "reported tracking only when 3 sigma of the frame-to-frame step error (pose "
          "sigma * 3 sqrt 2) stays within this; else dodgy (not mono; 0: no limit)");
  r->bind(s, "good_step_deg", &good_step_deg, 0.0, 180.0, "deg",
          "...and within this for the rotation (0: no limit)");
  r->bind(s, "unreliable_after_searches", &unreliable_after_searches, 1, 1000000, "frames",
          "a point searched this often and rarely found no longer counts in the quality");
  r->bind(s, "unreliable_found_ratio", &unreliable_found_ratio, 0.0, 1.0, "",
          "...rarely: found / searched below this");
}

void TrackerOptions::bind(OptionRegistry* r, const std::string& s) {
  motion.bind(r, s);
  motion_prior.bind(r, s);
  coarse.bind(r, s);
  fine.bind(r, s);
  projection.bind(r, s);
  search.bind(r, s);
  pose.bind(r, s);
  quality.bind(r, s);
  keyframes.bind(r, s);
  r->bind(s, "keyframes_while_dodgy", &keyframes_while_dodgy,
          "also add keyframes while tracking is dodgy, when the mode creates points from depth");
  keyframe_build.bind(r, s);
  depth_points.bind(r, s);
  r->bind(s, "init_min_points", &init_min_points, 3, 100000, "points",
          "keyframe 0 needs this many points from depth");
  r->bind(s, "relocalise_candidates", &relocalise_candidates, 1, 100, "keyframes",
          "most similar keyframes tried per frame when lost");
  r->bind(s, "relocalise_shortlist", &relocalise_shortlist, 2, 100000, "keyframes",
          "above this many keyframes a lost frame is compared only with this many: the nearest "
          "and the best by bag of words (depth modes)");
  r->bind(s, "relocalise_coast_frames", &relocalise_coast_frames, 0, 1000, "frames",
          "for this many frames after a loss also try the pose the last velocity carried the camera to "
          "(0: the last pose only)");
  r->bind(s, "relocalise_dead_reckoning", &relocalise_dead_reckoning,
          "while lost, follow the camera by aligning each frame's depth to a recent frame's and the nearest "
          "keyframes' surfaces from the motion prior's prediction (needs the motion prior); relocalisation and "
          "a new part start from that pose where depth held (else from the coast)");
  r->bind(s, "relocalise_reckoning_sigma_m", &relocalise_reckoning_sigma_m, 0.001, 100.0, "m",
          "dead reckoning: a direction of the pose counts as held by the surfaces when they fix it within this "
          "(1 sigma); elsewhere it follows the velocity");
  r->bind(s, "relocalise_reckoning_sigma_deg", &relocalise_reckoning_sigma_deg, 0.01, 180.0, "deg",
          "dead reckoning: the same for rotation");
  r->bind(s, "relocalise_last_pose_reach_m", &relocalise_last_pose_reach_m, 0.0, 1000.0, "m",
          "a pose relocalised from the last pose may be dodgy until the velocity at the loss has carried the "
          "camera this far from it; beyond, it must be good (0: always good)");
  r->bind(s, "relocalise_max_speed_m_s", &relocalise_max_speed_m_s, 0.0, 1000.0, "m/s",
          "a relocalised pose lies within this speed times the time since the last pose, plus 1 m, "
          "of the last pose; farther lookalike places are refused (0: anywhere)");
  r->bind(s, "new_part_after_failures", &new_part_after_failures, 0, 1000000, "relocalisations",
          "lost and this many relocalisations failed in a row (depth modes, adding keyframes): a new "
          "part of the map from the frame's depth, where the camera coasted to (0: never)");
  r->bind(s, "rejoin_every_frames", &rejoin_every_frames, 0, 1000000, "frames",
          "in a part started where the camera was lost, this many tracked frames with depth after the last "
          "round of tries, start another: the frames against the keyframes of the part it was lost in, one "
          "try a frame after its pose is out (0: never)");
  r->bind(s, "random_seed", &random_seed, 0, INT_MAX, "", "seed of the point subset selection");
  integrity.bind(r, s);
  occlusion.bind(r, s);
  photometric.bind(r, s);
  depth_align.bind(r, s);
  reloc_features.bind(r, s);
  local_map.bind(r, s);
  r->bind(s, "correction_rate_m_s", &correction_rate_m_s, 0.0, 100.0, "m/s",
          "the published pose takes in map corrections at most this fast (0: at once)");
  r->bind(s, "correction_rate_deg_s", &correction_rate_deg_s, 0.0, 3600.0, "deg/s",
          "...and rotations at most this fast (0: at once)");
  r->bind(s, "follow_map_corrections", &follow_map_corrections,
          "the tracker's pose moves with the keyframe nearest it when a map update moves that");
  bindRules(this, r);
}

}  // namespace rgbdslam
