#include "rgbdslam/mapping/ba_problem.h"

#include <algorithm>
#include <map>

namespace rgbdslam {
namespace {

// Point ids measured by the free keyframes, in increasing order.
std::set<PointId> pointsOf(const Map& map, const std::set<KeyframeId>& free_keyframes) {
  std::set<PointId> points;
  for (KeyframeId id : free_keyframes) {
    const Keyframe* kf = map.keyframe(id);
    if (!kf) continue;
    for (const auto& [point_id, m] : kf->measurements()) {
      if (map.point(point_id)) points.insert(point_id);
    }
  }
  return points;
}

}  // namespace

MapBaProblem buildBaProblem(const Map& map, const PinholeCamera& camera,
                            const std::set<KeyframeId>& free_keyframes, int min_fixed_keyframes,
                            bool fix_initial_points) {
  MapBaProblem ba;
  ba.problem.camera = &camera;
  const std::set<PointId> point_ids = pointsOf(map, free_keyframes);
  // Keyframes taking part: every observer of those points.
  std::map<KeyframeId, std::vector<PointId>> seen_by;
  for (PointId pid : point_ids) {
    for (KeyframeId kf : map.observers(pid)) {
      const Keyframe* keyframe = map.keyframe(kf);
      if (keyframe && keyframe->measurements().count(pid)) seen_by[kf].push_back(pid);
    }
  }
  std::map<KeyframeId, int> keyframe_index;
  std::map<KeyframeId, int> fixed_in_part;  // parts (Keyframe::part) share no measurement
  for (const auto& [kf, pids] : seen_by) {
    const bool fixed = kf == 0 || free_keyframes.count(kf) == 0;
    fixed_in_part[map.keyframe(kf)->part] += fixed ? 1 : 0;
    keyframe_index[kf] = static_cast<int>(ba.problem.keyframes.size());
    ba.problem.keyframes.push_back({kf, map.keyframe(kf)->T_w_c, fixed});
  }
  // Gauge, in every part: fix its oldest free keyframes until enough are fixed.
  for (auto& k : ba.problem.keyframes) {
    int& fixed_count = fixed_in_part[map.keyframe(k.id)->part];
    if (fixed_count < min_fixed_keyframes && !k.fixed) k.fixed = true, ++fixed_count;
  }
  std::map<PointId, int> point_index;
  for (PointId pid : point_ids) {
    point_index[pid] = static_cast<int>(ba.problem.points.size());
    const MapPoint* point = map.point(pid);
    const Keyframe* source = map.keyframe(point->source_keyframe);
    const bool fixed = fix_initial_points && source && source->part == source->id;  // a part's first
    ba.problem.points.push_back({pid, point->p_w, fixed});
  }
  for (const auto& [kf, pids] : seen_by) {
    const Keyframe* keyframe = map.keyframe(kf);
    for (PointId pid : pids) {
      const Measurement& m = keyframe->measurements().at(pid);
      ba.problem.observations.push_back({keyframe_index[kf], point_index[pid], m.uv, m.level, m.depth});
      ba.observation_ids.emplace_back(kf, pid);
    }
  }
  return ba;
}

int writeBackBa(const MapBaProblem& ba, Map* map, std::set<KeyframeId>* changed_keyframes,
                std::set<PointId>* changed_points) {
  int written = 0;
  for (const BaKeyframe& k : ba.problem.keyframes) {
    if (k.fixed) continue;
    if (Keyframe* kf = map->keyframe(k.id)) {
      kf->T_w_c = k.T_w_c;
      changed_keyframes->insert(k.id);
      ++written;
    }
  }
  for (const BaPoint& p : ba.problem.points) {
    if (p.fixed) continue;
    if (MapPoint* point = map->point(p.id)) {
      point->p_w = p.p_w;
      changed_points->insert(p.id);
      ++written;
    }
  }
  return written;
}

int applyBaOutliers(const MapBaProblem& ba, const BaResult& result, Map* map,
                    std::set<std::pair<PointId, KeyframeId>>* pending_2d_outliers) {
  if (result.outlier_2d.size() != ba.observation_ids.size()) return 0;
  int dropped_depth = 0;
  for (size_t i = 0; i < ba.observation_ids.size(); ++i) {
    const auto& [kf, pid] = ba.observation_ids[i];
    if (result.outlier_2d[i]) pending_2d_outliers->insert({pid, kf});
    else pending_2d_outliers->erase({pid, kf});
    if (!result.outlier_depth[i]) continue;
    const Keyframe* keyframe = map->keyframe(kf);
    if (!keyframe) continue;
    const auto it = keyframe->measurements().find(pid);
    if (it != keyframe->measurements().end() && it->second.depth > 0.0) {
      map->setMeasurementDepth(kf, pid, 0.0);
      ++dropped_depth;
    }
  }
  return dropped_depth;
}

}  // namespace rgbdslam
