#pragma once
// What the map publisher sends over a lossy, narrow link: the difference between the map and
// the state it last published. A delta lists the keyframes whose pose moved by more than a
// threshold since they were last published, the points that are new (in full), the points
// that moved by more than a threshold (id and position only: a third of the bytes), and the
// ids of points and keyframes removed; a snapshot lists everything in full, and every
// keyframe culled so far (8 bytes each).
// Deltas are built from the mapper's change reports (MapChanges), so their cost grows with
// what changed, not with the map. An entry below its threshold is not sent and its baseline
// (the value last published) is kept, so slow drift accumulates until it crosses the
// threshold (nothing is lost, only postponed). A point changes its patch (source keyframe,
// level, pixel) only when its source keyframe is culled (map_maintenance.h); it is then sent
// in full again. Versions and acknowledgements are the
// publisher's business (sync/map_publisher.h).
// Thresholds: 1 mm moves a point at 2 m by 0.26 px in a 525 px camera, below the tracker's
// measurement noise; the same for keyframe centres, and 0.5 mrad for their orientation.
// Memory: a baseline position per published point and pose per keyframe (grows with the map).
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
  // The entries of 'changes' that differ from the baseline by more than the thresholds, in
  // id order; the returned update has is_snapshot false and no version, map id or
  // acknowledgements. The baseline advances for what is returned. With 'held_back', only
  // what is new to the baseline (keyframes, points, points re-described), removals and moves
  // of more than 10 times their threshold (a loop closure's correction) are taken; the ids
  // of keyframes and points that only moved less go to *held_back.
  MapUpdate delta(const Map& map, const MapChanges& changes, MapChanges* held_back = nullptr);
  // The whole map; the baseline becomes the map.
  MapUpdate snapshot(const Map& map);

 private:
  MapDiffOptions options_;
  struct PublishedPoint {
    Vec3 p_w;            // position as last published
    KeyframeId source;   // source keyframe as last published
  };
  std::unordered_map<PointId, PublishedPoint> points_;
  struct PublishedKeyframe {
    SE3 T_w_c;
    KeyframeId part = 0;
  };
  std::map<KeyframeId, PublishedKeyframe> keyframes_;  // as last published
};

}  // namespace rgbdslam
