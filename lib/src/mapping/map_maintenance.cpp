#include "rgbdslam/mapping/map_maintenance.h"

#include <algorithm>
#include <iterator>
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

// How many keyframes other than 'self' measure the point at 'level' or finer.
int observersAtOrBelow(const Map& map, PointId pid, KeyframeId self, int level) {
  int count = 0;
  for (KeyframeId id : map.observers(pid)) {
    if (id == self) continue;
    const auto& measurements = map.keyframe(id)->measurements();
    const auto it = measurements.find(pid);
    if (it != measurements.end() && it->second.level <= level) ++count;
  }
  return count;
}

bool redundant(const Map& map, const Keyframe& kf, const CullOptions& options) {
  const size_t total = kf.measurements().size();
  if (total == 0 || static_cast<int>(total) < options.keyframe_cull_min_points) return false;
  size_t seen_elsewhere = 0;
  for (const auto& [pid, m] : kf.measurements()) {
    if (observersAtOrBelow(map, pid, kf.id, m.level) >= options.keyframe_redundant_observers) ++seen_elsewhere;
  }
  return static_cast<double>(seen_elsewhere) >= options.keyframe_redundancy * static_cast<double>(total);
}

// Points measured in both keyframes.
int sharedPoints(const Keyframe& a, const Keyframe& b) {
  const Keyframe& fewer = a.measurements().size() <= b.measurements().size() ? a : b;
  const Keyframe& more = &fewer == &a ? b : a;
  int shared = 0;
  for (const auto& [pid, m] : fewer.measurements()) shared += more.measurements().count(pid) > 0 ? 1 : 0;
  return shared;
}

// True when 'kf' holds the keyframe chain together: the keyframes before and after it (in id
// order, i.e. along the path) share fewer points without it than the link through it,
// min(keyframe_cull_min_shared, its points shared with either). Each culled keyframe is
// redundant on its own, but culled one after another the keyframes of a turn can take every
// point that the keyframes on either side of it shared, and bundle adjustment then holds
// what follows by a couple of points.
bool bridgesChain(const Map& map, const Keyframe& kf, const CullOptions& options) {
  if (options.keyframe_cull_min_shared <= 0) return false;
  const auto it = map.keyframes().find(kf.id);
  if (it == map.keyframes().end() || it == map.keyframes().begin()) return false;
  const auto next = std::next(it);
  if (next == map.keyframes().end()) return false;
  const Keyframe& before = *std::prev(it)->second;
  const Keyframe& after = *next->second;
  const int through = std::min({options.keyframe_cull_min_shared, sharedPoints(before, kf), sharedPoints(kf, after)});
  return sharedPoints(before, after) < through;
}

// The keyframe that describes the point once 'removed' is gone: the finest measurement,
// then the camera nearest the removed one; never keyframe 0 (see the header). -1: none.
KeyframeId newSource(const Map& map, PointId pid, const Keyframe& removed) {
  KeyframeId best = -1;
  int best_level = 0;
  double best_distance = 0.0;
  for (KeyframeId id : map.observers(pid)) {
    if (id == removed.id || id == 0) continue;
    const Keyframe* kf = map.keyframe(id);
    const int level = kf->measurements().at(pid).level;
    const double distance = (kf->T_w_c.translation() - removed.T_w_c.translation()).norm();
    if (best < 0 || level < best_level || (level == best_level && distance < best_distance)) {
      best = id, best_level = level, best_distance = distance;
    }
  }
  return best;
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
  r->bind(s, "cull_keyframes", &cull_keyframes, "remove keyframes whose points are nearly all measured in other keyframes");
  r->bind(s, "keyframe_redundancy", &keyframe_redundancy, 0.0, 1.0, "-",
          "a keyframe is redundant when this share of its measurements is also in keyframe_redundant_observers others at the same or a finer level");
  r->bind(s, "keyframe_redundant_observers", &keyframe_redundant_observers, 0, 100, "keyframes",
          "other keyframes that must measure a point for it to count as seen elsewhere in modes mono and depth-init "
          "(0: no keyframe is culled in those modes)");
  r->bind(s, "keyframe_redundant_observers_depth", &keyframe_redundant_observers_depth, 1, 100, "keyframes",
          "the same in mode depth-ba, where bundle adjustment holds each measurement's depth too");
  r->bind(s, "keyframe_cull_min_age", &keyframe_cull_min_age, 1, 1000, "keyframes",
          "the newest this many keyframes are never culled");
  r->bind(s, "keyframe_cull_min_shared", &keyframe_cull_min_shared, 0, 100000, "points",
          "a redundant keyframe stays when the keyframes before and after it would share fewer points without it "
          "than this many, or than the link through it if weaker (0: off)");
  r->bind(s, "keyframe_cull_min_points", &keyframe_cull_min_points, 0, 100000, "points",
          "keyframes measuring fewer points are never culled: where points are this scarce the tracker leans on "
          "the keyframes' depth surfaces (as tracker.keyframe_few_points)");
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

namespace {

// Removes keyframe 'id' (see the header: its points re-described or removed).
void removeKeyframe(Map* map, KeyframeId id, std::set<std::pair<PointId, KeyframeId>>* pending_2d_outliers,
                    KeyframeCullResult* result) {
  const Keyframe* kf = map->keyframe(id);
  std::vector<PointId> measured;
  for (const auto& [pid, m] : kf->measurements()) measured.push_back(pid);
  std::sort(measured.begin(), measured.end());
  for (PointId pid : measured) {
    MapPoint* point = map->point(pid);
    if (point->source_keyframe != id) continue;
    const KeyframeId source = newSource(*map, pid, *kf);
    if (source < 0) {
      map->removePoint(pid);
      result->removed_points.push_back(pid);
      continue;
    }
    const Measurement& m = map->keyframe(source)->measurements().at(pid);
    point->source_keyframe = source;
    point->source_level = m.level;
    point->source_uv = m.uv;
    result->resourced_points.push_back(pid);
  }
  // Points described by it that it does not measure (a 2-D outlier at the source, removed
  // before the point was culled) cannot keep it as their source either.
  std::vector<PointId> described;
  for (const auto& [pid, point] : map->points()) {
    if (point.source_keyframe == id) described.push_back(pid);
  }
  std::sort(described.begin(), described.end());
  for (PointId pid : described) {
    map->removePoint(pid);
    result->removed_points.push_back(pid);
  }
  result->removed_poses.emplace_back(kf->T_w_c, kf->part);
  map->removeKeyframe(id);
  for (PointId pid : measured) {
    if (map->point(pid) && map->observers(pid).empty()) {
      map->removePoint(pid);
      result->removed_points.push_back(pid);
    }
  }
  for (auto it = pending_2d_outliers->begin(); it != pending_2d_outliers->end();) {
    it = it->second == id ? pending_2d_outliers->erase(it) : std::next(it);
  }
  result->removed_keyframes.push_back(id);
}

}  // namespace

KeyframeCullResult cullRedundantKeyframes(Map* map, const std::vector<KeyframeId>& candidates,
                                          const CullOptions& options,
                                          std::set<std::pair<PointId, KeyframeId>>* pending_2d_outliers) {
  KeyframeCullResult result;
  if (options.keyframe_redundant_observers < 1) return result;  // culling off for this mode
  for (KeyframeId id : candidates) {
    const Keyframe* kf = map->keyframe(id);
    // A part's first keyframe (keyframe 0 for the map's start) names its part and holds its
    // gauge (mapper.h, "Parts").
    if (id != 0 && kf && kf->part != id && redundant(*map, *kf, options) && !bridgesChain(*map, *kf, options)) {
      removeKeyframe(map, id, pending_2d_outliers, &result);
    }
  }
  return result;
}

KeyframesKept keyframesKept(const Map& map, const CullOptions& options) {
  KeyframesKept kept;
  const std::set<KeyframeId> young = newestKeyframes(map, options.keyframe_cull_min_age);
  for (const auto& [id, kf] : map.keyframes()) {
    if (id == 0 || kf->part == id) ++kept.gauge;
    else if (young.count(id)) ++kept.young;
    else if (static_cast<int>(kf->measurements().size()) < options.keyframe_cull_min_points) ++kept.few_points;
    else if (!redundant(map, *kf, options)) ++kept.not_redundant;
    else if (bridgesChain(map, *kf, options)) ++kept.bridge;
    else ++kept.redundant;
  }
  return kept;
}

KeyframeCullResult removeKeyframes(Map* map, const std::vector<KeyframeId>& ids,
                                   std::set<std::pair<PointId, KeyframeId>>* pending_2d_outliers) {
  KeyframeCullResult result;
  for (KeyframeId id : ids) {
    if (id != 0 && map->hasKeyframe(id)) removeKeyframe(map, id, pending_2d_outliers, &result);
  }
  return result;
}

}  // namespace rgbdslam
