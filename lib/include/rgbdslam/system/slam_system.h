#pragma once
// Tracker and mapper together in one process, joined by the same map protocol as over LCM
// (sync/: TrackerSync at the tracker, MapperSync at the mapper), so rgbd-slam exercises the
// code that flies.
//   Deterministic: time is the frames' own (utime); the link is an in-memory one
//   (sync/memory_link.h), perfect by default, or lossy and delayed as 'link' says (seeded,
//   so a lossy run is repeatable). Over a perfect link nothing is saved by holding changes
//   back, so the publisher sends every change at once (sync.map_period_s and the move
//   thresholds taken as 0; measured: room 1.42 mm, teddy 5.70 mm, against 1.54 / 5.99 mm with
//   the radio link's 1 s and 1 mm); a simulated imperfect link uses the configured values,
//   as rgbd-mapper does. Before each frame the tracker takes the map messages due;
//   after it, the mapper takes the keyframes and receipts due, integrates every keyframe
//   that is next in order and refines until it has nothing left to do (bounded by
//   max_refine_steps), publishing as the protocol says. Two runs give the same trajectory.
//   Concurrent (default): the mapper runs in its own thread on the host's monotonic clock;
//   the link is perfect and so every change is sent at once, as above (keyframes and receipts handed to MapperSync, map messages through
//   a queue the tracker drains before each frame); a new keyframe interrupts refinement;
//   when keyframe_queue_length keyframes wait, the tracker waits for the mapper.
// Started from a map file (SlamStart): tracker and mapper load the same map before the first
//   frame (Tracker::load, Mapper::load) and the protocol continues after its keyframes. To
//   localise only, the tracker adds no keyframes and the mapper is not run: its map stays
//   the loaded one.
// What the link's codec does to a keyframe on its way to the mapper (SlamStart::keyframe_wire):
//   rgbd-tracker sends keyframes as JPEG grey and coarse depth (procs/common/link_budget.h);
//   the batch runner can pass every keyframe through the same encoding and decoding, so that
//   the map is built from what a ground station receives, deterministically.
// Call order: construct, process() per frame, finish() (waits for the mapper), then map().
#include <functional>
#include <memory>

#include "rgbdslam/mapping/mapper.h"
#include "rgbdslam/sync/memory_link.h"
#include "rgbdslam/sync/sync_options.h"
#include "rgbdslam/tracking/tracker.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

struct SlamOptions {
  std::string mode = "depth-ba";   // mono | depth-init | depth-ba (see slam_mode.h)
  int max_refine_steps = 8;        // deterministic mode: refine() calls per keyframe at most
  int keyframe_queue_length = 8;   // concurrent mode: keyframes waiting for the mapper at most
  TrackerOptions tracker;
  MapperOptions mapper;
  SyncOptions sync;

  void bind(OptionRegistry* registry);
};

// Where a run starts: a new map (default) or a loaded one.
struct SlamStart {
  const LoadedMap* map = nullptr;  // read during construction only
  bool localise_only = false;      // with a map: track in it, add nothing
  // Each keyframe as the mapper receives it (encoded and decoded as on the link); empty: the
  // tracker's keyframe itself. Called on the tracking thread, for first sends and re-sends.
  std::function<KeyframeData(const KeyframeData&)> keyframe_wire;
};

struct SlamStats {
  long frames = 0, keyframes = 0, lost_frames = 0, bad_frames = 0;
  long points = 0;                  // in the mapper's map at finish()
  long keyframe_sends = 0;          // first sends and re-sends
  long maps_applied = 0, maps_missing_delta = 0, maps_stale = 0;
  long snapshots = 0;               // published by the mapper
  long link_lost = 0;               // messages the simulated link lost (deterministic)
};

class SlamSystem {
 public:
  SlamSystem(const PinholeCamera& camera, const SlamOptions& options, bool deterministic,
             const LinkOptions& link = {}, const SlamStart& start = {});
  ~SlamSystem();
  TrackResult process(const RgbdFrame& frame);
  void finish();
  const Mapper& mapper() const;
  const Tracker& tracker() const;
  SlamStats stats() const;

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rgbdslam
