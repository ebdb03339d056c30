#include "rgbdslam/tracking/map_replica.h"

namespace rgbdslam {

void MapReplica::addProvisionalPoint(KeyframeId keyframe_id, const NewPoint& point) {
  addSlot(map_.addPoint(point.point));
  map_.addMeasurement(keyframe_id, point.measurement);
}

void MapReplica::clear() {
  map_ = Map();
  acked_.clear();
  slots_.clear();
  slot_index_.clear();
}

// Adds the point's slot, or re-initialises it (dropping its patch cache) if it exists.
void MapReplica::addSlot(MapPoint* point) {
  const auto it = slot_index_.find(point->id);
  if (it != slot_index_.end()) {
    if (!initSlot(map_, camera_, point, &slots_[it->second])) removeSlot(point->id);
    return;
  }
  PointSlot slot;
  if (!initSlot(map_, camera_, point, &slot)) return;
  slot_index_[point->id] = slots_.size();
  slots_.push_back(slot);
}

void MapReplica::removeSlot(PointId id) {
  const auto it = slot_index_.find(id);
  if (it == slot_index_.end()) return;
  const size_t index = it->second;
  slot_index_.erase(it);
  if (index + 1 != slots_.size()) {
    slots_[index] = slots_.back();
    slot_index_[slots_[index].point->id] = index;
  }
  slots_.pop_back();
}

void MapReplica::removePoint(PointId id) {
  removeSlot(id);
  map_.removePoint(id);
}

bool MapReplica::apply(const MapUpdate& update) {
  bool unknown = false;
  for (KeyframeId id : update.acked_keyframes) acked_.insert(id);
  for (const KeyframePose& pose : update.keyframes) {
    Keyframe* keyframe = map_.keyframe(pose.id);
    if (keyframe) keyframe->T_w_c = pose.T_w_c;
    else unknown = true;
  }
  if (update.is_snapshot) {
    std::unordered_set<PointId> kept;
    for (const MapPointData& p : update.points) kept.insert(p.id);
    std::vector<PointId> gone;
    for (const auto& [id, point] : map_.points()) {
      if (!kept.count(id) && acked_.count(point.source_keyframe)) gone.push_back(id);
    }
    for (PointId id : gone) removePoint(id);
  }
  for (const MapPointData& p : update.points) {
    if (!map_.hasKeyframe(p.source_keyframe)) {
      unknown = true;
      continue;
    }
    const MapPoint point(p);
    const MapPoint* before = map_.point(p.id);
    const bool same_patch = before && before->source_keyframe == p.source_keyframe &&
                            before->source_level == p.level && before->source_uv == p.uv;
    MapPoint* stored = map_.addPoint(point);
    if (same_patch && slot_index_.count(p.id)) continue;  // slot and patch cache stay valid
    addSlot(stored);
  }
  for (const PointPosition& moved : update.moved_points) {
    MapPoint* point = map_.point(moved.id);
    if (point) point->p_w = moved.p_w;  // same patch: slot and patch cache stay valid
    else unknown = true;
  }
  for (PointId id : update.removed_points) removePoint(id);
  return !unknown;
}

}  // namespace rgbdslam
