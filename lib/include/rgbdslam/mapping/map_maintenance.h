#pragma once
// Map clean-up after bundle adjustment (PTAM's HandleBadPoints): drop measurements judged
// 2-D outliers, and points that are mostly outliers or have too few good measurements.
// Points seen only in their source keyframe are kept while that keyframe is recent (the
// following keyframes may still find them).
// cullDivergedPoints: points that bundle adjustment has carried off: behind their source
// keyframe's camera, or farther from it than max_depth_m. Why: a point measured without
// depth along nearly parallel rays (a far wall beyond the sensor's range) has almost no
// parallax, so bundle adjustment can move it along its ray at no cost; on the full corridor
// through the split suite such points reached 20-1000 km. Sent on, a point beyond the map
// protocol's world bound (10 km) made the tracker refuse every later map version (each
// snapshot held it too), so it tracked a stale map for the rest of the run. Far points are
// not culled sooner: their direction still fixes the rotation (with a limit of 40 m the
// mono corridor, 900 frames, lost its scale: ATE 5.4 m instead of 15-17 mm).
#include <set>
#include <utility>
#include <vector>

#include "rgbdslam/map/map.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

struct CullOptions {
  int min_good_measurements = 2;      // fewer: the point goes (unless source-only and recent)
  double max_outlier_fraction = 0.5;  // more of a point's measurements flagged: the point goes
  int keep_source_only_keyframes = 3;  // points seen only in their source keyframe survive
                                       // while it is among this many newest keyframes
  // A tenth of the protocol's world bound: a point this far is at infinity for any camera
  // of ours (its direction is all it gives), and no published position comes near the bound.
  double max_depth_m = 1000.0;        // [m] in the source keyframe

  void bind(OptionRegistry* registry, const std::string& section);
};

struct CullResult {
  std::vector<PointId> removed_points;  // in id order
  int removed_measurements = 0;         // single measurements removed (points kept)
};

// 'pending_2d_outliers' (point id, keyframe id) is consumed.
CullResult cullMap(Map* map, std::set<std::pair<PointId, KeyframeId>>* pending_2d_outliers,
                   const CullOptions& options);

// Of 'candidates' (the points a bundle adjustment moved), removes those behind their source
// keyframe's camera or deeper in it than max_depth_m (see above); returns their ids. Run
// at once after every adjustment, so that no published map holds them.
std::vector<PointId> cullDivergedPoints(Map* map, const std::vector<PointId>& candidates, double max_depth_m);

// Point ids of the map in increasing order.
std::vector<PointId> sortedPointIds(const Map& map);

}  // namespace rgbdslam
