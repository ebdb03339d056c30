#include "rgbdslam/map/map_diff.h"

#include <algorithm>

namespace rgbdslam {

void MapChanges::merge(const MapChanges& later) {
  keyframes.insert(later.keyframes.begin(), later.keyframes.end());
  for (PointId id : later.removed_points) points.erase(id);
  for (PointId id : later.points) removed_points.erase(id);
  points.insert(later.points.begin(), later.points.end());
  removed_points.insert(later.removed_points.begin(), later.removed_points.end());
}

MapUpdate MapDiffer::delta(const Map& map, const MapChanges& changes) {
  MapUpdate update;
  for (KeyframeId id : changes.keyframes) {  // std::set: id order
    const Keyframe* kf = map.keyframe(id);
    if (!kf) continue;
    auto it = keyframes_.find(id);
    const bool moved =
        it == keyframes_.end() ||
        (kf->T_w_c.translation() - it->second.translation()).norm() > options_.keyframe_move_m ||
        kf->T_w_c.rotation().angularDistance(it->second.rotation()) > options_.keyframe_turn_rad;
    if (!moved) continue;
    update.keyframes.push_back({id, kf->T_w_c});
    keyframes_[id] = kf->T_w_c;
  }
  for (PointId id : changes.points) {
    const MapPoint* point = map.point(id);
    if (!point) continue;  // added and removed again since: in neither list
    auto it = points_.find(id);
    if (it == points_.end()) {
      update.points.push_back(point->data());
      points_[id] = point->p_w;
    } else if ((point->p_w - it->second).norm() > options_.point_move_m) {
      update.moved_points.push_back({id, point->p_w});
      it->second = point->p_w;
    }
  }
  // Every removal, published or not: the tracker may hold a point that was never published
  // (its own provisional points of a keyframe).
  for (PointId id : changes.removed_points) {
    points_.erase(id);
    update.removed_points.push_back(id);
  }
  return update;
}

MapUpdate MapDiffer::snapshot(const Map& map) {
  points_.clear();
  keyframes_.clear();
  MapChanges everything;
  for (const auto& [id, kf] : map.keyframes()) everything.keyframes.insert(id);
  for (const auto& [id, point] : map.points()) everything.points.insert(id);
  MapUpdate update = delta(map, everything);
  update.is_snapshot = true;
  return update;
}

}  // namespace rgbdslam
