#pragma once
// Map clean-up after bundle adjustment (PTAM's HandleBadPoints): drop measurements judged
// 2-D outliers, and points that are mostly outliers or have too few good measurements.
// Points seen only in their source keyframe are kept while that keyframe is recent (the
// following keyframes may still find them).
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

  void bind(OptionRegistry* registry, const std::string& section);
};

struct CullResult {
  std::vector<PointId> removed_points;  // in id order
  int removed_measurements = 0;         // single measurements removed (points kept)
};

// 'pending_2d_outliers' (point id, keyframe id) is consumed.
CullResult cullMap(Map* map, std::set<std::pair<PointId, KeyframeId>>* pending_2d_outliers,
                   const CullOptions& options);

// Point ids of the map in increasing order.
std::vector<PointId> sortedPointIds(const Map& map);

}  // namespace rgbdslam
