#pragma once
// The tracker's replica of the mapper's map (docs/design.md, "Map protocol"), with one search
// slot per point (point_projection.h: the patch cache and per-frame search state).
//   addKeyframe / addProvisionalPoint: a keyframe the tracker created and its points from
//   depth, tracked against at once, before the mapper has seen them.
//   apply(update): a map version's content, which sync/map_follower.h has already judged in
//   order. A snapshot replaces the poses and points of acknowledged keyframes (points of
//   acknowledged keyframes absent from it were culled by the mapper); provisional points of
//   keyframes the mapper has not acknowledged stay. A delta updates the listed keyframes,
//   adds the new points, moves the moved ones (keeping their slots' patch caches) and
//   removes the listed ids. Entries that name keyframes the replica lacks are skipped.
// Memory: grows with the map: every keyframe's pyramid (0.41 MB at 640x480; the tracker
// frees the keyframe's metric depth and corners once its points are made) and small blurry
// image, and every point's slot.
// Threads: not thread-safe; the tracker's thread owns it.
#include <memory>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/map/map.h"
#include "rgbdslam/model/point_creation.h"
#include "rgbdslam/tracking/point_projection.h"

namespace rgbdslam {

class MapReplica {
 public:
  explicit MapReplica(const PinholeCamera& camera) : camera_(camera) {}

  Keyframe* addKeyframe(std::unique_ptr<Keyframe> keyframe) { return map_.addKeyframe(std::move(keyframe)); }
  // A point from depth created in keyframe 'keyframe_id' and its measurement there.
  void addProvisionalPoint(KeyframeId keyframe_id, const NewPoint& point);
  // Returns false when entries named keyframes the replica lacks (they were skipped).
  bool apply(const MapUpdate& update);
  void clear();

  const Map& map() const { return map_; }
  std::vector<PointSlot>& slots() { return slots_; }

 private:
  void addSlot(MapPoint* point);
  void removeSlot(PointId id);
  void removePoint(PointId id);

  PinholeCamera camera_;
  Map map_;
  std::unordered_set<KeyframeId> acked_;  // keyframes the mapper has acknowledged
  std::vector<PointSlot> slots_;
  std::unordered_map<PointId, size_t> slot_index_;
};

}  // namespace rgbdslam
