#pragma once
// Plain data exchanged between tracker and mapper (and carried by keyframe_t / map_t).
// Ids: point_ids.h.
#include <cstdint>
#include <opencv2/core.hpp>
#include <set>
#include <vector>

#include "rgbdslam/geometry/se3.h"
#include "rgbdslam/map/point_ids.h"

namespace rgbdslam {

struct Measurement {
  PointId point_id = -1;
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();  // pixel at level 0 [px]
  int level = 0;                                 // pyramid level found at
  double depth = 0.0;  // measured depth at the corner [m]; 0 = no valid reading
};

struct MapPointData {
  PointId id = -1;
  Vec3 p_w = Vec3::Zero();            // position in the world [m]
  KeyframeId source_keyframe = -1;    // keyframe holding the point's patch
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();  // pixel in the source keyframe, level 0
  int level = 0;                      // pyramid level of the patch
};

struct KeyframeData {
  int64_t utime = 0;        // acquisition time [us]
  int64_t map_id = 0;       // the tracker session's map
  KeyframeId id = -1;
  SE3 T_w_c;
  cv::Mat grey;             // CV_8UC1
  cv::Mat depth;            // CV_16UC1 raw units (0 = none), or empty
  double depth_scale = 5000.0;  // raw units per metre
  std::vector<Measurement> measurements;
  std::vector<MapPointData> new_points;
  bool grey_lossy = false;  // 'grey' went through a lossy codec (JPEG on the link)
  // The first keyframe of a new part of the map (mapper.h, "Parts"): made where the tracker
  // was lost in unmapped space, at the pose it coasted to; it measures no earlier point.
  bool new_part = false;
  // The keyframe the pose was tracked against and its pose in the tracker's map then (-1:
  // none): the mapper re-expresses this keyframe in its own map through it (mapper.h).
  KeyframeId anchor = -1;
  SE3 T_w_anchor = SE3();
};

// Positions (camera centres, points) lie within this of the map's origin on every axis: the
// protocol refuses anything beyond (procs/common/protocol_limits.h), so nothing the mapper
// derives may go beyond it either.
constexpr double kWorldBoundM = 1e4;  // [m]

struct KeyframePose {
  KeyframeId id = -1;
  SE3 T_w_c;
  KeyframeId part = 0;  // Keyframe::part (map updates carry it; the loop closer renames parts)
};

struct PointPosition {
  PointId id = -1;
  Vec3 p_w = Vec3::Zero();  // new position in the world [m]
};

struct MapUpdate {
  int64_t utime = 0;        // publication time [us]
  int64_t map_id = 0;
  int64_t version = 0;      // increases by one per published change
  bool is_snapshot = false; // true: full map; false: delta against version - 1
  KeyframeId acked_below = 0;  // keyframes with smaller ids are integrated (acknowledged)
  std::vector<KeyframePose> keyframes;
  std::vector<MapPointData> points;         // new or re-described points (all, in a snapshot)
  std::vector<PointPosition> moved_points;  // known points that only moved (patch unchanged)
  std::vector<PointId> removed_points;
  // Keyframes culled as redundant (map_maintenance.h); their points that stay were
  // re-described from another keyframe and are in 'points'. A snapshot lists every keyframe
  // culled so far.
  std::vector<KeyframeId> removed_keyframes;
};

// What changed in a map since it was last asked (Mapper::takeChanges): the map publisher
// turns it into a delta. Ids only; the values are read from the map when published.
struct MapChanges {
  std::set<KeyframeId> keyframes;   // new, or pose changed
  std::set<PointId> points;         // new, or position changed
  std::set<PointId> removed_points; // culled (never in 'points' at the same time)
  std::set<KeyframeId> removed_keyframes;  // culled (never in 'keyframes' at the same time)
  bool empty() const {
    return keyframes.empty() && points.empty() && removed_points.empty() && removed_keyframes.empty();
  }
  void merge(const MapChanges& later);
};

// The tracker's receipt for map versions (carried by map_receipt_t): which version of which
// map it holds. The mapper's publisher reads it to find a tracker stuck behind a lost delta.
struct MapReceipt {
  int64_t utime = 0;                // time of the receipt [us]
  int64_t map_id = 0;               // the tracker's map
  int64_t applied_version = 0;      // newest version applied (0: none yet)
  int64_t newest_version_seen = 0;  // newest version of this map received, applied or not
  int64_t keyframes_created = 0;    // keyframe ids below this exist on the tracker
  int64_t keyframes_unacked = 0;    // of those, not yet acknowledged
  // The oldest keyframe id the tracker can still send (unacknowledged, or acknowledged and
  // retained); a mapper lacking keyframes below it skips them, since none will come.
  int64_t keyframes_sendable_from = 0;
};

}  // namespace rgbdslam
