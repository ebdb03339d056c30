#pragma once
// Between the map and the BundleAdjuster: a BaProblem for a window of free keyframes (all
// points they measure free; every other keyframe measuring those points fixed; keyframe 0
// always fixed), and the results written back (poses, points, outlier flags).
// Gauge: at least min_fixed_keyframes keyframes of each part of the map that takes part
// (Keyframe::part; parts share no measurement, mapper.h) are fixed (its oldest free ones are
// fixed to get there); fix_initial_points holds the points whose source is the keyframe that
// started a part fixed, keyframe 0's in a map of one part (2-D BA, where the cost does not
// see the scale).
// Determinism: keyframes, points and observations are in id order.
#include <set>
#include <utility>
#include <vector>

#include "rgbdslam/map/map.h"
#include "rgbdslam/mapping/bundle_adjuster.h"

namespace rgbdslam {

struct MapBaProblem {
  BaProblem problem;
  // Per observation: (keyframe id, point id), same order as problem.observations.
  std::vector<std::pair<KeyframeId, PointId>> observation_ids;
};

MapBaProblem buildBaProblem(const Map& map, const PinholeCamera& camera,
                            const std::set<KeyframeId>& free_keyframes, int min_fixed_keyframes,
                            bool fix_initial_points);

// Writes the free poses and points back into the map; adds their ids to the change sets.
// Returns how many poses and points it wrote.
int writeBackBa(const MapBaProblem& ba, Map* map, std::set<KeyframeId>* changed_keyframes,
                std::set<PointId>* changed_points);

// Applies the outlier flags: a 2-D outlier is added to *pending_2d_outliers (point id,
// keyframe id) for removal at culling, a 2-D inlier is taken out of it, and a depth outlier
// loses its depth reading in the keyframe's measurement (depth = 0). Returns the number of
// depth readings dropped.
int applyBaOutliers(const MapBaProblem& ba, const BaResult& result, Map* map,
                    std::set<std::pair<PointId, KeyframeId>>* pending_2d_outliers);

}  // namespace rgbdslam
