#include "rgbd-mapper/mapper_node.h"

#include <cstdio>
#include <iostream>
#include <string>

#include "common/lcm_conversions.h"
#include "common/process.h"

namespace rgbdslam {
namespace {

constexpr int kLcmTimeoutMs = 10;          // [ms] outbox flush period when nothing arrives
constexpr auto kWorkerTick = std::chrono::milliseconds(50);  // worker wake-up when idle
constexpr double kLogAnchorMoveM = 0.1;    // a keyframe moved with its anchor further is logged [m]...
constexpr double kLogAnchorTurnDeg = 5.0;  // ...or turned further [deg]

int64_t steadyNowUs() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
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
    : lcm_(lcm), options_(std::move(options)), mapper_(camera, mapper_options, mode) {}

MapperNode::~MapperNode() {
  if (worker_.joinable()) {
    stopping_ = true;
    sync_->stop();
    worker_.join();
  }
}

Status MapperNode::restore(const LoadedMap* start_map, int64_t map_id) {
  MapJournal::Contents contents;
  if (!options_.state_dir.empty()) {
    auto journal = MapJournal::open(options_.state_dir, &contents);
    if (!journal) return Error{journal.error()};
    journal_.emplace(std::move(*journal));
    if (!contents.warning.empty()) std::cerr << "rgbd-mapper: warning: " << contents.warning << "\n";
  }
  sync_ = std::make_unique<MapperSync>(&mapper_, options_.sync, journal_ ? &*journal_ : nullptr);
  if (start_map) {
    mapper_.load(*start_map);
    sync_->adopt(map_id, start_map->nextKeyframeId());
  }
  std::vector<IncomingKeyframe> journaled;
  for (auto& bytes : contents.keyframes) {
    auto msg = decodeMessage<rgbdslam::keyframe_t>(bytes.data(), bytes.size());
    auto keyframe = msg ? fromLcm(*msg) : Expected<KeyframeData>(Error{msg.error()});
    if (!keyframe) return Error{journal_->path() + ": a journaled keyframe does not decode: " + keyframe.error()};
    journaled.push_back(IncomingKeyframe{std::move(*keyframe), std::move(bytes)});
  }
  // No refinement here: the restored map is published at once (a snapshot), and the worker
  // refines it afterwards like any other (a tracker waits for it meanwhile).
  if (Status s = sync_->restore(journaled, contents.last_version, contents.culled); !s) {
    const bool continues_a_file = !start_map && !journaled.empty() && journaled.front().keyframe.id > 0;
    return Error{journal_->path() + ": " + s.error() +
                 (continues_a_file ? " (if this map started from a file: restart with the same --load-map and --map-id)" : "")};
  }
  if (!journaled.empty()) {
    std::cerr << "rgbd-mapper: restored map " << sync_->mapId() << " from " << journal_->path() << ": "
              << journaled.size() << " keyframes (" << contents.culled.size() << " culled since), " << mapper_.map().numPoints()
              << " points; publishing from version " << sync_->version() + 1 << "\n";
  }
  return Status{};
}

void MapperNode::run(const std::atomic<bool>& stop) {
  auto keyframes = subscribeRaw(lcm_, options_.channels.keyframe, this, &MapperNode::onKeyframe);
  auto receipts = subscribeRaw(lcm_, options_.channels.receipt, this, &MapperNode::onReceipt);
  worker_ = std::thread([this] { workerLoop(); });
  while (!stop) {
    lcm_->handleTimeout(kLcmTimeoutMs);
    flushOutbox();
  }
  stopping_ = true;
  sync_->stop();
  worker_.join();
}

void MapperNode::onKeyframe(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
  ++received_;
  auto msg = decodeMessage<rgbdslam::keyframe_t>(buffer->data, buffer->data_size);
  auto keyframe = msg ? fromLcm(*msg) : Expected<KeyframeData>(Error{msg.error()});
  if (!keyframe) {
    ++bad_messages_;
    std::cerr << "rgbd-mapper: ignoring a bad message on " << channel << ": " << keyframe.error() << "\n";
    return;
  }
  const auto* bytes = static_cast<const uint8_t*>(buffer->data);
  const KeyframeId id = keyframe->id;
  const int64_t map_id = keyframe->map_id;
  const IntakeVerdict verdict = sync_->offer(
      IncomingKeyframe{std::move(*keyframe), std::vector<uint8_t>(bytes, bytes + buffer->data_size)});
  if (verdict == IntakeVerdict::kForeignMap) {
    std::cerr << "rgbd-mapper: ignoring keyframe " << id << " of map " << map_id << ": this mapper holds map "
              << sync_->mapId() << " (restart it with --fresh for a new map)\n";
  }
}

void MapperNode::onReceipt(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
  auto msg = decodeMessage<rgbdslam::map_receipt_t>(buffer->data, buffer->data_size);
  auto receipt = msg ? fromLcm(*msg) : Expected<MapReceipt>(Error{msg.error()});
  if (!receipt) {
    ++bad_receipts_;
    std::cerr << "rgbd-mapper: ignoring a bad message on " << channel << ": " << receipt.error() << "\n";
    return;
  }
  if (sync_->onReceipt(*receipt) == ReceiptVerdict::kImplausible) {
    std::cerr << "rgbd-mapper: a receipt claims map version " << receipt->applied_version << " (newest seen "
              << receipt->newest_version_seen << "), this mapper published " << sync_->version() << "; ignored\n";
  }
}

void MapperNode::workerLoop() {
  auto last_status = std::chrono::steady_clock::time_point{};
  while (!stopping_) {
    const bool work = sync_->waitForWork(kWorkerTick);
    if (work) {
      const auto start = std::chrono::steady_clock::now();
      if (auto step = sync_->integrateNext()) {
        state_ = "integrating";
        if (step->result.status != MapperResult::Status::kIntegrated) {
          std::cerr << "rgbd-mapper: keyframe " << step->id << " refused: " << step->result.error << "\n";
        }
        if (step->result.anchor_moved_m > kLogAnchorMoveM || step->result.anchor_moved_deg > kLogAnchorTurnDeg) {
          std::cerr << "rgbd-mapper: keyframe " << step->id << " came " << step->result.anchor_moved_m << " m, "
                    << step->result.anchor_moved_deg << " deg off the map: moved with its anchor keyframe"
                    << (step->result.anchor_stand_in ? " (culled: with the keyframe that stood in for it)" : "") << "\n";
        }
        if (step->result.anchor_missing || step->result.anchor_refused) {
          std::cerr << "rgbd-mapper: keyframe " << step->id << " taken at its pose as it came: its anchor keyframe is "
                    << (step->result.anchor_refused ? "beyond the world bound when moved" : "not in the map or its part")
                    << "\n";
        }
        const std::string loop = describe(step->result.loop);
        // One write: scripts/lib/loop_audit.py parses the line, which another thread's output must not cut.
        if (!loop.empty()) std::cerr << "rgbd-mapper: keyframe " + std::to_string(step->id) + ": " + loop + "\n";
        if (!step->journal_error.empty()) {
          std::cerr << "rgbd-mapper: error: " << step->journal_error << " (the map is not persisted)\n";
        }
        integrate_ms_.add(step->result.integrate_ms);
        local_ba_ms_.add(step->result.local_ba_ms);
      } else {
        state_ = "refining";
        sync_->refine();
        refine_ms_.add(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
      }
    } else {
      state_ = sync_->mapId() == 0 ? "waiting" : "idle";
    }
    publish(steadyNowUs());
    const auto now = std::chrono::steady_clock::now();
    if (now - last_status >= std::chrono::duration<double>(options_.process.status_period_s)) {
      last_status = now;
      publishStatus();
    }
  }
}

void MapperNode::publish(int64_t now_us) {
  std::string journal_error;
  std::optional<MapUpdate> update = sync_->publishDue(now_us, &journal_error);
  if (!journal_error.empty()) std::cerr << "rgbd-mapper: error: " << journal_error << "\n";
  if (!update) return;
  update->utime = utimeNow();
  std::vector<uint8_t> bytes = encodeToBytes(toLcm(*update));
  map_bytes_ += static_cast<long>(bytes.size());
  post(options_.channels.map, std::move(bytes));
}

void MapperNode::publishStatus() {
  const MapperSync::Counters c = sync_->counters();
  const MemoryUsage memory = memoryUsage();
  ComponentStatus status;
  status.utime = utimeNow();
  status.component = "rgbd-mapper";
  status.state = state_;
  status.counters = {{"map_id", sync_->mapId()},
                     {"map_version", sync_->version()},
                     {"keyframes", static_cast<int64_t>(mapper_.map().numKeyframes())},
                     {"keyframes_culled", mapper_.keyframesCulled()},
                     {"points", static_cast<int64_t>(mapper_.map().numPoints())},
                     {"keyframes_received", received_.load()},
                     {"keyframes_integrated", c.integrated},
                     {"keyframes_restored", c.restored},
                     {"keyframes_queued", static_cast<int64_t>(sync_->queueLength())},
                     {"duplicates", c.duplicates},
                     {"out_of_order", c.out_of_order},
                     {"foreign_map_keyframes", c.foreign},
                     {"bad_messages", bad_messages_.load()},
                     {"bad_keyframes", c.refused},
                     {"dropped_queue_full", c.dropped_queue_full},
                     {"maps_published", c.maps_published},
                     {"snapshots_published", c.snapshots_published},
                     {"snapshots_requested", c.snapshots_asked},
                     {"snapshots_skipped", c.snapshots_skipped},
                     {"bad_receipts", bad_receipts_.load()},
                     {"receipts_implausible", c.receipts_implausible},
                     {"versions_caught_up", c.versions_caught_up},
                     {"keyframes_skipped", c.keyframes_skipped},
                     {"map_bytes", map_bytes_.load()},
                     {"journal_errors", c.journal_errors},
                     {"rss_kb", memory.rss_kb},
                     {"peak_rss_kb", memory.peak_rss_kb},
                     {"heap_kb", memory.heap_kb}};
  status.timings_ms = {{"integrate_ms_median", integrate_ms_.quantile(0.5)},
                       {"local_ba_ms_median", local_ba_ms_.quantile(0.5)},
                       {"local_ba_ms_max", local_ba_ms_.quantile(1.0)},
                       {"refine_ms_median", refine_ms_.quantile(0.5)},
                       {"refine_ms_max", refine_ms_.quantile(1.0)}};
  post(options_.channels.mapper_status, encodeToBytes(toLcm(status)));
}

void MapperNode::post(const std::string& channel, std::vector<uint8_t> bytes) {
  std::lock_guard<std::mutex> lock(outbox_mutex_);
  outbox_.emplace_back(channel, std::move(bytes));
}

void MapperNode::flushOutbox() {
  std::vector<std::pair<std::string, std::vector<uint8_t>>> out;
  {
    std::lock_guard<std::mutex> lock(outbox_mutex_);
    out.swap(outbox_);
  }
  for (const auto& [channel, bytes] : out) {
    lcm_->publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
  }
}

void MapperNode::printSummary() const {
  const MapperSync::Counters c = sync_->counters();
  std::cerr << "rgbd-mapper: map " << sync_->mapId() << " version " << sync_->version() << ": "
            << mapper_.map().numKeyframes() << " keyframes (" << c.restored << " restored, "
            << mapper_.keyframesCulled() << " culled), "
            << mapper_.map().numPoints() << " points; received " << received_ << ", duplicates "
            << c.duplicates << ", out of order " << c.out_of_order << ", foreign map " << c.foreign
            << ", bad messages " << bad_messages_ << ", bad keyframes " << c.refused << "; "
            << c.maps_published << " maps published (" << c.snapshots_published << " snapshots, "
            << c.snapshots_asked << " asked for by a stuck tracker, " << c.snapshots_skipped
            << " fallbacks skipped with the tracker in step, " << map_bytes_ << " bytes)";
  if (c.versions_caught_up > 0 || c.keyframes_skipped > 0) {
    std::cerr << "; the journal had lost versions (caught up with the tracker " << c.versions_caught_up
              << " times) and " << c.keyframes_skipped << " keyframes the tracker no longer held (skipped)";
  }
  std::cerr << "\n";
  printLoopClosures(mapper_.loopClosures());  // the worker has stopped
  printMapParts(mapper_.parts());
  printAnchors(mapper_.anchors());
  std::printf("keyframes_in_map %zu\nkeyframes_culled %ld\n", mapper_.map().numKeyframes(), mapper_.keyframesCulled());
  printKeyframesKept(mapper_.keyframesKept());
  printPeakRss();  // stdout, as the tracker's and rgbd-slam's summaries
  std::fflush(stdout);
}

}  // namespace rgbdslam
