#include "rgbdslam/tracking/map_replica.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <map>
#include <optional>
#include <utility>

#include "rgbdslam/image/codec.h"
#include "rgbdslam/image/pyramid.h"

namespace rgbdslam {
namespace {
// Added to every keyframe's bounding radius: the culling that relies on it must never miss a
// point to rounding.
constexpr double kBoundsSlackM = 1e-6;
// What a hole punched in the keyframe store's file (KeyframeStore::removeLater) counts for in
// applyDeferred()'s entries, against one per point: 0.19 ms median, 0.62 ms p99 on the
// development machine's ext4, against 1-2 us for a point. Counted as one entry, a step of
// 200 took up to 24 ms on the 10-minute flight, where the mapper culls 35-126 keyframes at
// once after a join.
constexpr size_t kStoreReleaseEntries = 100;
// Keyframes read back from the store for work held back (applyDeferred) that stay in memory
// between its steps while work is left: the work goes keyframe by keyframe, and a keyframe
// put back after each step of 200 entries and read again for the next would cost a write
// and a read a step.
constexpr size_t kLoadedKeptForDeferred = 4;
// Keyframes read back and cold again put back to the store per step of applyDeferred (a write
// each, if their bytes changed).
constexpr size_t kPutBackPerStep = 2;

// A point on storage (KeyframeStore::Kind::kPoints): what the tracker learnt of it, its
// statistics and depth record. What the map says of it (position, patch) stays in memory
// (MapReplica::StoredPoints), so that an update moving it or sending it again needs neither
// a read nor a write. Read back by the process that wrote it (the store's file goes with
// the process), so the layout is this build's.
struct StoredPoint {
  int64_t id;
  int32_t times_projected, times_found;
  int32_t checks, seen_through, missing;
  float read_max_m;
};
static_assert(sizeof(MapPoint) == 96, "a field added to MapPoint must be kept on storage too (StoredPoint)");
constexpr char kPointsMagic[4] = {'R', 'P', 'T', '2'};

std::vector<uint8_t> encodePoints(const Map& map, const std::vector<PointId>& ids) {
  std::vector<uint8_t> out(sizeof(kPointsMagic) + ids.size() * sizeof(StoredPoint));
  std::memcpy(out.data(), kPointsMagic, sizeof(kPointsMagic));
  uint8_t* at = out.data() + sizeof(kPointsMagic);
  for (PointId id : ids) {
    const MapPoint& p = *map.point(id);
    const DepthRecord& r = p.depth_record;
    const StoredPoint s{p.id, p.times_projected, p.times_found, r.checks, r.seen_through, r.missing, r.read_max_m};
    std::memcpy(at, &s, sizeof(s));
    at += sizeof(s);
  }
  return out;
}

std::optional<std::vector<StoredPoint>> decodePoints(const std::vector<uint8_t>& bytes) {
  if (bytes.size() < sizeof(kPointsMagic) || std::memcmp(bytes.data(), kPointsMagic, sizeof(kPointsMagic)) != 0 ||
      (bytes.size() - sizeof(kPointsMagic)) % sizeof(StoredPoint) != 0) {
    return std::nullopt;
  }
  std::vector<StoredPoint> points((bytes.size() - sizeof(kPointsMagic)) / sizeof(StoredPoint));
  if (!points.empty()) std::memcpy(points.data(), bytes.data() + sizeof(kPointsMagic), points.size() * sizeof(StoredPoint));
  return points;
}
}  // namespace

void LocalMapOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "local_map_keyframes", &keyframes, 0, 1000000, "keyframes",
          "keyframes that keep their image pyramid: the nearest to the camera; the others keep "
          "a JPEG and their points are not searched until the camera comes back (0: all)");
  r->bind(s, "local_map_changes_per_frame", &changes_per_frame, 1, 1000, "keyframes",
          "keyframes thawed (JPEG decoded, pyramid built: ~2 ms each) per frame at most; as many are "
          "frozen, plus as many as were thawed (relocalisation thaws more)");
  r->bind(s, "local_map_relocalise_thaws", &relocalise_thaws, 0, 1000, "keyframes",
          "keyframes thawed around each relocalisation candidate");
  r->bind(s, "cold_keyframe_jpeg_quality", &jpeg_quality, 1, 100, "",
          "JPEG quality of the images of keyframes outside the local map");
  r->bindPath(s, "local_map_store_dir", &store_dir,
              "directory on the flight computer's storage (not a RAM file system) where the images and "
              "extras of keyframes outside the local map are kept, in an unnamed file the system removes "
              "at exit; empty: they stay in memory");
  r->bind(s, "local_map_store_points", &store_points,
          "the points of keyframes outside the local map go to the store too (with local_map_store_dir), "
          "read back when the camera comes back or a map update changes their patch; memory keeps 49 bytes a point");
}

LocalMapChange MapReplica::updateLocalMap(const std::vector<KeyframeId>& wanted, int max_thaws,
                                          int max_freezes, int jpeg_quality, int max_hot) {
  LocalMapChange change;
  std::unordered_set<KeyframeId> thawed;
  for (KeyframeId id : wanted) {
    Keyframe* keyframe = map_.keyframe(id);
    if (!keyframe || !keyframe->cold()) continue;
    if (change.thawed >= max_thaws) {
      ++change.left_cold;
    } else if (thaw(keyframe)) {
      ++change.thawed;
      thawed.insert(id);
    }
  }
  addSlotsOf(thawed);
  if (max_freezes <= 0) return change;
  // At least as many frozen as thawed: a lost tracker thaws around every relocalisation
  // candidate (8 each, several candidates a frame), and with only max_freezes going back the
  // hot set grew to 117 of a window of 40 on the flight (+35 MB of pyramids).
  // Hot keyframes not wanted stay while the hot set is within max_hot: a keyframe that
  // leaves the wanted list for a frame or two and comes back is not frozen and thawed again
  // (each thaw rebuilds its pyramid from the JPEG, so its points' patches lose a little).
  const int freezes = std::min(max_freezes + change.thawed, hotKeyframes() - max_hot);
  if (freezes > 0) {
    const std::unordered_set<KeyframeId> keep(wanted.begin(), wanted.end());
    for (const auto& [id, keyframe] : map_.keyframes()) {  // oldest first
      if (keyframe->cold() || keep.count(id)) continue;
      freeze(keyframe.get(), jpeg_quality);
      if (++change.frozen >= freezes) break;
    }
  }
  return change;
}

int MapReplica::hotKeyframes() const {
  int hot = 0;
  for (const auto& [id, keyframe] : map_.keyframes()) hot += keyframe->cold() ? 0 : 1;
  return hot;
}

// The JPEG is made once; with a store it lives there, and the memory keeps none.
void MapReplica::freeze(Keyframe* keyframe, int jpeg_quality) {
  const bool stored = store_ && store_->has(keyframe->id, KeyframeStore::Kind::kImage);
  if (!stored && keyframe->cold_grey.empty()) keyframe->cold_grey = encodeJpeg(keyframe->grey(), jpeg_quality);
  if (!stored && store_ && store_->put(keyframe->id, KeyframeStore::Kind::kImage, keyframe->cold_grey)) {
    std::vector<uint8_t>().swap(keyframe->cold_grey);
  }
  ImagePyramid().levels.swap(keyframe->pyramid.levels);
  resetBounds(keyframe->id);
  // Its points' slots go too (their search state and patch caches were for the pyramid just
  // freed): thawing makes them anew. The points stay, with their depth records. Found from
  // the index, removed in slot order: a removal moves the last slot into the gap, so the
  // order of removal decides the slots' order, and with it the search order.
  std::vector<std::pair<size_t, PointId>> described;
  for (PointId id : describedBy(keyframe->id)) {
    if (const auto it = slot_index_.find(id); it != slot_index_.end()) described.emplace_back(it->second, id);
  }
  std::sort(described.begin(), described.end());
  for (const auto& [index, id] : described) removeSlot(id);
  storePoints(keyframe->id);
}

bool MapReplica::thaw(Keyframe* keyframe) {
  std::vector<uint8_t> stored;
  if (keyframe->cold_grey.empty() && store_) {
    Expected<std::vector<uint8_t>> bytes = store_->get(keyframe->id, KeyframeStore::Kind::kImage);
    if (!bytes) return false;  // the storage failed (counted by the store): stays cold
    stored = std::move(*bytes);
  }
  const std::vector<uint8_t>& jpeg = stored.empty() ? keyframe->cold_grey : stored;
  const Expected<cv::Mat> grey = decodeImage(jpeg.data(), jpeg.size(), 1, camera_.width, camera_.height);
  if (!grey) return false;  // cannot happen with bytes this process encoded (CRC-checked); stays cold
  buildPyramid(*grey, kMaxLevels, &keyframe->pyramid);
  loadPoints(keyframe->id);  // the entry stays until the keyframe is frozen again, or culled
  return true;
}

// The ids sorted: a point on storage is found by binary search (findStored).
bool MapReplica::storePoints(KeyframeId id) {
  if (!store_ || !store_points_ || stored_.count(id)) {
    forgetLoaded(id);
    return false;
  }
  const auto loaded = std::find_if(loaded_.begin(), loaded_.end(), [id](const Loaded& e) { return e.id == id; });
  const Loaded read = loaded == loaded_.end() ? Loaded{id} : *loaded;
  std::vector<PointId> ids = describedBy(id);
  if (ids.empty()) {  // none left since it was read back
    forgetLoaded(id);
    store_->removeLater(id, KeyframeStore::Kind::kPoints);
    return false;
  }
  std::sort(ids.begin(), ids.end());
  const std::vector<uint8_t> bytes = encodePoints(map_, ids);
  const bool unchanged = read.read && read.size == bytes.size() && read.checksum == KeyframeStore::checksum(bytes) &&
                         store_->has(id, KeyframeStore::Kind::kPoints);
  // A replaced entry's hole is punched later (applyDeferred: 0.2 ms each), not on this call.
  if (!unchanged && !store_->put(id, KeyframeStore::Kind::kPoints, bytes, /*release_later=*/true)) {
    noteLoaded(id);  // the store full: they stay, and go once it has room (storeLoaded)
    return false;
  }
  forgetLoaded(id);
  StoredPoints stored;
  stored.positions.reserve(ids.size());
  stored.uvs.reserve(ids.size());
  stored.levels.reserve(ids.size());
  for (PointId pid : ids) {
    const MapPoint& point = *map_.point(pid);
    stored.positions.push_back(point.p_w);
    stored.uvs.push_back({point.source_uv.x(), point.source_uv.y()});
    stored.levels.push_back(static_cast<int8_t>(point.source_level));
    const KeyframeId block = keyframeOfPoint(pid);
    if (std::find(stored.blocks.begin(), stored.blocks.end(), block) == stored.blocks.end()) {
      stored.blocks.push_back(block);
    }
    map_.removePoint(pid);  // no slot: the keyframe is cold
  }
  stored.ids = std::move(ids);
  for (KeyframeId block : stored.blocks) stored_blocks_[block].push_back(id);
  stored_points_ += stored.ids.size();
  io_entries_ += stored.ids.size() + kStoreReleaseEntries;
  stored_.emplace(id, std::move(stored));
  described_.erase(id);
  return true;
}

// The points in the store's bytes that are still the keyframe's (removals since are not
// written), at the positions memory holds. The entry stays: put back unchanged, it is not
// written again.
void MapReplica::loadPoints(KeyframeId id) {
  if (!stored_.count(id)) return;
  const StoredPoints stored = takeStored(id);
  io_entries_ += stored.ids.size() + kStoreReleaseEntries;
  const Expected<std::vector<uint8_t>> bytes = store_->get(id, KeyframeStore::Kind::kPoints);
  std::optional<std::vector<StoredPoint>> points;
  if (bytes) points = decodePoints(*bytes);
  std::vector<PointId>& described = described_[id];
  described.reserve(stored.ids.size());
  if (points) {
    for (const StoredPoint& s : *points) {
      const auto at = std::lower_bound(stored.ids.begin(), stored.ids.end(), s.id);
      if (at == stored.ids.end() || *at != s.id) continue;  // removed while on storage
      const auto i = static_cast<size_t>(at - stored.ids.begin());
      MapPoint point;
      point.id = s.id;
      point.p_w = stored.positions[i];
      point.source_keyframe = id;
      point.source_level = stored.levels[i];
      point.source_uv = Eigen::Vector2d(stored.uvs[i][0], stored.uvs[i][1]);
      point.times_projected = s.times_projected;
      point.times_found = s.times_found;
      point.depth_record.checks = s.checks;
      point.depth_record.seen_through = s.seen_through;
      point.depth_record.missing = s.missing;
      point.depth_record.read_max_m = s.read_max_m;
      map_.addPoint(point);
      described.push_back(point.id);
    }
  }
  if (described.size() != stored.ids.size()) {
    // The storage failed (counted by the store): the keyframe goes on without these points
    // until a snapshot sends them again. Cannot happen otherwise: the bytes are CRC-checked.
    points_lost_ += static_cast<int64_t>(stored.ids.size() - described.size());
    store_->removeLater(id, KeyframeStore::Kind::kPoints);  // (a failed read removed it already)
  }
  if (described.empty()) described_.erase(id);
  Loaded entry{id};
  if (bytes && points) entry = Loaded{id, true, KeyframeStore::checksum(*bytes), bytes->size()};
  forgetLoaded(id);
  loaded_.push_back(entry);
}

// Memory's list of a keyframe's points on storage, taken out of the index (the store's
// entry is the caller's); empty if it has none there.
MapReplica::StoredPoints MapReplica::takeStored(KeyframeId id) {
  const auto it = stored_.find(id);
  if (it == stored_.end()) return {};
  StoredPoints stored = std::move(it->second);
  stored_.erase(it);
  for (KeyframeId block : stored.blocks) {
    const auto holders = stored_blocks_.find(block);
    holders->second.erase(std::find(holders->second.begin(), holders->second.end(), id));
    if (holders->second.empty()) stored_blocks_.erase(holders);
  }
  stored_points_ -= stored.ids.size();
  return stored;
}

std::optional<MapReplica::StoredAt> MapReplica::findStored(PointId id) {
  const auto holders = stored_blocks_.find(keyframeOfPoint(id));
  if (holders == stored_blocks_.end()) return std::nullopt;
  for (KeyframeId holder : holders->second) {
    StoredPoints& stored = stored_.at(holder);
    const auto at = std::lower_bound(stored.ids.begin(), stored.ids.end(), id);
    if (at != stored.ids.end() && *at == id) {
      return StoredAt{holder, &stored, static_cast<size_t>(at - stored.ids.begin())};
    }
  }
  return std::nullopt;
}

void MapReplica::removeStored(const StoredAt& at) {
  StoredPoints& p = *at.points;
  const auto i = static_cast<std::ptrdiff_t>(at.index);
  p.ids.erase(p.ids.begin() + i);
  p.positions.erase(p.positions.begin() + i);
  p.uvs.erase(p.uvs.begin() + i);
  p.levels.erase(p.levels.begin() + i);
  --stored_points_;
  if (!at.points->ids.empty()) return;
  takeStored(at.keyframe);
  store_->removeLater(at.keyframe, KeyframeStore::Kind::kPoints);
}

bool MapReplica::moveStored(PointId id, const Vec3& p_w) {
  if (stored_.empty()) return false;
  const std::optional<StoredAt> at = findStored(id);
  if (!at) return false;
  moveStored(*at, p_w);
  return true;
}

void MapReplica::moveStored(const StoredAt& at, const Vec3& p_w) {
  at.points->positions[at.index] = p_w;
  growBounds(at.keyframe, p_w);
}

// Newest last; an entry there keeps what was read.
void MapReplica::noteLoaded(KeyframeId id) {
  const auto it = std::find_if(loaded_.begin(), loaded_.end(), [id](const Loaded& e) { return e.id == id; });
  Loaded entry{id};
  if (it != loaded_.end()) {
    entry = *it;
    loaded_.erase(it);
  }
  loaded_.push_back(entry);
}

void MapReplica::forgetLoaded(KeyframeId id) {
  loaded_.erase(std::remove_if(loaded_.begin(), loaded_.end(), [id](const Loaded& e) { return e.id == id; }),
                loaded_.end());
}

// The cold keyframes read back (or given points while cold) go to the store, oldest first
// and at most max_puts of them, but for the newest few while work is held back
// (kLoadedKeptForDeferred), and none while the store is full. Hot ones are remembered until
// they are frozen (a keyframe thawed and frozen again unsearched, as relocalisation does, is
// not written again); culled ones are forgotten.
void MapReplica::storeLoaded(size_t max_puts) {
  loaded_.erase(std::remove_if(loaded_.begin(), loaded_.end(), [&](const Loaded& e) { return !map_.hasKeyframe(e.id); }),
                loaded_.end());
  if (max_puts == 0 || !store_ || store_->full()) return;
  const std::vector<KeyframeId> cold = coldLoaded();
  const size_t keep = deferred_.empty() ? 0 : kLoadedKeptForDeferred;
  for (size_t i = 0, puts = 0; i + keep < cold.size() && puts < max_puts && !store_->full(); ++i, ++puts) {
    storePoints(cold[i]);  // (none left: forgotten; the store full: kept)
  }
}

std::vector<KeyframeId> MapReplica::coldLoaded() const {
  std::vector<KeyframeId> cold;
  for (const Loaded& e : loaded_) {
    const Keyframe* keyframe = map_.keyframe(e.id);
    if (keyframe && keyframe->cold()) cold.push_back(e.id);
  }
  return cold;
}

// Slots for the points the keyframes describe (from the index), in point id order (the
// search order follows the slots').
void MapReplica::addSlotsOf(const std::unordered_set<KeyframeId>& keyframes) {
  if (keyframes.empty()) return;
  std::vector<PointId> described;
  for (KeyframeId id : keyframes) {
    const std::vector<PointId>& points = describedBy(id);
    described.insert(described.end(), points.begin(), points.end());
  }
  std::sort(described.begin(), described.end());
  for (PointId id : described) addSlot(map_.point(id));
}

Keyframe* MapReplica::addKeyframe(std::unique_ptr<Keyframe> keyframe) {
  compactSmallBlurryImage(&keyframe->sbi);
  return map_.addKeyframe(std::move(keyframe));
}

void MapReplica::addProvisionalPoint(const NewPoint& point) { addSlot(putPoint(point.point)); }

Keyframe* MapReplica::addAcknowledgedKeyframe(std::unique_ptr<Keyframe> keyframe) {
  acked_below_ = std::max(acked_below_, keyframe->id + 1);
  return addKeyframe(std::move(keyframe));
}

void MapReplica::addAcknowledgedPoint(const MapPoint& point) { addSlot(putPoint(point)); }

const std::vector<PointId>& MapReplica::describedBy(KeyframeId id) const {
  static const std::vector<PointId> kNone;
  const auto it = described_.find(id);
  return it == described_.end() ? kNone : it->second;
}

MapReplica::Bounds MapReplica::boundsOf(KeyframeId id) const {
  const auto it = bounds_.find(id);
  return it == bounds_.end() ? Bounds{} : it->second;
}

// A keyframe's points are all in memory or all on storage: a point put in a keyframe on
// storage, or taken from one (re-described), reads its points back first.
MapPoint* MapReplica::putPoint(const MapPoint& point) {
  loadPoints(point.source_keyframe);
  if (!stored_.empty() && !map_.point(point.id)) {
    if (const std::optional<StoredAt> at = findStored(point.id)) loadPoints(at->keyframe);
  }
  if (store_ && store_points_) {
    const Keyframe* source = map_.keyframe(point.source_keyframe);
    if (source && source->cold()) noteLoaded(point.source_keyframe);  // to the store with the rest
  }
  const MapPoint* before = map_.point(point.id);
  if (!before || before->source_keyframe != point.source_keyframe) {
    if (before) unindex(before->source_keyframe, point.id);
    described_[point.source_keyframe].push_back(point.id);
  }
  MapPoint* stored = map_.addPoint(point);
  growBounds(stored->source_keyframe, stored->p_w);
  return stored;
}

void MapReplica::unindex(KeyframeId source, PointId id) {
  const auto entry = described_.find(source);
  if (entry == described_.end()) return;
  std::vector<PointId>& described = entry->second;
  const auto it = std::find(described.begin(), described.end(), id);
  if (it == described.end()) return;
  *it = described.back();
  described.pop_back();
}

// The smallest sphere holding the old one and p_w.
void MapReplica::growBounds(KeyframeId id, const Vec3& p_w) {
  Bounds& bounds = bounds_[id];
  if (bounds.radius < 0.0) {
    bounds.centre = p_w;
    bounds.radius = kBoundsSlackM;
    return;
  }
  const double d = (p_w - bounds.centre).norm();
  if (d <= bounds.radius) return;
  bounds.centre += (0.5 * (d - bounds.radius) / d) * (p_w - bounds.centre);
  bounds.radius = 0.5 * (d + bounds.radius) + kBoundsSlackM;
}

void MapReplica::resetBounds(KeyframeId id) {
  bounds_.erase(id);
  const std::vector<PointId>& points = describedBy(id);
  if (points.empty()) return;
  Vec3 centroid = Vec3::Zero();
  for (PointId pid : points) centroid += map_.point(pid)->p_w;
  centroid /= static_cast<double>(points.size());
  double radius = 0.0;
  for (PointId pid : points) radius = std::max(radius, (map_.point(pid)->p_w - centroid).norm());
  bounds_[id] = Bounds{centroid, radius + kBoundsSlackM};
}

void MapReplica::clear() {
  if (store_) store_->clear();
  map_ = Map();
  acked_below_ = 0;
  slots_.clear();
  slot_index_.clear();
  described_.clear();
  bounds_.clear();
  deferred_ = Deferred{};
  stored_.clear();
  stored_blocks_.clear();
  loaded_.clear();
  stored_points_ = 0;
}

// Adds the point's slot, or re-initialises it (dropping its patch cache) if it exists. A
// point whose source keyframe is cold has none (thaw() makes it).
void MapReplica::addSlot(MapPoint* point) {
  const Keyframe* source = map_.keyframe(point->source_keyframe);
  if (source && source->cold()) {
    removeSlot(point->id);
    return;
  }
  const auto it = slot_index_.find(point->id);
  if (it != slot_index_.end()) {
    if (!initSlot(map_, camera_, point, &slots_[it->second])) removeSlot(point->id);
    return;
  }
  PointSlot slot;
  if (!initSlot(map_, camera_, point, &slot)) return;
  slot_index_[point->id] = slots_.size();
  slots_.push_back(std::move(slot));
}

void MapReplica::removeSlot(PointId id) {
  const auto it = slot_index_.find(id);
  if (it == slot_index_.end()) return;
  const size_t index = it->second;
  slot_index_.erase(it);
  if (index + 1 != slots_.size()) {
    slots_[index] = std::move(slots_.back());
    slot_index_[slots_[index].point->id] = index;
  }
  slots_.pop_back();
}

void MapReplica::removePoint(PointId id) {
  if (!stored_.empty() && !map_.point(id)) {
    if (const std::optional<StoredAt> at = findStored(id)) removeStored(*at);  // no read: memory lists its points
    return;
  }
  removeSlot(id);
  if (const MapPoint* point = map_.point(id)) {
    unindex(point->source_keyframe, id);
  }
  map_.removePoint(id);
}

bool MapReplica::apply(const MapUpdate& update, bool defer_cold) {
  applyDeferred(SIZE_MAX);  // versions in order
  bool unknown = false;
  acked_below_ = std::max(acked_below_, update.acked_below);
  // A point re-described from a keyframe on storage culled now keeps its statistics and depth
  // record (below): that keyframe's points are read back first. Other culled keyframes' are
  // not read (removeKeyframe).
  if (!stored_.empty() && !update.removed_keyframes.empty()) {
    const std::unordered_set<KeyframeId> culled(update.removed_keyframes.begin(), update.removed_keyframes.end());
    for (const MapPointData& p : update.points) {
      if (map_.point(p.id)) continue;
      const std::optional<StoredAt> at = findStored(p.id);
      if (at && culled.count(at->keyframe)) loadPoints(at->keyframe);
    }
  }
  std::map<KeyframeId, KeyframeId> renamed;  // parts the mapper joined to others
  for (const KeyframePose& pose : update.keyframes) {
    Keyframe* keyframe = map_.keyframe(pose.id);
    if (!keyframe) {
      unknown = true;
      continue;
    }
    keyframe->T_w_c = pose.T_w_c;
    // The keyframe that started a part, in another now: the loop closer joined the part to
    // that one. The tracker's keyframes of it not yet in a map version follow.
    if (pose.id == keyframe->part && pose.part != keyframe->part) renamed[keyframe->part] = pose.part;
    keyframe->part = pose.part;
  }
  for (const auto& [id, keyframe] : map_.keyframes()) {
    const auto it = renamed.find(keyframe->part);
    if (it != renamed.end()) keyframe->part = it->second;
  }
  // Work on points without a slot (a cold keyframe's: not searched) can wait (defer_cold).
  const auto slotless = [&](PointId id) { return defer_cold && !slot_index_.count(id); };
  if (update.is_snapshot) {
    // Points of acknowledged keyframes absent from it were culled: looked for keyframe by
    // keyframe (the index), after the snapshot's points (equivalent: none of those goes).
    deferred_.kept.clear();
    for (const MapPointData& p : update.points) deferred_.kept.push_back(p.id);
    std::sort(deferred_.kept.begin(), deferred_.kept.end());
    for (const auto& [id, keyframe] : map_.keyframes()) {
      if (id >= acked_below_) continue;
      if (defer_cold && keyframe->cold()) {
        deferred_.gone_in.push_back(id);
      } else {
        removeAbsentPoints(id);
      }
    }
  }
  // A point re-described from a keyframe culled now is put now: the cull below would take
  // it (and its depth record) with the keyframe.
  const std::unordered_set<KeyframeId> culled(update.removed_keyframes.begin(), update.removed_keyframes.end());
  const auto culled_source = [&](PointId id) {
    const MapPoint* before = map_.point(id);
    return before && culled.count(before->source_keyframe) > 0;
  };
  for (const MapPointData& p : update.points) {
    const Keyframe* source = map_.keyframe(p.source_keyframe);
    if (!source) {
      unknown = true;
    } else if (source->cold() && slotless(p.id) && !culled_source(p.id)) {
      deferred_.points.push_back(p);
    } else {
      putPointAndSlot(p);
    }
  }
  // Moves go in at once, cold or not: telling them apart costs as much as moving them (the
  // positions of points on storage are in memory).
  for (const PointPosition& moved : update.moved_points) {
    if (!moveStored(moved.id, moved.p_w)) {
      if (MapPoint* point = map_.point(moved.id)) {
        point->p_w = moved.p_w;  // same patch: slot and patch cache stay valid
        growBounds(point->source_keyframe, point->p_w);
      } else {
        unknown = true;
      }
    }
  }
  for (PointId id : update.removed_points) {
    if (slotless(id)) {
      deferred_.removed_points.push_back(id);
    } else {
      removePoint(id);
    }
  }

  // Culled keyframes go at once (the tracker's parts, anchor and bag of words follow the
  // keyframes), their store entries' bytes later.
  for (KeyframeId id : update.removed_keyframes) {
    // The mapper culls only keyframes it has integrated, never keyframe 0: a message naming
    // another is refused for it (this keyframe would never come back to the replica).
    if (id == 0 || id >= acked_below_) {
      unknown = unknown || map_.hasKeyframe(id);
    } else {
      removeKeyframe(id, /*store_later=*/defer_cold);
    }
  }
  storeLoaded(defer_cold ? 0 : SIZE_MAX);  // held back: applyDeferred puts them back, a few a step
  return !unknown;
}

bool MapReplica::Deferred::empty() const {
  return gone_in.size() == next_gone && points.size() == next_point && removed_points.size() == next_removed_point;
}

// In the order apply() would have taken them: a snapshot's culled points, the points, the
// removed points; then the keyframe store's holes. Reading points back from the store and
// writing them count too (io_entries_).
size_t MapReplica::applyDeferred(size_t max_entries) {
  Deferred& d = deferred_;
  size_t done = 0;
  const size_t io_before = io_entries_;
  const auto more = [&] { return done + (io_entries_ - io_before) < max_entries; };
  for (; more() && d.next_gone < d.gone_in.size(); ++d.next_gone) {
    done += removeAbsentPoints(d.gone_in[d.next_gone]);
  }
  for (; more() && d.next_point < d.points.size(); ++d.next_point, ++done) {
    const MapPointData& p = d.points[d.next_point];
    if (map_.hasKeyframe(p.source_keyframe)) {
      putPointAndSlot(p);
    } else {
      removePoint(p.id);  // its new source culled since (a whole apply puts it, then culls it)
    }
  }
  for (; more() && d.next_removed_point < d.removed_points.size(); ++d.next_removed_point, ++done) {
    removePoint(d.removed_points[d.next_removed_point]);
  }
  storeLoaded(kPutBackPerStep);
  done += io_entries_ - io_before;
  if (d.empty()) d = Deferred{};  // its memory too
  if (store_ && done < max_entries) store_->releaseQueued((max_entries - done) / kStoreReleaseEntries + 1);
  return hasDeferred() ? 1 : 0;
}

// Work held back, holes to punch in the store, or keyframes read back to put back (while the
// store has room).
bool MapReplica::hasDeferred() const {
  if (!deferred_.empty() || (store_ && store_->queued() > 0)) return true;
  // (no list made: rgbd-tracker asks at every turn of its loop)
  return store_ && !store_->full() && std::any_of(loaded_.begin(), loaded_.end(), [this](const Loaded& e) {
           const Keyframe* keyframe = map_.keyframe(e.id);
           return keyframe && keyframe->cold();
         });
}

void MapReplica::putPointAndSlot(const MapPointData& p) {
  if (!stored_.empty() && !map_.point(p.id)) {
    // On storage with the same patch: only its position changes (Map::addPoint keeps the
    // statistics), in memory.
    const std::optional<StoredAt> at = findStored(p.id);
    if (at && at->keyframe == p.source_keyframe && at->points->levels[at->index] == p.level &&
        at->points->uvs[at->index][0] == p.uv.x() && at->points->uvs[at->index][1] == p.uv.y()) {
      moveStored(*at, p.p_w);
      return;
    }
  }
  const MapPoint* before = map_.point(p.id);
  const bool same_patch = before && before->source_keyframe == p.source_keyframe && before->source_level == p.level &&
                          before->source_uv == p.uv;
  MapPoint* stored = putPoint(MapPoint(p));
  if (same_patch && slot_index_.count(p.id)) return;  // slot and patch cache stay valid
  addSlot(stored);
}

// A snapshot's points of keyframe 'id' absent from it (deferred_.kept), in slot order (as in
// freeze()). Returns how many points were looked at.
size_t MapReplica::removeAbsentPoints(KeyframeId id) {
  if (const auto it = stored_.find(id); it != stored_.end()) {  // in memory's list, without a read
    const size_t looked_at = it->second.ids.size() + 1;
    const std::vector<PointId> ids = it->second.ids;
    for (PointId pid : ids) {
      if (!std::binary_search(deferred_.kept.begin(), deferred_.kept.end(), pid)) removePoint(pid);
    }
    return looked_at;
  }
  const std::vector<PointId>& points = describedBy(id);
  std::vector<std::pair<size_t, PointId>> gone;
  for (PointId pid : points) {
    if (std::binary_search(deferred_.kept.begin(), deferred_.kept.end(), pid)) continue;
    const auto it = slot_index_.find(pid);
    gone.emplace_back(it == slot_index_.end() ? SIZE_MAX : it->second, pid);
  }
  const size_t looked_at = points.size() + 1;
  std::sort(gone.begin(), gone.end());
  for (const auto& [index, pid] : gone) removePoint(pid);
  return looked_at;
}

// After the update's points: those the mapper kept were re-described from other keyframes;
// any still described by this keyframe (the mapper never had them) go with it.
// Found from the index (a pass over every point, once for each keyframe culled, was most of
// a map update's time on the tracking thread: 3 ms a keyframe at 15 000 points). Removed in
// slot order, as in freeze(): removing a slot moves the last one into its place, so the
// order decides the slots' (the search's) order after it; the slotless ones (a cold
// keyframe's) leave the slots as they are.
void MapReplica::removeKeyframe(KeyframeId id, bool store_later) {
  if (!map_.hasKeyframe(id)) return;
  takeStored(id);  // its points on storage go unread (the store's entries go below)
  std::vector<std::pair<size_t, PointId>> described;
  for (PointId pid : describedBy(id)) {
    const auto it = slot_index_.find(pid);
    described.emplace_back(it == slot_index_.end() ? SIZE_MAX : it->second, pid);
  }
  std::sort(described.begin(), described.end());
  described_.erase(id);  // first: removePoint need not find each point in it
  for (const auto& [index, pid] : described) removePoint(pid);
  bounds_.erase(id);
  map_.removeKeyframe(id);
  if (store_ && store_later) {
    store_->removeLater(id);
  } else if (store_) {
    store_->remove(id);
  }
}

}  // namespace rgbdslam
