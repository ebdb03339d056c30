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
  // ones, down to weak_min_shi_tomasi, until the keyframe measures weak_until_points points
  // (0: never); a richly textured view keeps only the strong ones, which localise better.
  double weak_min_shi_tomasi = 10.0;  // [(grey/px)^2]
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

std::vector<NewPoint> createPointsFromDepth(const Keyframe& keyframe, const PinholeCamera& camera,
                                            const DepthPointOptions& options, PointId first_id);

}  // namespace rgbdslam
