#include "rgbdslam/system/slam_system.h"

#include <chrono>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <optional>
#include <thread>

#include "rgbdslam/sync/mapper_sync.h"
#include "rgbdslam/sync/tracker_sync.h"

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
  sync.bind(registry);
}

namespace {

constexpr int64_t kMapId = 1;  // one process, one map
constexpr auto kWorkerTick = std::chrono::milliseconds(20);  // idle mapper: publication checks

int64_t steadyNowUs() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// In one process the mapper keeps no journal that could lose keyframes, and a retained
// keyframe here is a whole KeyframeData (images, about 1 MB): keep none.
KeyframeOutboxOptions withoutRetention(KeyframeOutboxOptions options) {
  options.retained = 0;
  return options;
}

}  // namespace

class SlamSystem::Impl {
 public:
  Impl(const PinholeCamera& camera, const SlamOptions& options, bool deterministic,
       const LinkOptions& link, const SlamStart& start)
      : options_(options), mode_(*parseSlamMode(options.mode)), deterministic_(deterministic),
        localise_only_(start.map && start.localise_only), keyframe_wire_(start.keyframe_wire),
        tracker_(camera, options.tracker, mode_, kMapId),
        tracker_sync_(kMapId, withoutRetention(options.sync.outbox)),
        mapper_(camera, options.mapper, mode_),
        mapper_sync_(&mapper_, mapperSyncOptions(options.sync.mapper, link)),
        keyframe_link_(link), map_link_(withSeed(link, 2)), receipt_link_(withSeed(link, 3)) {
    if (start.map) startFrom(*start.map);
    // Localising only, the mapper has nothing to do: it is not run at all, so its map stays
    // the loaded one whatever the refinement would find to improve.
    if (localise_only_) return;
    if (!deterministic_) worker_ = std::thread([this] { mapperLoop(); });
  }

  ~Impl() { finish(); }

  TrackResult process(const RgbdFrame& frame) {
    const int64_t now_us = clock(frame);
    receiveMaps(now_us);
    TrackResult result = tracker_.track(frame);
    ++stats_.frames;
    if (result.status == TrackResult::Status::kLost) ++stats_.lost_frames;
    if (result.status == TrackResult::Status::kBadFrame) ++stats_.bad_frames;
    if (result.new_keyframe) {
      ++stats_.keyframes;
      sendKeyframe(*result.new_keyframe, now_us);
      tracker_sync_.send(result.new_keyframe->id, *result.new_keyframe, now_us);  // shares the images
    }
    for (const KeyframeData* again : tracker_sync_.resendsDue(now_us)) sendKeyframe(*again, now_us);
    if (now_us - last_receipt_us_ >= static_cast<int64_t>(options_.sync.receipt_period_s * 1e6)) {
      last_receipt_us_ = now_us;
      sendReceipt(tracker_sync_.receipt(now_us), now_us);
    }
    if (deterministic_ && !localise_only_) runMapper(now_us);
    return result;
  }

  void finish() {
    if (worker_.joinable()) {
      finishing_ = true;
      worker_.join();
      receiveMaps(steadyNowUs());
    }
    stats_.points = static_cast<long>(mapper_.map().numPoints());
    const auto counters = mapper_sync_.counters();
    stats_.snapshots = counters.snapshots_published;
    stats_.link_lost = keyframe_link_.lost() + map_link_.lost() + receipt_link_.lost();
  }

  const Mapper& mapper() const { return mapper_; }
  const Tracker& tracker() const { return tracker_; }
  SlamStats stats() const { return stats_; }

 private:
  // Over a perfect in-process link every change goes to the tracker at once.
  static MapperSyncOptions mapperSyncOptions(MapperSyncOptions options, const LinkOptions& link) {
    if (link.imperfect()) return options;
    options.publisher.map_period_s = 0.0;
    options.publisher.diff = MapDiffOptions{0.0, 0.0, 0.0};
    return options;
  }

  // Both ends from the same file, before the first frame: the mapper's map and the
  // tracker's replica agree, and keyframe ids (and so point ids) continue after the loaded.
  void startFrom(const LoadedMap& map) {
    tracker_.load(map, !localise_only_);
    mapper_.load(map);
    mapper_sync_.adopt(kMapId, map.nextKeyframeId());
    tracker_sync_.startAfter(map.nextKeyframeId());
  }

  static LinkOptions withSeed(LinkOptions link, uint32_t offset) {
    link.seed += offset;  // each direction its own random stream
    return link;
  }

  int64_t clock(const RgbdFrame& frame) {
    if (!deterministic_) return steadyNowUs();
    sequence_now_us_ = std::max(sequence_now_us_, frame.utime);  // never backwards
    return sequence_now_us_;
  }

  // The tracker's end.
  void sendKeyframe(const KeyframeData& sent, int64_t now_us) {
    ++stats_.keyframe_sends;
    std::optional<KeyframeData> wired;  // through the link's codec (SlamStart::keyframe_wire)
    if (keyframe_wire_) wired = keyframe_wire_(sent);
    const KeyframeData& keyframe = wired ? *wired : sent;
    if (deterministic_) {
      keyframe_link_.send(keyframe, now_us);
      return;
    }
    {
      // Back-pressure: a mapper far behind makes the tracker wait rather than drop keyframes.
      std::unique_lock<std::mutex> lock(mutex_);
      while (static_cast<int>(mapper_sync_.queueLength()) >= options_.keyframe_queue_length) {
        space_.wait_for(lock, kWorkerTick);
      }
    }
    mapper_sync_.offer(IncomingKeyframe{keyframe, {}});
  }

  void sendReceipt(const MapReceipt& receipt, int64_t now_us) {
    if (deterministic_) receipt_link_.send(receipt, now_us);
    else mapper_sync_.onReceipt(receipt);
  }

  void receiveMaps(int64_t now_us) {
    std::vector<MapUpdate> updates;
    if (deterministic_) {
      updates = map_link_.receive(now_us);
    } else {
      std::lock_guard<std::mutex> lock(mutex_);
      updates.assign(std::make_move_iterator(published_.begin()), std::make_move_iterator(published_.end()));
      published_.clear();
    }
    for (const MapUpdate& update : updates) {
      const MapReceiveResult r = tracker_sync_.receive(
          update, now_us, [this](const MapUpdate& u) { return tracker_.applyMap(u); });
      if (r.applied) ++stats_.maps_applied;
      if (r.verdict == MapVerdict::kMissingDelta) ++stats_.maps_missing_delta;
      if (r.verdict == MapVerdict::kStale) ++stats_.maps_stale;
    }
  }

  // The mapper's end, deterministic: everything due, then refinement to convergence.
  void runMapper(int64_t now_us) {
    for (KeyframeData& keyframe : keyframe_link_.receive(now_us)) {
      mapper_sync_.offer(IncomingKeyframe{std::move(keyframe), {}});
    }
    for (const MapReceipt& receipt : receipt_link_.receive(now_us)) mapper_sync_.onReceipt(receipt);
    while (mapper_sync_.integrateNext()) publishDue(now_us);
    for (int i = 0; i < options_.max_refine_steps && mapper_sync_.refine(); ++i) publishDue(now_us);
    publishDue(now_us);
  }

  void publishDue(int64_t now_us) {
    std::optional<MapUpdate> update = mapper_sync_.publishDue(now_us);
    if (!update) return;
    if (deterministic_) {
      map_link_.send(*update, now_us);
      return;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    published_.push_back(std::move(*update));
  }

  // The mapper's end, concurrent: integrate what is next, else refine, else wait.
  void mapperLoop() {
    for (;;) {
      const bool work = mapper_sync_.waitForWork(kWorkerTick);
      if (!work && finishing_) break;
      if (mapper_sync_.integrateNext()) {
        { std::lock_guard<std::mutex> lock(mutex_); }  // the tracker waits or sees the queue
        space_.notify_all();
      } else {
        mapper_sync_.refine();
      }
      publishDue(steadyNowUs());
    }
  }

  SlamOptions options_;
  SlamMode mode_;
  bool deterministic_;
  bool localise_only_;
  std::function<KeyframeData(const KeyframeData&)> keyframe_wire_;  // SlamStart::keyframe_wire
  Tracker tracker_;
  TrackerSync<KeyframeData> tracker_sync_;
  Mapper mapper_;
  MapperSync mapper_sync_;
  // Deterministic mode's link, one per direction and kind.
  MemoryLink<KeyframeData> keyframe_link_;
  MemoryLink<MapUpdate> map_link_;
  MemoryLink<MapReceipt> receipt_link_;
  int64_t sequence_now_us_ = 0;
  int64_t last_receipt_us_ = 0;
  SlamStats stats_;

  // Concurrent mode.
  std::mutex mutex_;
  std::condition_variable space_;
  std::deque<MapUpdate> published_;  // guarded by mutex_
  std::atomic<bool> finishing_{false};
  std::thread worker_;
};

SlamSystem::SlamSystem(const PinholeCamera& camera, const SlamOptions& options, bool deterministic,
                       const LinkOptions& link, const SlamStart& start)
    : impl_(std::make_unique<Impl>(camera, options, deterministic, link, start)) {}
SlamSystem::~SlamSystem() = default;
TrackResult SlamSystem::process(const RgbdFrame& frame) { return impl_->process(frame); }
void SlamSystem::finish() { impl_->finish(); }
const Mapper& SlamSystem::mapper() const { return impl_->mapper(); }
const Tracker& SlamSystem::tracker() const { return impl_->tracker(); }
SlamStats SlamSystem::stats() const { return impl_->stats(); }

}  // namespace rgbdslam
