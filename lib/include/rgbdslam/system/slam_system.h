#pragma once
// Tracker and mapper together in one process, speaking the same protocol as over LCM
// (KeyframeData one way, MapUpdate the other), so the batch runner and the distributed
// suite exercise the same code.
//   Deterministic: every keyframe is integrated and the mapper refines until it has nothing
//   left to do (bounded by max_refine_steps) before the next frame; two runs give the same
//   trajectory.
//   Concurrent (default): the mapper runs in its own thread behind a bounded queue of
//   keyframes; its map updates are applied by the tracker at the start of the next frame;
//   a new keyframe interrupts the mapper's background work.
// Call order: construct, process() per frame, finish() (waits for the mapper), then map().
#include <memory>

#include "rgbdslam/mapping/mapper.h"
#include "rgbdslam/tracking/tracker.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

struct SlamOptions {
  std::string mode = "depth-ba";   // mono | depth-init | depth-ba (see slam_mode.h)
  int max_refine_steps = 8;        // deterministic mode: refine() calls per keyframe at most
  int keyframe_queue_length = 8;   // concurrent mode: keyframes waiting for the mapper at most
  TrackerOptions tracker;
  MapperOptions mapper;

  void bind(OptionRegistry* registry);
};

struct SlamStats {
  long frames = 0, keyframes = 0, lost_frames = 0, bad_frames = 0, map_updates = 0;
  long points = 0;
};

class SlamSystem {
 public:
  SlamSystem(const PinholeCamera& camera, const SlamOptions& options, bool deterministic);
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
