#include "rgbdslam/mapping/map_maintenance.h"

#include <algorithm>
#include <map>

namespace rgbdslam {

std::vector<PointId> sortedPointIds(const Map& map) {
  std::vector<PointId> ids;
  ids.reserve(map.numPoints());
  for (const auto& [id, point] : map.points()) ids.push_back(id);
  std::sort(ids.begin(), ids.end());
  return ids;
}

namespace {

// The newest 'count' keyframes.
std::set<KeyframeId> newestKeyframes(const Map& map, int count) {
  std::set<KeyframeId> newest;
  for (auto it = map.keyframes().rbegin(); it != map.keyframes().rend(); ++it) {
    if (static_cast<int>(newest.size()) >= count) break;
    newest.insert(it->first);
  }
  return newest;
}

}  // namespace

void CullOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "min_good_measurements", &min_good_measurements, 1, 100, "measurements",
          "points with fewer good measurements are culled");
  r->bind(s, "keep_source_only_keyframes", &keep_source_only_keyframes, 0, 1000, "keyframes",
          "source-only points survive while their keyframe is this recent");
  r->bind(s, "max_outlier_fraction", &max_outlier_fraction, 0.0, 1.0, "-",
          "points with a larger share of outlier measurements are culled");
  r->bind(s, "max_point_depth_m", &max_depth_m, 1.0, 10000.0, "m",
          "points carried farther than this from their source keyframe's camera (or behind it) by bundle adjustment are culled");
}

CullResult cullMap(Map* map, std::set<std::pair<PointId, KeyframeId>>* pending_2d_outliers,
                   const CullOptions& options) {
  CullResult result;
  const std::set<KeyframeId> recent_keyframes = newestKeyframes(*map, options.keep_source_only_keyframes);
  std::set<PointId> removed;
  auto remove = [&](PointId pid) {
    map->removePoint(pid);
    removed.insert(pid);
  };
  // 1. Points that are mostly outliers, or whose patch measurement (source) is one.
  std::map<PointId, int> flagged;
  for (const auto& [pid, kf] : *pending_2d_outliers) ++flagged[pid];
  for (const auto& [pid, count] : flagged) {
    const MapPoint* point = map->point(pid);
    if (!point) continue;
    const size_t total = map->observers(pid).size();
    const bool source_bad = pending_2d_outliers->count({pid, point->source_keyframe}) > 0;
    if (source_bad || count > options.max_outlier_fraction * static_cast<double>(total)) remove(pid);
  }
  // 2. The remaining outlier measurements.
  for (const auto& [pid, kf] : *pending_2d_outliers) {
    if (removed.count(pid) || !map->point(pid)) continue;
    const Keyframe* keyframe = map->keyframe(kf);
    if (!keyframe || !keyframe->measurements().count(pid)) continue;
    map->removeMeasurement(kf, pid);
    ++result.removed_measurements;
  }
  pending_2d_outliers->clear();
  // 3. Points with too few good measurements.
  for (PointId pid : sortedPointIds(*map)) {
    const std::vector<KeyframeId> seen = map->observers(pid);
    if (static_cast<int>(seen.size()) >= options.min_good_measurements) continue;
    const MapPoint* point = map->point(pid);
    const bool recent_source_only = seen.size() == 1 && seen[0] == point->source_keyframe &&
                                    recent_keyframes.count(point->source_keyframe) > 0;
    if (!recent_source_only) remove(pid);
  }
  result.removed_points.assign(removed.begin(), removed.end());
  return result;
}

std::vector<PointId> cullDivergedPoints(Map* map, const std::vector<PointId>& candidates, double max_depth_m) {
  std::vector<PointId> removed;
  for (PointId pid : candidates) {
    const MapPoint* point = map->point(pid);
    const Keyframe* source = point ? map->keyframe(point->source_keyframe) : nullptr;
    if (!source) continue;
    const double depth = (source->T_c_w() * point->p_w).z();
    if (depth > 0.0 && depth <= max_depth_m) continue;
    map->removePoint(pid);
    removed.push_back(pid);
  }
  return removed;
}

}  // namespace rgbdslam
