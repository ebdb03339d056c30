#include "rgbdslam/map/map_diff.h"

#include <algorithm>

namespace rgbdslam {

void MapChanges::merge(const MapChanges& later) {
  for (KeyframeId id : later.removed_keyframes) keyframes.erase(id);
  keyframes.insert(later.keyframes.begin(), later.keyframes.end());
  removed_keyframes.insert(later.removed_keyframes.begin(), later.removed_keyframes.end());
  for (PointId id : later.removed_points) points.erase(id);
  for (PointId id : later.points) removed_points.erase(id);
  points.insert(later.points.begin(), later.points.end());
  removed_points.insert(later.removed_points.begin(), later.removed_points.end());
}

// A move this many times its threshold (a loop closure's correction) is never held back: the
// tracker would track up to a refinement period against a map corrected only in part.
constexpr double kHoldAtMost = 10.0;

MapUpdate MapDiffer::delta(const Map& map, const MapChanges& changes, MapChanges* held_back) {
  MapUpdate update;
  for (KeyframeId id : changes.keyframes) {  // std::set: id order
    const Keyframe* kf = map.keyframe(id);
    if (!kf) continue;
    auto it = keyframes_.find(id);
    const bool renamed = it != keyframes_.end() && it->second.part != kf->part;  // its part joined another
    if (held_back && it != keyframes_.end() && !renamed &&
        (kf->T_w_c.translation() - it->second.T_w_c.translation()).norm() <= kHoldAtMost * options_.keyframe_move_m &&
        kf->T_w_c.rotation().angularDistance(it->second.T_w_c.rotation()) <= kHoldAtMost * options_.keyframe_turn_rad) {
      held_back->keyframes.insert(id);
      continue;
    }
    const bool moved =
        it == keyframes_.end() || renamed ||
        (kf->T_w_c.translation() - it->second.T_w_c.translation()).norm() > options_.keyframe_move_m ||
        kf->T_w_c.rotation().angularDistance(it->second.T_w_c.rotation()) > options_.keyframe_turn_rad;
    if (!moved) continue;
    update.keyframes.push_back({id, kf->T_w_c, kf->part});
    keyframes_[id] = PublishedKeyframe{kf->T_w_c, kf->part};
  }
  for (PointId id : changes.points) {
    const MapPoint* point = map.point(id);
    if (!point) continue;  // added and removed again since: in neither list
    auto it = points_.find(id);
    if (held_back && it != points_.end() && it->second.source == point->source_keyframe &&
        (point->p_w - it->second.p_w).norm() <= kHoldAtMost * options_.point_move_m) {
      held_back->points.insert(id);
    } else if (it == points_.end() || it->second.source != point->source_keyframe) {
      update.points.push_back(point->data());  // new, or re-described (a new patch)
      points_[id] = {point->p_w, point->source_keyframe};
    } else if ((point->p_w - it->second.p_w).norm() > options_.point_move_m) {
      update.moved_points.push_back({id, point->p_w});
      it->second.p_w = point->p_w;
    }
  }
  // Every removal, published or not: the tracker may hold a point that was never published
  // (its own provisional points of a keyframe).
  for (PointId id : changes.removed_points) {
    points_.erase(id);
    update.removed_points.push_back(id);
  }
  for (KeyframeId id : changes.removed_keyframes) {
    keyframes_.erase(id);
    update.removed_keyframes.push_back(id);
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
  // Every keyframe culled so far: a tracker that missed the delta naming one still holds it,
  // and a keyframe merely absent (lost with a mapper's journal, to be sent again) must stay.
  update.removed_keyframes.assign(map.removedKeyframes().begin(), map.removedKeyframes().end());
  update.is_snapshot = true;
  return update;
}

}  // namespace rgbdslam
