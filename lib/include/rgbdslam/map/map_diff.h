#pragma once
// What the mapper publishes over a lossy, narrow link: the difference between its map and the
// state it last published. A delta lists the keyframes whose pose moved by more than a
// threshold since it was last published, the points that are new (in full), the points that
// moved by more than a threshold (id and position only: a third of the bytes), and the ids
// removed; a snapshot lists everything in full.
// A point whose patch the mapper re-describes keeps its id and patch here (the mapper never
// changes a point's source keyframe, level or pixel). Entries below the threshold are
// not sent, and their baseline is kept, so slow drift accumulates until it crosses the
// threshold (nothing is lost, only postponed). Versions and acknowledgements are the
// caller's business (the process stamps them).
// Thresholds: 1 mm moves a point at 2 m by 0.26 px in a 525 px camera, below the tracker's
// measurement noise; the same for keyframe centres, and 0.5 mrad for their orientation.
#include <map>
#include <unordered_map>

#include "rgbdslam/map/map.h"

namespace rgbdslam {

struct MapDiffOptions {
  double point_move_m = 0.001;     // a point moved further than this is re-sent [m]
  double keyframe_move_m = 0.001;  // a keyframe centre moved further than this is re-sent [m]
  double keyframe_turn_rad = 5e-4; // ...or its orientation turned more than this [rad]
};

class MapDiffer {
 public:
  explicit MapDiffer(const MapDiffOptions& options = {}) : options_(options) {}
  // Changes since the last delta() or snapshot(); the returned update has is_snapshot false
  // and no version, map id or acknowledgements. The baseline advances for what is returned.
  MapUpdate delta(const Map& map);
  // The whole map; the baseline becomes the map.
  MapUpdate snapshot(const Map& map);
  bool empty(const MapUpdate& update) const {
    return update.keyframes.empty() && update.points.empty() && update.removed_points.empty();
  }

 private:
  MapDiffOptions options_;
  std::unordered_map<PointId, Vec3> points_;  // position as last published
  std::map<KeyframeId, SE3> keyframes_;       // pose as last published
};

}  // namespace rgbdslam
