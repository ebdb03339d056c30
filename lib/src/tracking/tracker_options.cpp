#include <climits>

#include "rgbdslam/tracking/tracker.h"

namespace rgbdslam {
namespace {

// Options that only make sense together; a contradiction leaves nothing to track.
void bindRules(TrackerOptions* o, OptionRegistry* r) {
  r->requireBelow("tracker", "keyframe_min_depth_m", "keyframe_max_depth_m");
  r->require("tracker.quality_lost must not exceed tracker.quality_good",
             [o] { return o->quality_lost <= o->quality_good; });
  r->require("tracker.min_points_tracked must not exceed tracker.fine_max_points (no frame could be tracked)",
             [o] { return o->min_points_tracked <= o->fine_max_points; });
  r->require("tracker.init_min_points must not exceed kMaxLevels (4) times tracker.depth_points_per_level (the map could never start)",
             [o] { return o->init_min_points <= kMaxLevels * o->depth_points.max_points_per_level; });
  r->require("tracker.max_robust_sigma must be 0 (no cap) or at least tracker.min_robust_sigma",
             [o] { return o->max_robust_sigma == 0 || o->max_robust_sigma >= o->min_robust_sigma; });
}

}  // namespace

void TrackerOptions::bind(OptionRegistry* r) {
  const std::string s = "tracker";
  r->bind(s, "velocity_damping", &velocity_damping, 0.0, 1.0, "",
          "fraction of the last inter-frame motion kept in the prediction");
  r->bind(s, "use_sbi_rotation", &use_sbi_rotation,
          "predict the rotation by aligning the previous and current small blurry images");
  r->bind(s, "coarse_max_points", &coarse_max_points, 0, 10000, "points",
          "points searched in the coarse stage at most");
  r->bind(s, "coarse_min_level", &coarse_min_level, 0, kMaxLevels - 1, "level",
          "coarse stage uses points whose search level is at least this");
  r->bind(s, "coarse_radius_px", &coarse_radius_px, 1, 100, "px",
          "coarse search radius at the search level");
  r->bind(s, "coarse_min_points", &coarse_min_points, 3, 10000, "points",
          "fewer coarse candidates than this: skip the coarse stage");
  r->bind(s, "coarse_min_motion_px", &coarse_min_motion_px, 0.0, 1000.0, "px",
          "coarse stage only when the visible points move at least this much (median) between "
          "the last pose and the start pose (0: always)");
  r->bind(s, "retry_without_coarse", &retry_without_coarse,
          "a frame tracked below quality_good after a coarse stage is tracked again from the "
          "prediction without it; the better of the two is kept");
  r->bind(s, "retry_quality_ratio", &retry_quality_ratio, 0.0, 1.0, "",
          "...also when its quality is below this fraction of the last tracked frame's (a "
          "sudden drop: the coarse stage pulled the pose off; 0: off)");
  r->bind(s, "fine_max_points", &fine_max_points, 10, 100000, "points",
          "points searched in the fine stage at most (random subset beyond)");
  r->bind(s, "fine_radius_px", &fine_radius_px, 1, 50, "px",
          "fine search radius at the search level");
  r->bind(s, "max_zmssd_per_pixel", &max_zmssd_per_pixel, 1, 65025, "grey^2",
          "patch match accepted when ZMSSD / 64 is below this");
  r->bind(s, "max_zmssd_energy_ratio", &max_zmssd_energy_ratio, 0.0, 2.0, "",
          "...or when ZMSSD is below this times the template's zero-mean energy (0: off)");
  r->bind(s, "max_zmssd_flat_ratio", &max_zmssd_flat_ratio, 0.0, 2.0, "",
          "...and in any case only when ZMSSD is below this times the template's zero-mean "
          "energy, which a textureless image patch exceeds (0: off)");
  r->bind(s, "search_dense_fallback", &search_dense_fallback,
          "no FAST corner in the search radius matches: test every pixel in it");
  r->bind(s, "image_margin_px", &image_margin_px, 0, 100, "px",
          "projected points closer than this to the image border are not searched");
  r->bind(s, "patch_cache_tolerance", &patch_cache_tolerance, 0.0, 1.0, "",
          "re-warp a cached patch when an entry of its warp matrix changed by more");
  r->bind(s, "gauss_newton_iterations", &gauss_newton_iterations, 1, 100, "iterations",
          "pose Gauss-Newton iterations per stage");
  r->bind(s, "tukey_c", &tukey_c, 1.0, 20.0, "sigmas", "Tukey biweight cut-off");
  r->bind(s, "min_robust_sigma", &min_robust_sigma, 0.01, 10.0, "sigmas",
          "floor of the robust scale estimated from the median error");
  r->bind(s, "max_robust_sigma", &max_robust_sigma, 0.0, 10.0, "sigmas",
          "cap of the robust scale after the free iterations, so many wrong matches cannot "
          "widen the cut-off (0: no cap)");
  r->bind(s, "free_scale_iterations", &free_scale_iterations, 0, 100, "iterations",
          "pose iterations per stage with the median scale uncapped, before the cap applies");
  r->bind(s, "use_depth_in_pose", &use_depth_in_pose,
          "add depth residuals of tracked corners with a depth reading to the pose (never in "
          "mono, where depth serves only the first frame)");
  r->bind(s, "depth_sigma_coefficient", &depth_sigma_coefficient, 1e-5, 1.0, "1/m",
          "a in sigma_d = a d^2 for the depth residuals");
  r->bind(s, "random_seed", &random_seed, 0, INT_MAX, "", "seed of the point subset selection");
  r->bind(s, "quality_good", &quality_good, 0.0, 1.0, "", "found / searched for state tracking");
  r->bind(s, "quality_lost", &quality_lost, 0.0, 1.0, "", "found / searched below this: lost");
  r->bind(s, "min_points_tracked", &min_points_tracked, 3, 100000, "points",
          "fewer points found: lost whatever the ratio");
  r->bind(s, "max_pose_sigma_m", &max_pose_sigma_m, 0.0, 100.0, "m",
          "lost when the pose's translation standard deviation (from the fit, worst "
          "direction) exceeds this");
  r->bind(s, "max_pose_sigma_deg", &max_pose_sigma_deg, 0.0, 180.0, "deg",
          "lost when the pose's rotation standard deviation (worst axis) exceeds this");
  r->bind(s, "unreliable_after_searches", &unreliable_after_searches, 1, 1000000, "frames",
          "a point searched this often and rarely found no longer counts in the quality");
  r->bind(s, "unreliable_found_ratio", &unreliable_found_ratio, 0.0, 1.0, "",
          "...rarely: found / searched below this");
  r->bind(s, "init_min_points", &init_min_points, 3, 100000, "points",
          "keyframe 0 needs this many points from depth");
  r->bind(s, "relocalise_candidates", &relocalise_candidates, 1, 100, "keyframes",
          "most similar keyframes tried per frame when lost");
  r->bind(s, "min_frames_between_keyframes", &min_frames_between_keyframes, 0, 100000, "frames",
          "frames since the last keyframe before another");
  r->bind(s, "keyframe_distance_ratio", &keyframe_distance_ratio, 0.0, 10.0, "",
          "new keyframe when every keyframe is farther than this times the median depth...");
  r->bind(s, "keyframe_angle_deg", &keyframe_angle_deg, 0.0, 180.0, "deg",
          "...or rotated by more than this");
  r->bind(s, "keyframe_few_points", &keyframe_few_points, 0, 100000, "points",
          "fewer points found, and the mode makes points from depth: a keyframe is due "
          "whatever the distance (0: off)");
  r->bind(s, "keyframe_few_points_min_frames", &keyframe_few_points_min_frames, 0, 100000,
          "frames", "...after at least this many frames since the last keyframe");
  r->bind(s, "keyframe_few_points_mono", &keyframe_few_points_mono, 0, 100000, "points",
          "mono (no points from depth): fewer points found gives a keyframe whatever the "
          "distance (0: off)");
  r->bind(s, "keyframe_few_points_mono_min_frames", &keyframe_few_points_mono_min_frames, 0,
          100000, "frames", "...after at least this many frames since the last keyframe");
  r->bind(s, "keyframes_while_dodgy", &keyframes_while_dodgy,
          "also add keyframes while tracking is dodgy, when the mode creates points from depth");
  r->bind(s, "keyframe_min_depth_m", &keyframe_build.min_depth_m, 0.0, 100.0, "m",
          "depth readings nearer than this are invalid");
  r->bind(s, "keyframe_max_depth_m", &keyframe_build.max_depth_m, 0.0, 100.0, "m",
          "depth readings farther than this are invalid");
  r->bind(s, "depth_points_per_level", &depth_points.max_points_per_level, 0, 100000, "points",
          "new points from depth per keyframe and pyramid level at most");
  r->bind(s, "depth_points_min_shi_tomasi", &depth_points.min_shi_tomasi, 0.0, 1e6, "(grey/px)^2",
          "weaker corners give no point");
  r->bind(s, "depth_points_weak_min_shi_tomasi", &depth_points.weak_min_shi_tomasi, 0.0, 1e6,
          "(grey/px)^2", "a keyframe with few points also takes corners down to this score...");
  r->bind(s, "depth_points_weak_until_points", &depth_points.weak_until_points, 0, 100000,
          "points", "...until it measures this many points (0: never)");
  r->bind(s, "depth_points_min_separation_px", &depth_points.min_separation_px, 0.0, 100.0, "px",
          "new points keep this distance from measured points and each other");
  r->bind(s, "depth_points_discontinuity", &depth_points.depth_discontinuity, 0.0, 1.0, "fraction",
          "a spread of the 3x3 window's depths above this (relative to the corner's) rejects the corner");
  r->bind(s, "depth_points_dense_fraction", &depth_points.dense_depth_fraction, 0.0, 1.0, "fraction",
          "with at least this fraction of pixels valid, a missing 3x3 neighbour rejects a corner");
  bindRules(this, r);
}

}  // namespace rgbdslam
