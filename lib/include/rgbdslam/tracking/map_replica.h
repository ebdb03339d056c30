#pragma once
// The tracker's replica of the mapper's map (docs/design.md, "Map protocol"), with a search
// slot (point_projection.h: the patch cache and per-frame search state) for each point of a
// hot keyframe.
//   addKeyframe / addProvisionalPoint: a keyframe the tracker created and its points from
//   depth, tracked against at once, before the mapper has seen them.
//   apply(update): a map version's content, which sync/map_follower.h has already judged in
//   order. A snapshot replaces the poses and points of acknowledged keyframes (points of
//   acknowledged keyframes absent from it were culled by the mapper); provisional points of
//   keyframes the mapper has not acknowledged stay. A delta updates the listed keyframes,
//   adds the new points (a known point sent in full again was re-described from another
//   keyframe: its slot is made anew), moves the moved ones (keeping their slots' patch
//   caches) and removes the listed ids. Keyframes the mapper culled (acknowledged ones
//   other than keyframe 0; any other named is kept and reported as unknown) (listed in a delta, and
//   all of them in a snapshot) go last, with any point still described by them; a keyframe
//   merely absent from a snapshot stays (a mapper that lost its journal has not had it again yet). Entries that name keyframes the replica lacks are skipped.
//   With tracker_node.defer_cold_map_work (on by default), rgbd-tracker applies with
//   defer_cold: the work on cold keyframes' points (most of a
//   snapshot's or a join's) and the store's holes for culled keyframes wait, and
//   applyDeferred() does them in steps between frames (docs/design.md, "Map protocol").
//   updateLocalMap(wanted): the local map. The keyframes nearest the camera keep their
//   pyramid ('hot'); the others are 'cold': their level-0 image is kept as JPEG (encoded
//   once), the pyramid freed, and their points lose their slots (the points stay, with their
//   depth records) until the camera comes back and the keyframe is thawed (JPEG decoded,
//   pyramid rebuilt, slots made anew in point id order). The tracker counts a cold
//   keyframe's points in view from the points themselves (point_projection.h, inView),
//   found by the replica's index of each keyframe's points (describedBy), and only for the
//   keyframes whose points' bounding sphere may be in view (boundsOf, sphereMayBeInView).
//   Points on storage: with a store and LocalMapOptions::store_points, a keyframe going cold
//   puts its points in the store too (Kind::kPoints: what the tracker learnt of each, its
//   statistics and depth record), and memory keeps what the map says of them (id, position,
//   patch: StoredPoints), so that a version moving such a point, sending it again with the
//   same patch, removing it or leaving it out of a snapshot changes memory's lists only, and
//   the count in view (forEachPosition) is the same. Its keyframe's points are read back
//   when it is thawed, when a version puts a new point in it or takes one to another
//   keyframe, or re-describes a point of it as it is culled; cold again, they go back at the
//   end of the call (apply; with defer_cold 2 a step of applyDeferred instead, the newest 4
//   staying while work is held back), written only if their bytes changed. Why: over a 10-minute flight the
//   tracker's map grew from 7.6 to 42 thousand points, nearly all of cold keyframes
//   (docs/open_work.md, sessions 40 and 41).
// Memory: every keyframe's pose and small blurry image (compact: its image only, 4.8 kB at
// 640x480; the relocaliser restores the gradients and support it aligns with); every point
// in memory (about 150 bytes with its hash-map entry; no measurements:
// Keyframe::releaseMappingData), but the cold keyframes' points on storage, 49 bytes each in
// memory (with a store); the slots
// of the hot keyframes' points only (about 250 bytes each with their index; over
// a long flight most points are cold); the pyramids of the hot keyframes (0.41 MB each at
// 640x480; the tracker frees a keyframe's metric depth, corners and measurements once its
// points are made) and the JPEG of the cold ones (30-60 kB at quality 90 on textured
// 640x480 images), unless a keyframe store (keyframe_store.h) holds those: then a
// keyframe's JPEG is written there when it first goes cold and read back to thaw it.
// Threads: not thread-safe; the tracker's thread owns it.
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/map/map.h"
#include "rgbdslam/model/point_creation.h"
#include "rgbdslam/tracking/keyframe_store.h"
#include "rgbdslam/tracking/point_projection.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

// The local map: how many keyframes stay hot, and how much work one frame may do on it.
struct LocalMapOptions {
  // Hot keyframes, at most this many: the sources of the points in view (most points first),
  // then the nearest to the camera (0: all stay hot). 40 (16 MB of pyramids at 640x480)
  // since keyframe culling leaves 1.2-1.7 per metre, so 40 span 25-35 m of a corridor;
  // measured against 80 (2026-11-25): full corridor
  // --deterministic 20.7 mm (33.1), through the suite tracker peak 109 MB (126), ATE 36.2 mm
  // (35.8), every frame posed; the room, teddy, office and the first 720 frames of the
  // flight keep fewer keyframes than that and are unchanged.
  int keyframes = 40;
  int changes_per_frame = 2;   // keyframes thawed per frame at most; as many frozen, plus
                               // as many as were thawed (updateLocalMap)
  int relocalise_thaws = 8;    // keyframes thawed around each relocalisation candidate
  int jpeg_quality = 90;       // cold keyframes' images [1, 100]
  // Where cold keyframes' images and extras go (keyframe_store.h); empty: they stay in memory.
  std::string store_dir = "/var/tmp";
  bool store_points = true;  // cold keyframes' points go to the store too (with a store_dir)
  void bind(OptionRegistry* registry, const std::string& section);  // as local_map_*
};

struct LocalMapChange {
  int thawed = 0, frozen = 0;
  int left_cold = 0;  // wanted but over the thaw budget: thawed on a later call
};

class MapReplica {
 public:
  explicit MapReplica(const PinholeCamera& camera) : camera_(camera) {}
  // Cold keyframes' JPEGs go to 'store' (owned by the caller, outliving the replica;
  // nullptr: they stay in memory), and with 'points' their points too. Set before the first
  // keyframe.
  void setStore(KeyframeStore* store, bool points = true) {
    store_ = store;
    store_points_ = points;
  }

  Keyframe* addKeyframe(std::unique_ptr<Keyframe> keyframe);
  // A point from depth created in its source keyframe. Its measurement there is not kept:
  // the replica holds no measurements (Keyframe::releaseMappingData), since the tracker
  // reads none once a keyframe's points are made (they go to the mapper in KeyframeData).
  void addProvisionalPoint(const NewPoint& point);
  // A keyframe and a point of a loaded map (map_file.h): the mapper holds them already, so
  // the keyframe counts as acknowledged. Keyframes first (a point's slot needs its source).
  Keyframe* addAcknowledgedKeyframe(std::unique_ptr<Keyframe> keyframe);
  void addAcknowledgedPoint(const MapPoint& point);
  // Returns false when entries named keyframes the replica lacks (they were skipped).
  // defer_cold: the work on points without a slot (a cold keyframe's, not searched: put,
  // re-described, removed, or absent from a snapshot) is held back for applyDeferred(), so
  // that the tracking thread can spread it over the time between frames (issue 10, item 6),
  // and so are the holes punched in the keyframe store for culled keyframes. Every
  // keyframe's pose and part, every move, the points with slots, the points re-described
  // from a keyframe culled now and the culls themselves are applied at once. Any work held
  // back is done first, whole: map versions go in in order.
  bool apply(const MapUpdate& update, bool defer_cold = false);
  // Does up to about max_entries of the work held back (a point each; a keyframe looked
  // through for a snapshot's absent points, one plus its points; a hole in the store, 100),
  // in the order apply() would have. Returns 0 when none is left. The replica is consistent
  // in between: a keyframe thawed meanwhile gets its slots, and the work held back then
  // updates them as for any hot keyframe.
  size_t applyDeferred(size_t max_entries);
  bool hasDeferred() const;
  void clear();
  // Thaws the cold keyframes of 'wanted' (nearest first; at most max_thaws) and freezes hot
  // keyframes not in it, oldest first, while more than max_hot are hot (at most max_freezes
  // plus as many as were thawed; max_hot 0: every hot keyframe not wanted goes).
  LocalMapChange updateLocalMap(const std::vector<KeyframeId>& wanted, int max_thaws,
                                int max_freezes, int jpeg_quality, int max_hot = 0);
  int hotKeyframes() const;

  // The map's keyframes and the points in memory (the points on storage are not in it).
  const Map& map() const { return map_; }
  size_t numPoints() const { return map_.numPoints() + stored_points_; }  // in memory and on storage
  size_t storedPoints() const { return stored_points_; }
  int64_t pointsLost() const { return points_lost_; }  // on storage that failed (store's errors)
  // f(p_w) for each point the keyframe describes, in memory or on storage, in no order.
  template <typename F>
  void forEachPosition(KeyframeId id, F&& f) const;
  std::vector<PointSlot>& slots() { return slots_; }

  // The points a keyframe describes (is the source of), in no order; kept with every change
  // to the points, so that a keyframe's points are found without a pass over the whole map
  // (36 500 points at the end of the 10-minute flight; such passes, once for every pose tried,
  // were a third of its tracking time).
  const std::vector<PointId>& describedBy(KeyframeId id) const;
  // A sphere holding every point the keyframe describes: exact when it last went cold,
  // grown (never shrunk) as its points are added or moved. Radius < 0: it describes none.
  struct Bounds {
    Vec3 centre = Vec3::Zero();
    double radius = -1.0;  // [m]
  };
  Bounds boundsOf(KeyframeId id) const;

 private:
  MapPoint* putPoint(const MapPoint& point);  // map_.addPoint, with the index and bounds
  void putPointAndSlot(const MapPointData& point);  // an update's point: a new slot if its patch changed
  size_t removeAbsentPoints(KeyframeId id);          // a snapshot's culled points of a keyframe
  void unindex(KeyframeId source, PointId id);  // no longer described by 'source'
  void growBounds(KeyframeId id, const Vec3& p_w);
  void resetBounds(KeyframeId id);  // exact again, from its points
  void addSlot(MapPoint* point);
  void removeSlot(PointId id);
  void removePoint(PointId id);
  void removeKeyframe(KeyframeId id, bool store_later = false);  // store_later: KeyframeStore::removeLater
  bool thaw(Keyframe* keyframe);  // the pyramid only: addSlotsOf() then makes the slots
  void addSlotsOf(const std::unordered_set<KeyframeId>& keyframes);
  void freeze(Keyframe* keyframe, int jpeg_quality);
  // Points on storage. storePoints: a cold keyframe's points to the store (false: none, or
  // the store refused them: they stay). loadPoints: back into memory, if on storage.
  // findStored: where a point on storage is listed. storeLoaded: the keyframes read back (or
  // given points while cold) go back, but for the newest few while work is held back
  // (applyDeferred goes on with them).
  struct StoredPoints;
  struct StoredAt {
    KeyframeId keyframe;
    StoredPoints* points;
    size_t index;
  };
  bool storePoints(KeyframeId id);
  void loadPoints(KeyframeId id);
  StoredPoints takeStored(KeyframeId id);
  std::optional<StoredAt> findStored(PointId id);
  void removeStored(const StoredAt& at);
  bool moveStored(PointId id, const Vec3& p_w);  // false: not on storage
  void moveStored(const StoredAt& at, const Vec3& p_w);
  void noteLoaded(KeyframeId id);
  void storeLoaded(size_t max_puts);
  std::vector<KeyframeId> coldLoaded() const;
  void forgetLoaded(KeyframeId id);

  PinholeCamera camera_;
  KeyframeStore* store_ = nullptr;
  Map map_;
  KeyframeId acked_below_ = 0;  // the mapper has acknowledged every keyframe below this id
  std::vector<PointSlot> slots_;
  std::unordered_map<PointId, size_t> slot_index_;
  std::unordered_map<KeyframeId, std::vector<PointId>> described_;
  std::unordered_map<KeyframeId, Bounds> bounds_;
  bool store_points_ = true;
  // A cold keyframe's points on storage: what the map says of them, in memory (49 bytes a
  // point), in id order; their statistics and depth records are in the store.
  struct StoredPoints {
    std::vector<PointId> ids;
    std::vector<Vec3> positions;
    std::vector<std::array<double, 2>> uvs;  // the patch: source pixel and level
    std::vector<int8_t> levels;
    std::vector<KeyframeId> blocks;  // the id blocks of its points (keyframeOfPoint), each once
  };
  std::unordered_map<KeyframeId, StoredPoints> stored_;
  std::unordered_map<KeyframeId, std::vector<KeyframeId>> stored_blocks_;  // block -> keyframes in stored_
  // Read back (or given points while cold) and not yet put back (storeLoaded), oldest first,
  // with the size and checksum of the bytes read (none read: write them).
  struct Loaded {
    KeyframeId id = -1;
    bool read = false;
    uint32_t checksum = 0;
    size_t size = 0;
  };
  std::vector<Loaded> loaded_;
  size_t stored_points_ = 0;
  int64_t points_lost_ = 0;
  size_t io_entries_ = 0;  // work of the store's reads and writes, in applyDeferred()'s entries
  // Work held back by apply(defer_cold), each list done from its 'next' on.
  struct Deferred {
    std::vector<PointId> kept;       // a snapshot's point ids, sorted
    std::vector<KeyframeId> gone_in;  // keyframes whose points absent from 'kept' go
    std::vector<MapPointData> points;
    std::vector<PointId> removed_points;
    size_t next_gone = 0, next_point = 0, next_removed_point = 0;
    bool empty() const;
  };
  Deferred deferred_;
};

template <typename F>
void MapReplica::forEachPosition(KeyframeId id, F&& f) const {
  if (const auto it = stored_.find(id); it != stored_.end()) {
    for (const Vec3& p_w : it->second.positions) f(p_w);
    return;
  }
  for (PointId pid : describedBy(id)) f(map_.point(pid)->p_w);
}

}  // namespace rgbdslam
