#pragma once
// PTAM's mapper with depth (paper II-B, III-C, IV). It owns the authoritative map.
//   addKeyframe(kf): integrate a keyframe (the caller, sync/mapper_sync.h, brings them in
//   id order from keyframe 0 and filters duplicates and foreign maps): add the keyframe, its
//   measurements of existing points and its provisional points from depth (measurements of
//   unknown points are dropped and counted); for corners without depth (every corner in mono
//   mode) add points by epipolar search against a partner keyframe (the nearest, or a
//   farther one for parallax: EpipolarPartnerOptions; in mono then also the nearest others,
//   partners_mono) (epipolar_search.h); run local bundle adjustment (the new
//   keyframe and its nearest neighbours free, the other keyframes that see their points
//   fixed, keyframe 0 always fixed).
//   refine(interrupt): the background work, one PTAM loop pass per call: re-find the newest
//   points in the other keyframes (data_association.h), global bundle adjustment (all but
//   keyframe 0; only the newest max_global_ba_keyframes free), then cull 2-D outlier
//   measurements and points with too few good ones, then, once per new keyframe, redundant
//   keyframes (both map_maintenance.h). Returns true when
//   the map changed, false when there is nothing left to do (converged). Interrupted
//   (returns early, keeping what was done) when *interrupt becomes true, i.e. a new
//   keyframe arrived.
//   load(map): before the first keyframe, start from a map file's content (map_file.h): its
//   keyframes (images rebuilt), points and measurements as saved; nothing is re-optimised
//   and nothing counts as a change. Keyframes added later continue after its ids.
//   Loop closure (loop_closer.h): after its local BA a new keyframe's place is looked up
//   among the old keyframes; a verified loop moves every keyframe and point (a pose graph)
//   and triggers global bundle adjustment.
//   takeChanges(): the ids of keyframes and points changed or removed since the last call.
//   The mapper versions nothing: the map publisher (sync/map_publisher.h) does.
// Anchor: the tracker tracks against the map as it last received it. A keyframe it made
// before a correction reached it (bundle adjustment, a loop closure, a join of parts: over
// the link, a second or more) carries its pose in the map as it was; after a join, metres and
// tens of degrees off. Local BA cannot pull it back from there: the loop closer saw each such
// keyframe as a new loop (26 closed in one 10-minute flight, 22 within one part, 13 of them
// 1.1-3.6 m and 17-52 deg off, several right after a closure with the same place). So each
// keyframe names the
// keyframe its pose rests on and that keyframe's pose then (KeyframeData::anchor); if the
// anchor is in the map, the new keyframe and its provisional points move by what the anchor
// has moved since (MapperResult::anchor_moved_*); an anchor culled since is reached through
// the keyframe that stood in for it when it was culled (the newest 2048 culls are on record).
// Without it (a part's first keyframe, an anchor in no record or in another part, a move
// that would leave the world bound), the pose is taken as it comes.
// Outliers: after every BA, a measurement judged an outlier in 2-D is queued for removal at
// the next culling; a depth reading judged an outlier is dropped at once (depth set to 0),
// keeping the 2-D measurement.
// Gauge: keyframe 0 is always fixed. In the 2-D modes (mono, depth-init) the BA cost does
// not see the scale, so keyframe 0's points (the map initialisation from measured depth)
// are held fixed and keep it (fixing a second, tracked keyframe instead would pin its
// tracking error into the whole map).
// Parts: where the tracker was lost with nothing in the map to relocalise against, it starts
// a new part of the map from one RGB-D frame, as at the start (tracker.h,
// new_part_after_failures), at the pose it coasted to: a guess relative to the map before.
// A part's keyframes and points are kept to themselves until the loop closer joins it to
// another (loop_closer.h): a keyframe joins the part whose points it measures most (a new
// part when KeyframeData::new_part says so), its measurements of other parts' points are
// dropped (counted), and epipolar partners, local bundle adjustment's neighbours and
// re-finding stay within its part; bundle adjustment fixes the oldest keyframe of every part
// it holds (ba_problem.h). Why not one map tied by the coasted pose: after a second or more
// lost, that pose is off by metres and degrees, and points made from it in the old map's
// frame would tie wrong places together.
// Point ids: the tracker's provisional points and the mapper's own, by point_ids.h.
// Determinism: no randomness; everything iterates in id order, so equal inputs give equal
// maps.
// Threads: not thread-safe; one thread calls everything (interrupt may be set by another).
#include <atomic>
#include <memory>
#include <optional>
#include <string>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/map/map.h"
#include "rgbdslam/map/map_file.h"
#include "rgbdslam/mapping/bundle_adjuster.h"
#include "rgbdslam/mapping/data_association.h"
#include "rgbdslam/mapping/epipolar_search.h"
#include "rgbdslam/mapping/loop_closer.h"
#include "rgbdslam/mapping/map_maintenance.h"
#include "rgbdslam/model/slam_mode.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

// When bundle adjustment runs and over which keyframes.
struct BaWindowOptions {
  int local_ba_neighbours = 4;          // nearest keyframes optimised with the new one
  int global_ba_every = 1;              // run global BA after this many new keyframes
  int max_global_ba_keyframes = 40;     // above this, global BA optimises only the newest ones
                                        // (bounds its cost on long runs: the corridor makes a
                                        // keyframe every ~0.15 m)

  void bind(OptionRegistry* registry, const std::string& section);
};

// Which keyframes a new keyframe's epipolar search pairs it with.
struct EpipolarPartnerOptions {
  // The partner: the farthest keyframe within this times the new keyframe's median depth
  // whose optical axis is within the angle (nearest if none is farther): with a keyframe
  // every few frames (forward motion, few points) the nearest gives no parallax [-, deg].
  double distance_ratio = 0.25;
  double max_angle_deg = 20.0;
  // Mono keyframes (no points from depth) search against this many partners: the one
  // above, then the other keyframes within the angle, nearest first; corners taken by an
  // earlier partner are not tried again [keyframes]. Measured on the corridor (900 frames):
  // 1 partner 899/900 posed, 0.054 % final; 2: 900/900, 0.072 %, and keyframe settings
  // that collapsed the scale with 1 partner (keyframe_policy.h) got through (0.09-0.18 %);
  // 3: 0.22 %.
  int partners_mono = 2;

  void bind(OptionRegistry* registry, const std::string& section);  // as epipolar_partner*
};

// Options of the mapper, bound in section "mapper" (bundle adjustment in
// "bundle_adjustment", its noise model in "noise"). Each part binds its own keys; the
// defaults are the parts' in-class ones.
struct MapperOptions {
  BaWindowOptions ba_windows;
  EpipolarPartnerOptions epipolar_partners;
  EpipolarOptions epipolar;     // points where there is no depth (epipolar_search.h)
  PatchMatchOptions matching;   // patch acceptance of epipolar search and re-finding
  RefindOptions refind;         // re-finding new points in the other keyframes
  CullOptions cull;             // map clean-up (map_maintenance.h)
  BaOptions ba;                 // use_depth only in mode depth-ba
  KeyframeBuildOptions keyframe_build;
  LoopClosureOptions loop_closure;  // sections loop_closure, place_recognition, pose_graph
  // Move a keyframe tracked against a map the mapper has since moved with its anchor
  // ("Anchor"); false: take every keyframe at its pose as it came (as before session 36).
  bool move_with_anchor = true;

  void bind(OptionRegistry* registry, const std::string& section = "mapper");
};

struct MapperResult {
  enum class Status {
    kIntegrated,   // the keyframe is in the map
    kBadKeyframe,  // unusable content (no image, wrong size, id already in the map):
                   // refused (error says why)
  };
  Status status = Status::kBadKeyframe;
  std::string error;
  int dropped_measurements = 0;  // measurements of points the map does not know
  int cross_part_measurements = 0;  // of points of another part of the map: dropped ("Parts")
  int epipolar_points = 0;       // points added by epipolar search
  double anchor_moved_m = 0.0;    // how far the keyframe was moved with its anchor ("Anchor") [m]
  double anchor_moved_deg = 0.0;  // ...and turned [deg]
  bool anchor_missing = false;    // its anchor is in neither the map nor the culls' record, or not in its part: taken as it came
  bool anchor_stand_in = false;   // its anchor was culled: moved with the keyframe that stood in for it ("Anchor")
  bool anchor_refused = false;    // the anchor's move would put it beyond the world: taken as it came
  double integrate_ms = 0.0, local_ba_ms = 0.0;
  LoopClosureResult loop;        // the loop closer's verdict on this keyframe
};

const char* toString(MapperResult::Status status);

struct MapParts {
  long started = 0;  // keyframes that started a part (keyframe 0 not counted)
  long joined = 0;   // parts the loop closer joined to another
  int now = 0;       // parts in the map now (1: one connected map)
};

// What the keyframes' anchors did (MapperResult::anchor_*), counted over the run.
struct AnchorCounts {
  long placed = 0;    // placed through their anchor (moved by what it moved since, maybe nothing)
  long stand_in = 0;  // ...of which through a culled anchor's stand-in
  long missing = 0;   // anchor in no record or in another part: taken as they came
  long refused = 0;   // the move would leave the world: taken as they came
};

class Mapper {
 public:
  Mapper(const PinholeCamera& camera, const MapperOptions& options, SlamMode mode);
  ~Mapper();
  MapperResult addKeyframe(const KeyframeData& keyframe, const std::atomic<bool>* interrupt = nullptr);
  void load(const LoadedMap& loaded);
  bool refine(const std::atomic<bool>* interrupt = nullptr);
  MapChanges takeChanges();
  const Map& map() const;
  const LoopClosureCounters& loopClosures() const;
  const std::vector<LoopClosureResult>& loopsRecognised() const;  // LoopCloser::recognised()
  long keyframesCulled() const;  // redundant keyframes removed so far
  MapParts parts() const;
  const AnchorCounts& anchors() const;
  KeyframesKept keyframesKept() const;  // why the map's keyframes stay (map_maintenance.h)
  // Removes the keyframes as culling would, unjudged (a restart repeating its journal's culls).
  void removeKeyframes(const std::vector<KeyframeId>& ids);

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rgbdslam
