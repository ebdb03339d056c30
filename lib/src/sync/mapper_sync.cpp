#include "rgbdslam/sync/mapper_sync.h"

#include <algorithm>

namespace rgbdslam {

const char* toString(IntakeVerdict verdict) {
  switch (verdict) {
    case IntakeVerdict::kQueued: return "queued";
    case IntakeVerdict::kDuplicate: return "duplicate";
    case IntakeVerdict::kForeignMap: return "foreign_map";
    case IntakeVerdict::kQueueFull: return "queue_full";
  }
  return "?";
}

MapperSync::MapperSync(Mapper* mapper, const MapperSyncOptions& options, KeyframeJournal* journal)
    : mapper_(mapper), options_(options), journal_(journal), publisher_(options.publisher) {}

Status MapperSync::restore(const std::vector<IncomingKeyframe>& journaled, int64_t last_version,
                           const std::vector<KeyframeId>& culled) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (const IncomingKeyframe& incoming : journaled) {
    const KeyframeData& kf = incoming.keyframe;
    if (kf.id < next_id_ || (map_id_ != 0 && kf.map_id != map_id_)) {
      return Error{"journaled keyframe " + std::to_string(kf.id) + " of map " +
                   std::to_string(kf.map_id) + " does not follow keyframe " +
                   std::to_string(next_id_ - 1) + " of map " + std::to_string(map_id_)};
    }
    const MapperResult result = mapper_->addKeyframe(kf);
    if (result.status != MapperResult::Status::kIntegrated) {
      return Error{"journaled keyframe " + std::to_string(kf.id) + " was not integrated: " +
                   result.error};
    }
    map_id_ = kf.map_id;
    next_id_ = kf.id + 1;
    ++counters_.restored;
  }
  mapper_->removeKeyframes(culled);
  mapper_->takeChanges();  // the first publication is a snapshot anyway
  if (map_id_ != 0) publisher_.start(map_id_, last_version);
  converged_ = counters_.restored == 0;
  return Status{};
}

IntakeVerdict MapperSync::offer(IncomingKeyframe incoming) {
  const KeyframeData& kf = incoming.keyframe;
  std::lock_guard<std::mutex> lock(mutex_);
  if (kf.map_id <= 0 || (map_id_ != 0 && kf.map_id != map_id_)) {
    ++counters_.foreign;
    return IntakeVerdict::kForeignMap;
  }
  if (kf.id < next_id_ || kf.id == integrating_ || queue_.count(kf.id)) {
    ++counters_.duplicates;
    publisher_.acknowledgementDue();  // the acknowledgement was probably lost
    return IntakeVerdict::kDuplicate;
  }
  if (static_cast<int>(queue_.size()) >= options_.max_queued_keyframes) {
    ++counters_.dropped_queue_full;
    return IntakeVerdict::kQueueFull;
  }
  if (kf.id > next_id_) ++counters_.out_of_order;
  ++counters_.queued;
  const KeyframeId id = kf.id;
  queue_[id] = std::move(incoming);
  if (nextReadyLocked()) {
    interrupt_ = true;
    wake_.notify_all();
  }
  return IntakeVerdict::kQueued;
}

ReceiptVerdict MapperSync::onReceipt(const MapReceipt& receipt) {
  std::lock_guard<std::mutex> lock(mutex_);
  skipUnsendableLocked(receipt);
  const ReceiptVerdict verdict = publisher_.onReceipt(receipt);
  if (verdict == ReceiptVerdict::kImplausible) ++counters_.receipts_implausible;
  if (verdict == ReceiptVerdict::kCaughtUp) ++counters_.versions_caught_up;
  return verdict;
}

// Only a keyframe of that map waiting here makes the receipt's claim believable: a forged
// receipt alone skips nothing.
void MapperSync::skipUnsendableLocked(const MapReceipt& receipt) {
  const KeyframeId from = receipt.keyframes_sendable_from;
  if (receipt.map_id <= 0 || from > receipt.keyframes_created || queue_.count(next_id_) || integrating_ >= 0) return;
  if (map_id_ == 0 && receipt.keyframes_created == 0) return;
  if (map_id_ != 0 && from <= next_id_) return;
  KeyframeId to = from;
  if (map_id_ == receipt.map_id) {
    if (!queue_.count(from)) return;  // the tracker sends it (again): wait for it
  } else if (map_id_ == 0) {
    // The whole journal is gone; a keyframe of that map waiting here vouches for the receipt.
    const auto it = std::find_if(queue_.lower_bound(from), queue_.end(), [&](const auto& entry) {
      return entry.second.keyframe.map_id == receipt.map_id;
    });
    if (it == queue_.end() || receipt.applied_version > MapFollower::kDefaultMaxVersionStep) return;
    map_id_ = receipt.map_id;
    dropForeignLocked();
    if (from == 0) {
      // The tracker still holds keyframe 0: an empty delta tells it to send its keyframes again.
      publisher_.startAfterLoss(map_id_, receipt.applied_version);
      return;
    }
    // Nobody can send the keyframes below 'from': the map starts again at the oldest
    // keyframe of that map waiting here; versions go on after the tracker's.
    to = it->first;
    publisher_.start(map_id_, std::max(receipt.applied_version, receipt.newest_version_seen));
  } else {
    return;
  }
  counters_.keyframes_skipped += to - next_id_;
  next_id_ = to;
  queue_.erase(queue_.begin(), queue_.lower_bound(next_id_));
  publisher_.acknowledgementDue();
  interrupt_ = true;
  wake_.notify_all();
}

// Keyframes queued before the map had a name that are of another map.
void MapperSync::dropForeignLocked() {
  for (auto it = queue_.begin(); it != queue_.end();) {
    if (it->second.keyframe.map_id == map_id_) {
      ++it;
      continue;
    }
    ++counters_.foreign;
    it = queue_.erase(it);
  }
}

std::optional<IntegrationStep> MapperSync::integrateNext() {
  IncomingKeyframe incoming;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = queue_.find(next_id_);
    if (it == queue_.end()) return std::nullopt;
    incoming = std::move(it->second);
    queue_.erase(it);
    integrating_ = next_id_;
    interrupt_ = false;
  }
  IntegrationStep step;
  step.id = incoming.keyframe.id;
  step.result = mapper_->addKeyframe(incoming.keyframe, &interrupt_);
  if (step.result.status != MapperResult::Status::kIntegrated) {
    std::lock_guard<std::mutex> lock(mutex_);
    integrating_ = -1;
    ++counters_.refused;  // the tracker's re-sends bring it again; nothing else is lost
    return step;
  }
  // Durable before it is acknowledged (by the next publication).
  if (journal_) {
    if (Status s = journal_->appendKeyframe(incoming); !s) step.journal_error = s.error();
  }
  MapChanges changes = takeChangesJournaled();  // before the lock: a journal write syncs the disk
  std::lock_guard<std::mutex> lock(mutex_);
  if (!step.journal_error.empty()) ++counters_.journal_errors;
  if (map_id_ == 0) {
    map_id_ = incoming.keyframe.map_id;
    publisher_.start(map_id_, 0);
    dropForeignLocked();
  }
  next_id_ = incoming.keyframe.id + 1;
  integrating_ = -1;
  ++counters_.integrated;
  publisher_.note(changes, /*integrated=*/true);
  converged_ = false;
  return step;
}

// The mapper's changes, its culled keyframes journaled first (worker thread, outside the
// lock; a failed write is counted as a journal error).
MapChanges MapperSync::takeChangesJournaled() {
  MapChanges changes = mapper_->takeChanges();
  if (journal_ && !changes.removed_keyframes.empty()) {
    const std::vector<KeyframeId> ids(changes.removed_keyframes.begin(), changes.removed_keyframes.end());
    if (Status s = journal_->appendCulled(ids); !s) culled_journal_errors_.fetch_add(1);
  }
  return changes;
}

bool MapperSync::refine() {
  if (converged_) return false;
  const bool changed = mapper_->refine(&interrupt_);
  converged_ = !changed && !interrupt_;
  MapChanges changes = takeChangesJournaled();
  std::lock_guard<std::mutex> lock(mutex_);
  publisher_.note(changes, /*integrated=*/false);
  return changed;
}

std::optional<MapUpdate> MapperSync::publishDue(int64_t now_us, std::string* journal_error) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::optional<MapUpdate> update = publisher_.publishDue(mapper_->map(), next_id_, now_us);
  if (!update) return update;
  if (journal_) {
    if (Status s = journal_->appendVersion(update->version); !s) {
      ++counters_.journal_errors;
      if (journal_error) *journal_error = s.error();
    }
  }
  ++counters_.maps_published;
  return update;
}

bool MapperSync::waitForWork(std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mutex_);
  wake_.wait_for(lock, timeout, [this] { return stopping_ || nextReadyLocked() || !converged_; });
  return !stopping_ && (nextReadyLocked() || !converged_);
}

void MapperSync::adopt(int64_t map_id, KeyframeId next_id) {
  std::lock_guard<std::mutex> lock(mutex_);
  map_id_ = map_id;
  next_id_ = next_id;
  publisher_.start(map_id_, 0);
}

void MapperSync::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  interrupt_ = true;
  wake_.notify_all();
}

MapperSync::Counters MapperSync::counters() const {
  std::lock_guard<std::mutex> lock(mutex_);
  Counters c = counters_;
  c.journal_errors += culled_journal_errors_.load();
  c.snapshots_published = publisher_.snapshotsPublished();
  c.snapshots_asked = publisher_.snapshotsAsked();
  c.snapshots_skipped = publisher_.snapshotsSkipped();
  return c;
}

int64_t MapperSync::mapId() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return map_id_;
}

int64_t MapperSync::version() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return publisher_.version();
}

size_t MapperSync::queueLength() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return queue_.size();
}

}  // namespace rgbdslam
