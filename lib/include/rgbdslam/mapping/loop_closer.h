#pragma once
// Loop closure in the ground mapper (issue 11, item 2): when a new keyframe sees again a
// place mapped long before that the map does not yet tie it to, the drift between the two
// is taken out of every keyframe at once.
//
// On each new keyframe (Mapper::addKeyframe, after its local bundle adjustment):
//  1. its ORB features with depth (extractFeatures3d) go into the place database
//     (place_recognition.h); a query runs against the keyframes at least min_keyframe_gap
//     older that share no point with it (a keyframe that already measures an old
//     keyframe's points is tied to it by bundle adjustment: nothing to close);
//  2. a recognised place gives a loop edge (quadratic: see verifiedLoops) (the verified T_k_q, its sigma floored at
//     loop_sigma_min_*) in a pose graph over all keyframes (pose_graph.h): odometry edges
//     between consecutive keyframes from the current poses, with sigmas that grow with the
//     step (odometry_sigma_*: what the drift between two keyframes may be), keyframe 0
//     fixed (and a loaded map's keyframes: onKeyframe), and the loop edges accepted before
//     (mapper.h, "Parts": odometry edges only within a part, the oldest keyframe of each
//     part that no loop edge joins fixed; a place recognised in another part joins the
//     two, within join_max_speed_m_s);
//  3. a loop edge that already agrees with the map (its residual at the current poses within
//     agree_sigmas of its own noise) has nothing to correct: it joins the loop edges kept for
//     later closures (counted as agreed) and the map stays as it is, with no graph solved;
//  4. loop edges that disagree with the solution are dropped and the graph solved again;
//     if the new edge is among them the loop is refused (counted), the map stays as it was;
//  5. otherwise, if some keyframe moves by more than min_correction_m / _deg, every
//     keyframe takes its new pose and every point moves rigidly with its source keyframe;
//     the caller records the changes and runs bundle adjustment, and the tracker gets the
//     corrected map as an ordinary map update (it takes corrections in smoothly,
//     tracker.correction_rate_*).
// Mono: off (its scale drifts, which an SE(3) graph cannot take out).
// Cost: the vocabulary is trained (projectVocabulary, ~2 s once per process) only when the
// map first has more than min_keyframe_gap keyframes; the features are kept until then.
// Memory ~30 kB per keyframe (place_recognition.h). Time per keyframe: recognition ~15 ms on
// average (place_recognition.h), a pose graph only when a place is recognised.
// Determinism: no randomness beyond the seeded RANSAC of the verification.
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "rgbdslam/map/map.h"
#include "rgbdslam/mapping/place_recognition.h"
#include "rgbdslam/mapping/pose_graph.h"
#include "rgbdslam/tracking/feature_relocaliser.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

struct LoopClosureOptions {
  bool enabled = true;                    // in the depth modes (never in mono)
  int min_keyframe_gap = 20;              // a loop candidate is at least this many keyframes older [keyframes]
  double odometry_sigma_min_m = 0.005;    // 1-sigma drift between consecutive keyframes, at least [m]...
  double odometry_sigma_fraction = 0.05;  // ...or this fraction of their distance [-]
  double odometry_sigma_min_deg = 0.2;    // rotation: at least [deg]...
  double odometry_sigma_deg_per_m = 2.0;  // ...or this much per metre between them [deg/m]
  double loop_sigma_min_m = 0.005;        // a loop edge's 1-sigma translation, at least [m]
  double loop_sigma_min_deg = 0.2;        // ...and rotation [deg]
  double min_correction_m = 0.005;        // a closure that moves no keyframe further [m]...
  double min_correction_deg = 0.2;        // ...nor turns one further [deg] changes nothing
  // A recognised place whose loop edge's whitened residual at the map's current poses is at
  // most this (the 99% point of a 6-D chi distribution is 4.1; the edge's sigma is its worst
  // axis, so the test leans to "agrees") is one the map already closes: a correction would
  // only move the map by the loop measurement's own noise, and re-send it over the link.
  // Without this gate, a keyframe of a revisit that does not yet share points with the old
  // place solved the graph again and, past min_correction_*, moved the whole map by that
  // noise (LoopCloser.ClosesOnceAndThenAgrees: 7 closures without it, 2 with it).
  double agree_sigmas = 4.0;              // [sigmas]; 0: every recognised place is solved
  // Parts of the map (mapper.h, "Parts"): a place recognised in another part joins the two
  // (the newer part moves rigidly onto the older, through the loop edge) only if the newer
  // part's first keyframe then lies within this speed times the time since the keyframe
  // before it, plus the margin (as tracker.relocalise_max_speed_m_s bounds a relocalisation;
  // 0: anywhere). Odometry cannot bound it: the part started where the tracker was lost.
  double join_max_speed_m_s = 3.0;        // [m/s]
  double join_margin_m = 1.0;             // [m]
  int features = 500;                     // ORB features per keyframe at most
  PlaceRecognitionOptions place;          // section "place_recognition"
  PoseGraphOptions graph = verifiedLoops();  // section "pose_graph"

  // The pose graph's options for loops that passed place recognition's checks (geometry,
  // odometry bound, ambiguity): a quadratic loss. With the Cauchy loss at 1 sigma, a loop
  // whose drift (12 cm, 3 deg over 50 keyframes: test_loop_closer) exceeds what the odometry
  // sigmas make cheap stayed open (the edge kept 0.195 m of its disagreement). A loop edge
  // that then disagrees with the others (two closures that cannot both hold) is still
  // dropped (disagree_sigmas), and the new one refused.
  static PoseGraphOptions verifiedLoops() {
    PoseGraphOptions options;
    options.loop_loss = PoseGraphOptions::LoopLoss::kNone;
    return options;
  }

  // The loop closer's own keys in 'section'; place recognition and the pose graph in theirs.
  void bind(OptionRegistry* registry, const std::string& section = "loop_closure");
};

struct LoopClosureResult {
  PlaceStatus place = PlaceStatus::kNoCandidate;  // what recognition said (kNoCandidate: not tried)
  bool tried = false;         // a query ran
  bool closed = false;        // the map was corrected
  bool refused = false;       // recognised, but the loop edge disagreed with the graph
  bool agreed = false;        // recognised, and the map already agrees with it (agree_sigmas)
  bool same_part = false;     // the place is in the keyframe's own part (else: a join)
  double disagreement_sigmas = 0.0;  // the new loop edge's whitened residual before any solve
                                     // (meaningful with same_part; across parts the frames differ) [-]
  double disagreement_m = 0.0;       // ...its translation [m]
  double disagreement_deg = 0.0;     // ...and rotation [deg]
  KeyframeId with = -1;       // the old keyframe recognised
  // The loop edge as measured (the new keyframe in the recognised one's frame, from the
  // verification alone) and both keyframes' acquisition times: what an audit against ground
  // truth compares (eval/loop_audit.h), whatever the map made of the edge.
  SE3 T_with_query;
  int64_t with_utime = 0, query_utime = 0;  // [us]
  double correction_m = 0.0;  // the largest keyframe move [m]
  double correction_deg = 0.0;  // ...and turn [deg]
  double recognise_ms = 0.0, graph_ms = 0.0;
  KeyframeId joined_part = -1;  // a part joined to another by this closure (mapper.h, "Parts")...
  KeyframeId joined_to = -1;    // ...and the part it joined, whose name it takes
};

struct LoopClosureCounters {
  long queries = 0, recognised = 0, closed = 0, refused = 0;
  long agreed = 0;  // recognised places the map already agreed with (no solve, nothing moved)
  // Queries whose place verified but was refused by recognition itself: farther from the
  // keyframe's pose than the drift since explains (a lookalike place), or two verified
  // places that disagree (PlaceStatus kInconsistentWithOdometry, kAmbiguous).
  long beyond_drift = 0, ambiguous = 0;
  long parts_joined = 0;  // closures that joined two parts of the map
};

// One line for a log: "loop with keyframe J: closed, disagreement 5.2 sigmas (0.031 m, 0.40
// deg), correction 0.052 m, 0.61 deg; edge utime U_J -> U_K t X Y Z q QX QY QZ QW" (empty when
// no place was recognised). The edge (T_with_query: metres, a unit quaternion) is for
// scripts/lib/loop_audit.py, which checks a split run's loops against the ground truth.
std::string describe(const LoopClosureResult& result);

class LoopCloser {
 public:
  LoopCloser(const PinholeCamera& camera, const LoopClosureOptions& options);
  ~LoopCloser();
  // Keyframe 'id', just integrated into 'map' (ids increasing; a loaded map's keyframes
  // through here too, with 'close' false). Moved keyframes and points go into 'changes'.
  // A loaded map is the reference a session extends: its keyframes are held fixed in every
  // pose graph (as ORB-SLAM3 holds the older map when it merges two), so a loop closed into
  // it bends only the session's keyframes, and the frame an earlier run localised in stays.
  LoopClosureResult onKeyframe(Map* map, KeyframeId id, MapChanges* changes, bool close = true);
  // Keyframe 'id' was culled from the map (map_maintenance.h): no longer a place to close to.
  void onKeyframeRemoved(KeyframeId id);
  const LoopClosureCounters& counters() const { return counters_; }
  // Every recognised place's verdict in order, the first kMaxRecognisedKept (~170 bytes
  // each, 1.7 MB at most; a flight of ten minutes recognises tens): for rgbd-slam's audit
  // against the ground truth (eval/loop_audit.h; rgbd-slam prints how many are past the cap).
  static constexpr size_t kMaxRecognisedKept = 10000;
  const std::vector<LoopClosureResult>& recognised() const { return recognised_; }

 private:
  struct Pending {
    KeyframeId id;
    SE3 T_w_k;
    Features3d features;
  };
  PlaceMatch recognise(const Map& map, const Keyframe& kf, const Features3d& features,
                       const PlaceExclusion& exclusion, LoopClosureResult* result);
  bool partJoinWithinReach(const Map& map, KeyframeId part, KeyframeId onto, const SE3& moved) const;
  void joinParts(Map* map, KeyframeId newer, KeyframeId older, MapChanges* changes);
  PoseGraph buildGraph(const Map& map, const PoseGraphEdge& loop) const;
  void solveAndApply(Map* map, const PoseGraphEdge& loop, MapChanges* changes, LoopClosureResult* result);
  bool apply(Map* map, const PoseGraphResult& solved, const PoseGraph& graph, MapChanges* changes,
             LoopClosureResult* result) const;

  PinholeCamera camera_;
  LoopClosureOptions options_;
  std::unique_ptr<PlaceDatabase> places_;  // made when first needed (the vocabulary costs ~2 s)
  std::vector<Pending> pending_;           // keyframes' features until then
  std::vector<PoseGraphEdge> loops_;       // loop edges accepted so far
  std::set<KeyframeId> loaded_;            // a loaded map's keyframes: fixed in the graph
  LoopClosureCounters counters_;
  std::vector<LoopClosureResult> recognised_;
};

}  // namespace rgbdslam
