#pragma once
// A map point's record of the tracker's depth integrity check (tracking/depth_integrity.h)
// at accepted poses. It lives with the point (MapPoint::depth_record), not with the
// tracker's search slot (tracking/point_projection.h), which is per-frame search state: a
// point without a slot for a while (its keyframe outside the local map,
// tracking/map_replica.h) keeps its record for when the camera comes back.
#include <cstdint>

namespace rgbdslam {

// What the check found at one point.
enum class DepthVerdict : int8_t { kUnchecked, kAgrees, kSeenThrough, kOccluded, kMissing };

struct DepthRecord {
  static constexpr int kMinChecks = 3;  // the record counts after this many checks with a reading
  int checks = 0;        // with a reading
  int seen_through = 0;  // ...of which seen through
  int missing = 0;       // without a reading
  float read_max_m = 0.0f;  // the point's farthest depth at a check with a reading [m]

  // Adds an accepted pose's verdict; 'depth_m': the point's depth at that pose.
  void add(DepthVerdict verdict, double depth_m);
  // Glass, a wrong point: seen through at most of its checks, so the check leaves it out.
  bool mostlySeenThrough() const { return checks >= kMinChecks && 2 * seen_through > checks; }
  // Whether a missing reading at depth 'depth_m' [m] counts as seen through: the surface gave
  // a reading at most checks, and the point is no farther than at any of them. Why the
  // distance: the infrared a surface returns falls with its square, so a dark surface read at
  // 3 m may give none at 4 m, and a camera moving away from one would see "through" a right
  // pose (synth:flight,minutes=2, the store: lost at frames 2602 and 2744 before).
  bool expectsReadingAt(double depth_m) const {
    return checks >= kMinChecks && missing < checks && depth_m <= read_max_m;
  }
};

}  // namespace rgbdslam
