#pragma once
// New map points from measured depth (paper III-B, III-C): at the FAST corners of every
// pyramid level that survive non-maximum suppression and have a valid depth reading, a
// point p_w = T_w_c * unproject(uv, d). Used for the initial map (keyframe 0) and, by the
// tracker, for the provisional points of each new keyframe. Corners close to a point the
// keyframe already measures are skipped, so a keyframe does not duplicate what it tracks.
// Ids: first_id + i, where the tracker passes provisionalPointId(keyframe_id, 0) (point_ids.h).
#include <vector>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/map/map.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

struct DepthPointOptions {
  int max_points_per_level = 300;     // strongest corners kept per level (by Shi-Tomasi score)
  double min_shi_tomasi = 30.0;       // weaker corners are not used: smallest eigenvalue of the mean structure tensor [(grey/px)^2]
  double min_separation_px = 8.0;     // from already-measured points and each other, level 0 [px]
  // A view with few strong corners (weakly textured walls: a corridor) also takes weaker
  // ones until the keyframe measures weak_until_points points (0: never); a richly textured
  // view keeps only the strong ones, which localise better. How weak: down to
  // weak_noise_ratio times the score the image's own noise gives (weakScoreFloors), but not
  // under weak_min_shi_tomasi. Why relative to the noise: a corner's worth is how far its
  // weakest gradient direction stands above the noise, and cameras differ in noise (the
  // renderer's level 0: sigma 1.6 grey levels, score 1.3; TUM fr3/teddy's: 0.5, 0.13).
  // Pure noise scores about 0.8x on average over the 7x7 window, and no window of 32000
  // reached 3x (test_corners). A richly textured or very noisy level 0 (an estimate of 3.9
  // grey levels or more) puts the floor at min_shi_tomasi: no weak corners then.
  // weak_min_shi_tomasi is for what the estimate does not see (rounding, shading, blur).
  // Measured against the fixed floor of 10 used before (batch, --deterministic; corridor
  // 900 frames, worlds 1-3: 180 / 192 / 187 keyframes at 13.5 / 114 / 19.2 mm ATE; now
  // 153 / 158 / 142 at 9.5 / 9.2 / 7.9 mm, the floor 5.4 at level 0 and 2 above it).
  // Where it costs: the office's plain walls (docs/open_work.md, 2026-11-26).
  double weak_min_shi_tomasi = 2.0;   // [(grey/px)^2]
  double weak_noise_ratio = 4.0;      // [-]
  int weak_until_points = 100;        // [points]
  int patch_border_px = 6;            // corners this close to the level's border are skipped [px]
  double dense_depth_fraction = 0.5;  // at least this fraction of pixels with depth: a missing 3x3 neighbour rejects a corner
  double depth_discontinuity = 0.05;  // max spread of the 3x3 window's depths relative to the centre's (edges are skipped)

  void bind(OptionRegistry* registry, const std::string& section);  // as depth_points_*
};

struct NewPoint {
  MapPoint point;
  Measurement measurement;  // its observation in the source keyframe (with depth)
};

// The weak pass's score floor per pyramid level (see DepthPointOptions), never above
// min_shi_tomasi: level 0's noise by imageNoiseSigma, halved per level.
std::vector<double> weakScoreFloors(const ImagePyramid& pyramid, const DepthPointOptions& options);

std::vector<NewPoint> createPointsFromDepth(const Keyframe& keyframe, const PinholeCamera& camera,
                                            const DepthPointOptions& options, PointId first_id);

}  // namespace rgbdslam
