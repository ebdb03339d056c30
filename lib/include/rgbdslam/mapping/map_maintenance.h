#pragma once
// Map clean-up after bundle adjustment (PTAM's HandleBadPoints): drop measurements judged
// 2-D outliers, and points that are mostly outliers or have too few good measurements.
// Points seen only in their source keyframe are kept while that keyframe is recent (the
// following keyframes may still find them).
// cullDivergedPoints: points that bundle adjustment has carried off: behind their source
// keyframe's camera, or farther from it than max_depth_m. Why: a point measured without
// depth along nearly parallel rays (a far wall beyond the sensor's range) has almost no
// parallax, so bundle adjustment can move it along its ray at no cost; on the full corridor
// through the split suite such points reached 20-1000 km. Sent on, a point beyond the map
// protocol's world bound (10 km) made the tracker refuse every later map version (each
// snapshot held it too), so it tracked a stale map for the rest of the run. Far points are
// not culled sooner: their direction still fixes the rotation (with a limit of 40 m the
// mono corridor, 900 frames, lost its scale: ATE 5.4 m instead of 15-17 mm).
// cullRedundantKeyframes (issue 10, item 2): ORB-SLAM's keyframe culling. A keyframe goes
// when at least keyframe_redundancy of its measurements are also measured in at least
// keyframe_redundant_observers other keyframes at the same or a finer pyramid level: the
// map loses no point and little geometry, and every keyframe fewer is bundle adjustment,
// memory on both ends and map-message bytes saved. Except a keyframe that measures fewer
// than keyframe_cull_min_points (the tracker's keyframe_few_points, 60): the tracker made it
// where points are scarce, and there it tracks with the help of the nearest keyframes' depth
// surfaces (depth_alignment.h), which the point count does not see. Measured on the office
// (plain walls; its keyframes measure 17-77 points, the corridor's 112-635, 10th-90th
// percentile): culling those left 8 of 36 keyframes and the tracker was lost for good at
// frame 215 instead of 770 (rgbd-slam --source synth:office --deterministic).
// How many other keyframes: 2 in depth-ba, where each measurement's depth residual holds
// the point too. Measured (rgbd-slam --deterministic, corridor 900 frames / full): with 3,
// 60 / 252 keyframes left (2.0 / 2.3 per metre), ATE 13.1 / 18.9 mm; with 2, 32 / 127
// (1.1 / 1.2 per metre), 13.4 / 33.1 mm (32.0 mm without culling), room 1.75 mm (1.67).
// Nor is a keyframe culled that holds the chain of keyframes together (keyframe_cull_min_shared):
// the keyframes before and after it (id order) must share at least 15 points without it (the
// count ORB-SLAM asks of an edge of its covisibility graph), or as many as the weaker of its
// links to them. Culled one by one, the redundant keyframes of a
// turn from a corridor into a room took every point the two sides shared (synth:flight,
// 1800 frames: keyframes 108-114), the room's keyframes stayed tied to the rest of the map
// by 2 points without depth, each free along a fixed camera's ray, and every global bundle
// adjustment turned them rigidly by about 1 deg (0.13 m at the far end) at no cost
// (4424.1 -> 4423.9): map corrections of 0.52 m, ATE 45 mm; with the guard 0.02 m, 22 mm.
// Where bundle adjustment sees only directions (mono, depth-init) no keyframe is culled by
// default (keyframe_redundant_observers 0): there a point's depth rests on the baselines of
// the keyframes that measure it, and every measured culling cost accuracy on the corridor,
// where culling matters (ORB-SLAM's 3 other keyframes; ATE without / with culling): mono
// 450 frames 54.7 / 62.1 mm, 900 frames 17.1 / 17.8 mm; depth-init 450 frames 66.9 / 68.6 mm
// and a frame lost to the depth check, 900 frames 88 / 197 mm; with 2 mono lost the scale
// (93 mm). The flight's mode is depth-ba.
// Why so many keyframes are redundant: where points are scarce (a corridor
// seen head-on) the tracker must add a keyframe every few frames to keep finding enough
// points (keyframe_policy.h); measured on maps saved at the end of a run, all but 133 of the
// full corridor's 789 keyframes pass this rule (docs/open_work.md).
// What the removal does: the keyframe's measurements go; a point whose patch it held takes
// the patch of another keyframe that measures it (the finest level, then the camera nearest
// the removed one; never keyframe 0, whose points hold the scale in the 2-D modes), and the
// map publisher sends it in full again; a point no other keyframe measures goes. Keyframe 0
// (the gauge) is never culled; the caller keeps the newest keyframes out of 'candidates'
// (the tracker is still extending them and re-finding has not yet searched them).
#include <set>
#include <utility>
#include <vector>

#include "rgbdslam/map/map.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

struct CullOptions {
  int min_good_measurements = 2;      // fewer: the point goes (unless source-only and recent)
  double max_outlier_fraction = 0.5;  // more of a point's measurements flagged: the point goes
  int keep_source_only_keyframes = 3;  // points seen only in their source keyframe survive
                                       // while it is among this many newest keyframes
  // A tenth of the protocol's world bound: a point this far is at infinity for any camera
  // of ours (its direction is all it gives), and no published position comes near the bound.
  double max_depth_m = 1000.0;        // [m] in the source keyframe
  bool cull_keyframes = true;         // remove redundant keyframes (see above)
  double keyframe_redundancy = 0.9;   // share of measurements seen elsewhere to be redundant [0, 1]
  int keyframe_redundant_observers = 0;  // ...in mono, depth-init (0: no culling there; see above)
  int keyframe_redundant_observers_depth = 2;  // ...in mode depth-ba (see above)
  int keyframe_cull_min_age = 5;      // the newest this many keyframes are never culled [keyframes]
  int keyframe_cull_min_points = 60;  // keyframes measuring fewer points are never culled [points]
  int keyframe_cull_min_shared = 15;  // ...nor one whose neighbours (by id) would then share fewer
                                      // points than this, or than through it (0: off) [points]

  void bind(OptionRegistry* registry, const std::string& section);
};

struct CullResult {
  std::vector<PointId> removed_points;  // in id order
  int removed_measurements = 0;         // single measurements removed (points kept)
};

// 'pending_2d_outliers' (point id, keyframe id) is consumed.
CullResult cullMap(Map* map, std::set<std::pair<PointId, KeyframeId>>* pending_2d_outliers,
                   const CullOptions& options);

// Of 'candidates' (the points a bundle adjustment moved), removes those behind their source
// keyframe's camera or deeper in it than max_depth_m (see above); returns their ids. Run
// at once after every adjustment, so that no published map holds them.
std::vector<PointId> cullDivergedPoints(Map* map, const std::vector<PointId>& candidates, double max_depth_m);

struct KeyframeCullResult {
  std::vector<KeyframeId> removed_keyframes;  // in the order removed
  std::vector<std::pair<SE3, KeyframeId>> removed_poses;  // each one's pose and part then, in that order
  std::vector<PointId> resourced_points;      // now described by another keyframe's patch
  std::vector<PointId> removed_points;        // measured in no other keyframe
};

// Tests the 'candidates' in order (each removal counts for the following tests) and removes
// the redundant ones (see above). Pending 2-D outliers of removed keyframes are dropped.
KeyframeCullResult cullRedundantKeyframes(Map* map, const std::vector<KeyframeId>& candidates,
                                          const CullOptions& options,
                                          std::set<std::pair<PointId, KeyframeId>>* pending_2d_outliers);

// Why the keyframes of a map stay, by the culling rule (counts; each keyframe in the first
// that applies): keyframe 0; the newest keyframe_cull_min_age; fewer than
// keyframe_cull_min_points measurements; not redundant; holding the chain together; or
// redundant now (culling has not tested it since it became so). For run summaries.
struct KeyframesKept {
  long gauge = 0, young = 0, few_points = 0, not_redundant = 0, bridge = 0, redundant = 0;
};
KeyframesKept keyframesKept(const Map& map, const CullOptions& options);

// Removes the listed keyframes as culling does, without judging them (a restarted mapper
// repeats the culls of its journal); keyframe 0 and unknown ids are left alone.
KeyframeCullResult removeKeyframes(Map* map, const std::vector<KeyframeId>& ids,
                                   std::set<std::pair<PointId, KeyframeId>>* pending_2d_outliers);

// Point ids of the map in increasing order.
std::vector<PointId> sortedPointIds(const Map& map);

}  // namespace rgbdslam
