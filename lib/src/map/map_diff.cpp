#include "rgbdslam/map/map_diff.h"

#include <algorithm>

namespace rgbdslam {

MapUpdate MapDiffer::delta(const Map& map) {
  MapUpdate update;
  for (const auto& [id, kf] : map.keyframes()) {
    auto it = keyframes_.find(id);
    const bool moved =
        it == keyframes_.end() ||
        (kf->T_w_c.translation() - it->second.translation()).norm() > options_.keyframe_move_m ||
        kf->T_w_c.rotation().angularDistance(it->second.rotation()) > options_.keyframe_turn_rad;
    if (!moved) continue;
    update.keyframes.push_back({id, kf->T_w_c});
    keyframes_[id] = kf->T_w_c;
  }
  for (const auto& [id, point] : map.points()) {
    auto it = points_.find(id);
    if (it == points_.end()) {
      update.points.push_back(point.data());
      points_[id] = point.p_w;
    } else if ((point.p_w - it->second).norm() > options_.point_move_m) {
      update.moved_points.push_back({id, point.p_w});
      it->second = point.p_w;
    }
  }
  for (auto it = points_.begin(); it != points_.end();) {
    if (map.point(it->first)) {
      ++it;
      continue;
    }
    update.removed_points.push_back(it->first);
    it = points_.erase(it);
  }
  // Deterministic order (the map's point table is unordered).
  std::sort(update.points.begin(), update.points.end(),
            [](const MapPointData& a, const MapPointData& b) { return a.id < b.id; });
  std::sort(update.moved_points.begin(), update.moved_points.end(),
            [](const PointPosition& a, const PointPosition& b) { return a.id < b.id; });
  std::sort(update.removed_points.begin(), update.removed_points.end());
  return update;
}

MapUpdate MapDiffer::snapshot(const Map& map) {
  points_.clear();
  keyframes_.clear();
  MapUpdate update = delta(map);
  update.removed_points.clear();
  update.is_snapshot = true;
  return update;
}

}  // namespace rgbdslam
