#include "rgbd-mapper/mapper_node.h"

#include <iostream>

#include "common/lcm_conversions.h"
#include "common/process.h"

namespace rgbdslam {
namespace {

constexpr int kLcmTimeoutMs = 10;          // [ms] outbox flush period when nothing arrives
constexpr auto kWorkerTick = std::chrono::milliseconds(50);  // worker wake-up when idle

double msBetween(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

bool elapsed(std::chrono::steady_clock::time_point since, std::chrono::steady_clock::time_point now,
             double seconds) {
  return since == std::chrono::steady_clock::time_point{} || msBetween(since, now) >= seconds * 1000.0;
}

template <typename T>
std::vector<uint8_t> encodeToBytes(const T& msg) {
  std::vector<uint8_t> bytes(msg.getEncodedSize());
  msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

}  // namespace

MapperNode::MapperNode(lcm::LCM* lcm, const PinholeCamera& camera, const MapperOptions& mapper_options,
                       SlamMode mode, MapperNodeOptions options)
    : lcm_(lcm), options_(std::move(options)), mapper_(camera, mapper_options, mode),
      differ_(options_.diff) {}

MapperNode::~MapperNode() {
  if (worker_.joinable()) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
    }
    wake_.notify_all();
    worker_.join();
  }
}

Status MapperNode::restore() {
  if (options_.state_dir.empty()) return Status{};
  MapJournal::Contents contents;
  auto journal = MapJournal::open(options_.state_dir, &contents);
  if (!journal) return Error{journal.error()};
  journal_.emplace(std::move(*journal));
  if (!contents.warning.empty()) std::cerr << "rgbd-mapper: warning: " << contents.warning << "\n";
  for (const auto& bytes : contents.keyframes) {
    auto msg = decodeMessage<rgbdslam::keyframe_t>(bytes.data(), bytes.size());
    auto keyframe = msg ? fromLcm(*msg) : Expected<KeyframeData>(Error{msg.error()});
    if (!keyframe) return Error{journal_->path() + ": a journaled keyframe does not decode: " + keyframe.error()};
    MapperResult result = mapper_.addKeyframe(*keyframe);
    if (result.status != MapperResult::Status::kIntegrated) {
      return Error{journal_->path() + ": journaled keyframe " + std::to_string(keyframe->id) +
                   " was not integrated: " + toString(result.status) + " " + result.error};
    }
    map_id_ = keyframe->map_id;
    next_id_ = keyframe->id + 1;
    ++counters_.restored;
  }
  // No refinement here: the restored map is published at once, and the worker refines it
  // afterwards like any other (a tracker waits for it meanwhile).
  version_ = contents.last_version;
  published_version_ = version_;
  converged_ = counters_.restored == 0;
  counters_.integrated = counters_.restored.load();
  if (counters_.restored > 0) {
    std::cerr << "rgbd-mapper: restored map " << map_id_ << " from " << journal_->path() << ": "
              << counters_.restored << " keyframes, " << mapper_.map().numPoints()
              << " points; publishing from version " << version_ + 1 << "\n";
  }
  return Status{};
}

void MapperNode::run(const std::atomic<bool>& stop) {
  auto keyframes = subscribeRaw(lcm_, options_.keyframe_channel, this, &MapperNode::onKeyframe);
  auto tracker_status = subscribeRaw(lcm_, options_.tracker_status_channel, this, &MapperNode::onTrackerStatus);
  worker_ = std::thread([this] { workerLoop(); });
  while (!stop) {
    lcm_->handleTimeout(kLcmTimeoutMs);
    flushOutbox();
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  interrupt_ = true;
  wake_.notify_all();
  worker_.join();
}

void MapperNode::onKeyframe(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
  ++counters_.received;
  auto msg = decodeMessage<rgbdslam::keyframe_t>(buffer->data, buffer->data_size);
  auto keyframe = msg ? fromLcm(*msg) : Expected<KeyframeData>(Error{msg.error()});
  if (!keyframe) {
    ++counters_.bad_messages;
    std::cerr << "rgbd-mapper: ignoring a bad message on " << channel << ": " << keyframe.error() << "\n";
    return;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (map_id_ != 0 && keyframe->map_id != map_id_) {
    ++counters_.foreign;
    std::cerr << "rgbd-mapper: ignoring keyframe " << keyframe->id << " of map " << keyframe->map_id
              << ": this mapper holds map " << map_id_ << " (restart it with --fresh for a new map)\n";
    return;
  }
  if (keyframe->id < next_id_ || queue_.count(keyframe->id)) {
    ++counters_.duplicates;
    ack_due_ = true;  // the acknowledgement was probably lost: send it again
    return;
  }
  if (keyframe->id > next_id_) ++counters_.out_of_order;
  if (static_cast<int>(queue_.size()) >= options_.max_queued_keyframes) {
    ++counters_.dropped_queue_full;  // the tracker re-sends it
    return;
  }
  const auto* bytes = static_cast<const uint8_t*>(buffer->data);
  queue_[keyframe->id] = Queued{std::move(*keyframe), std::vector<uint8_t>(bytes, bytes + buffer->data_size)};
  if (queue_.count(next_id_)) {
    interrupt_ = true;
    wake_.notify_all();
  }
}

void MapperNode::onTrackerStatus(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
  auto msg = decodeMessage<rgbdslam::status_t>(buffer->data, buffer->data_size);
  auto status = msg ? fromLcm(*msg) : Expected<ComponentStatus>(Error{msg.error()});
  if (!status) {
    ++counters_.bad_status_messages;
    std::cerr << "rgbd-mapper: ignoring a bad message on " << channel << ": " << status.error() << "\n";
    return;
  }
  if (status->component != "rgbd-tracker") return;
  std::optional<int64_t> map_id, version;
  for (const auto& [name, value] : status->counters) {
    if (name == "map_id") map_id = value;
    if (name == "map_version") version = value;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (!map_id || !version || *map_id != map_id_) return;
  if (*version < published_version_ && *version == tracker_version_ && !snapshot_requested_) {
    snapshot_requested_ = true;
    ++counters_.snapshots_requested;
  }
  tracker_version_ = *version;
}

void MapperNode::workerLoop() {
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      if (stopping_) return;
      if (converged_ && !queue_.count(next_id_)) {
        state_ = map_id_ == 0 ? "waiting" : "idle";
        wake_.wait_for(lock, kWorkerTick, [this] { return stopping_ || queue_.count(next_id_) > 0; });
      }
      if (stopping_) return;
    }
    if (!integrateNext() && !converged_) {
      state_ = "refining";
      const auto start = Clock::now();
      const bool changed = mapper_.refine(&interrupt_).has_value();
      refine_ms_.add(msBetween(start, Clock::now()));
      dirty_ = dirty_ || changed;
      converged_ = !changed && !interrupt_;
    }
    const auto now = Clock::now();
    publishIfDue(now);
    if (elapsed(last_status_, now, options_.status_period_s)) {
      last_status_ = now;
      publishStatus();
    }
  }
}

bool MapperNode::integrateNext() {
  Queued queued;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = queue_.find(next_id_);
    if (it == queue_.end()) return false;
    queued = std::move(it->second);
    queue_.erase(it);
    interrupt_ = false;
  }
  state_ = "integrating";
  MapperResult result = mapper_.addKeyframe(queued.keyframe, &interrupt_);
  if (result.status != MapperResult::Status::kIntegrated) {
    ++counters_.bad_keyframes;
    std::cerr << "rgbd-mapper: keyframe " << queued.keyframe.id << " refused: " << toString(result.status)
              << " " << result.error << "\n";
    return true;
  }
  if (journal_) {
    if (Status s = journal_->appendKeyframe(queued.bytes.data(), queued.bytes.size()); !s) {
      ++counters_.journal_errors;
      std::cerr << "rgbd-mapper: error: " << s.error() << " (the map is not persisted)\n";
    }
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    map_id_ = queued.keyframe.map_id;
    next_id_ = queued.keyframe.id + 1;
    // Keyframes queued from before a gap that is now closed stay queued; older ones are gone,
    // and so are keyframes of another map that arrived before this map had a name.
    queue_.erase(queue_.begin(), queue_.lower_bound(next_id_));
    for (auto it = queue_.begin(); it != queue_.end();) {
      if (it->second.keyframe.map_id == map_id_) {
        ++it;
        continue;
      }
      ++counters_.foreign;
      std::cerr << "rgbd-mapper: dropping keyframe " << it->first << " of map " << it->second.keyframe.map_id
                << ": this mapper holds map " << map_id_ << "\n";
      it = queue_.erase(it);
    }
  }
  ++counters_.integrated;
  integrate_ms_.add(result.integrate_ms);
  local_ba_ms_.add(result.local_ba_ms);
  dirty_ = true;
  integrated_unpublished_ = true;
  converged_ = false;
  return true;
}

void MapperNode::publishIfDue(Clock::time_point now) {
  int64_t map_id;
  KeyframeId next_id;
  bool ack_due, requested;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    map_id = map_id_, next_id = next_id_, ack_due = ack_due_, requested = snapshot_requested_;
  }
  if (map_id == 0) return;  // no map yet
  const bool snapshot = snapshot_due_ || requested || elapsed(last_snapshot_, now, options_.snapshot_period_s);
  // A newly integrated keyframe is published at once (its acknowledgement stops the
  // tracker's re-sends); refinement results at most every map_period_s.
  const bool urgent = integrated_unpublished_;
  if (!snapshot && !urgent && !((dirty_ || ack_due) && elapsed(last_publish_, now, options_.map_period_s))) return;
  MapUpdate update = snapshot ? differ_.snapshot(mapper_.map()) : differ_.delta(mapper_.map());
  update.map_id = map_id;
  update.version = version_ + 1;
  update.utime = utimeNow();
  for (KeyframeId id = 0; id < next_id; ++id) update.acked_keyframes.push_back(id);
  // The version is journaled before it is published, so a restarted mapper never re-uses it.
  if (journal_) {
    if (Status s = journal_->appendVersion(update.version); !s) {
      ++counters_.journal_errors;
      std::cerr << "rgbd-mapper: error: " << s.error() << "\n";
    }
  }
  std::vector<uint8_t> bytes = encodeToBytes(toLcm(update));
  counters_.map_bytes += static_cast<long>(bytes.size());
  post(options_.map_channel, std::move(bytes));
  version_ = update.version;
  ++counters_.maps_published;
  if (snapshot) {
    ++counters_.snapshots_published;
    last_snapshot_ = now;
    snapshot_due_ = false;
  }
  last_publish_ = now;
  dirty_ = false;
  integrated_unpublished_ = false;
  std::lock_guard<std::mutex> lock(mutex_);
  ack_due_ = false;
  published_version_ = version_;
  if (snapshot) {
    snapshot_requested_ = false;
    tracker_version_ = -1;  // judge the tracker again from its next two reports
  }
}

void MapperNode::publishStatus() {
  ComponentStatus status;
  status.utime = utimeNow();
  status.component = "rgbd-mapper";
  status.state = state_;
  long queued;
  int64_t map_id;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    queued = static_cast<long>(queue_.size());
    map_id = map_id_;
  }
  const Counters& c = counters_;
  status.counters = {{"map_id", map_id},
                     {"map_version", version_},
                     {"keyframes", static_cast<int64_t>(mapper_.map().numKeyframes())},
                     {"points", static_cast<int64_t>(mapper_.map().numPoints())},
                     {"keyframes_received", c.received},
                     {"keyframes_integrated", c.integrated},
                     {"keyframes_restored", c.restored},
                     {"keyframes_queued", queued},
                     {"duplicates", c.duplicates},
                     {"out_of_order", c.out_of_order},
                     {"foreign_map_keyframes", c.foreign},
                     {"bad_messages", c.bad_messages},
                     {"bad_keyframes", c.bad_keyframes},
                     {"dropped_queue_full", c.dropped_queue_full},
                     {"maps_published", c.maps_published},
                     {"snapshots_published", c.snapshots_published},
                     {"snapshots_requested", c.snapshots_requested},
                     {"bad_status_messages", c.bad_status_messages},
                     {"map_bytes", c.map_bytes},
                     {"journal_errors", c.journal_errors}};
  status.timings_ms = {{"integrate_ms_median", integrate_ms_.quantile(0.5)},
                       {"local_ba_ms_median", local_ba_ms_.quantile(0.5)},
                       {"local_ba_ms_max", local_ba_ms_.quantile(1.0)},
                       {"refine_ms_median", refine_ms_.quantile(0.5)},
                       {"refine_ms_max", refine_ms_.quantile(1.0)}};
  post(options_.status_channel, encodeToBytes(toLcm(status)));
}

void MapperNode::post(const std::string& channel, std::vector<uint8_t> bytes) {
  std::lock_guard<std::mutex> lock(mutex_);
  outbox_.emplace_back(channel, std::move(bytes));
}

void MapperNode::flushOutbox() {
  std::vector<std::pair<std::string, std::vector<uint8_t>>> out;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    out.swap(outbox_);
  }
  for (const auto& [channel, bytes] : out) {
    lcm_->publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
  }
}

void MapperNode::printSummary() const {
  const Counters& c = counters_;
  std::cerr << "rgbd-mapper: map " << map_id_ << " version " << version_ << ": "
            << mapper_.map().numKeyframes() << " keyframes (" << c.restored << " restored), "
            << mapper_.map().numPoints() << " points; received " << c.received << ", duplicates "
            << c.duplicates << ", out of order " << c.out_of_order << ", foreign map " << c.foreign
            << ", bad messages " << c.bad_messages << ", bad keyframes " << c.bad_keyframes << "; "
            << c.maps_published << " maps published (" << c.snapshots_published << " snapshots, "
            << c.snapshots_requested << " asked for by a stuck tracker, "
            << c.map_bytes << " bytes)\n";
}

}  // namespace rgbdslam
