#include "rgbdslam/system/slam_system.h"

#include <condition_variable>
#include <deque>
#include <mutex>
#include <random>
#include <thread>

namespace rgbdslam {

void SlamOptions::bind(OptionRegistry* registry) {
  registry->bind("slam", "mode", &mode, {"mono", "depth-init", "depth-ba"},
                 "how depth is used: first frame only, new points, or also bundle adjustment");
  registry->bind("slam", "max_refine_steps", &max_refine_steps, 0, 1000, "calls",
                 "deterministic mode: mapper refinement steps after each keyframe at most");
  registry->bind("slam", "keyframe_queue_length", &keyframe_queue_length, 1, 1000, "keyframes",
                 "concurrent mode: keyframes waiting for the mapper at most");
  tracker.bind(registry);
  mapper.bind(registry);
}

class SlamSystem::Impl {
 public:
  Impl(const PinholeCamera& camera, const SlamOptions& options, bool deterministic)
      : options_(options), mode_(*parseSlamMode(options.mode)), deterministic_(deterministic),
        tracker_(camera, options.tracker, mode_, /*map_id=*/1),
        mapper_(camera, options.mapper, mode_) {
    if (!deterministic_) worker_ = std::thread([this] { mapperLoop(); });
  }

  ~Impl() { finish(); }

  TrackResult process(const RgbdFrame& frame) {
    applyPendingUpdates();
    TrackResult result = tracker_.track(frame);
    ++stats_.frames;
    if (result.status == TrackResult::Status::kLost) ++stats_.lost_frames;
    if (result.status == TrackResult::Status::kBadFrame) ++stats_.bad_frames;
    if (result.new_keyframe) {
      ++stats_.keyframes;
      if (deterministic_) integrateNow(*result.new_keyframe);
      else enqueue(*result.new_keyframe);
    }
    return result;
  }

  void finish() {
    if (worker_.joinable()) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        stopping_ = true;
      }
      wake_.notify_all();
      worker_.join();
      applyPendingUpdates();
    }
    stats_.points = static_cast<long>(mapper_.map().numPoints());
  }

  const Mapper& mapper() const { return mapper_; }
  const Tracker& tracker() const { return tracker_; }
  SlamStats stats() const { return stats_; }

 private:
  void integrateNow(const KeyframeData& keyframe) {
    MapperResult added = mapper_.addKeyframe(keyframe);
    apply(added.update);
    for (int i = 0; i < options_.max_refine_steps; ++i) {
      std::optional<MapUpdate> update = mapper_.refine();
      if (!update) break;
      apply(*update);
    }
  }

  void apply(const MapUpdate& update) {
    tracker_.applyMapUpdate(update);
    ++stats_.map_updates;
  }

  // Concurrent mode: the tracker side.
  void enqueue(const KeyframeData& keyframe) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      // A full queue means the mapper is far behind: wait for it rather than drop a keyframe
      // (the map must not lose keyframes the tracker already built points on).
      space_.wait(lock, [this] { return static_cast<int>(queue_.size()) < options_.keyframe_queue_length; });
      queue_.push_back(keyframe);
    }
    interrupt_ = true;
    wake_.notify_all();
  }

  void applyPendingUpdates() {
    std::deque<MapUpdate> updates;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      updates.swap(updates_);
    }
    for (const auto& update : updates) apply(update);
  }

  // Concurrent mode: the mapper thread. Integrates queued keyframes first, refines otherwise.
  void mapperLoop() {
    bool idle = false;
    for (;;) {
      std::optional<KeyframeData> keyframe;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [&] { return stopping_ || !queue_.empty() || !idle; });
        if (!queue_.empty()) {
          keyframe = std::move(queue_.front());
          queue_.pop_front();
          interrupt_ = !queue_.empty();
        } else if (stopping_ && idle) {
          return;
        }
      }
      space_.notify_all();
      if (keyframe) {
        publish(mapper_.addKeyframe(*keyframe, &interrupt_).update);
        idle = false;
        continue;
      }
      std::optional<MapUpdate> update = mapper_.refine(&interrupt_);
      if (update) publish(*update);
      idle = !update;
    }
  }

  void publish(const MapUpdate& update) {
    std::lock_guard<std::mutex> lock(mutex_);
    updates_.push_back(update);
  }

  SlamOptions options_;
  SlamMode mode_;
  bool deterministic_;
  Tracker tracker_;
  Mapper mapper_;
  SlamStats stats_;

  std::mutex mutex_;
  std::condition_variable wake_, space_;
  std::deque<KeyframeData> queue_;   // guarded by mutex_
  std::deque<MapUpdate> updates_;    // guarded by mutex_
  bool stopping_ = false;            // guarded by mutex_
  std::atomic<bool> interrupt_{false};
  std::thread worker_;
};

SlamSystem::SlamSystem(const PinholeCamera& camera, const SlamOptions& options, bool deterministic)
    : impl_(std::make_unique<Impl>(camera, options, deterministic)) {}
SlamSystem::~SlamSystem() = default;
TrackResult SlamSystem::process(const RgbdFrame& frame) { return impl_->process(frame); }
void SlamSystem::finish() { impl_->finish(); }
const Mapper& SlamSystem::mapper() const { return impl_->mapper(); }
const Tracker& SlamSystem::tracker() const { return impl_->tracker(); }
SlamStats SlamSystem::stats() const { return impl_->stats(); }

}  // namespace rgbdslam
