#pragma once
// The mapper's end of the map protocol (docs/design.md, "Map protocol"), with no transport:
// rgbd-mapper's node and rgbd-slam convert messages, call this, and send what it returns.
//   offer(kf): keyframe intake. Keyframes are integrated strictly in id order from 0; later
//     ones wait in a queue of at most max_queued_keyframes (beyond, they are dropped: the
//     tracker re-sends), earlier ones and repeats are duplicates that only make the next
//     publication re-acknowledge. The map id of keyframe 0 names the map; keyframes of
//     another map (and map ids <= 0, which no tracker uses) are refused.
//   integrateNext(now): the next keyframe in order, if it is here: Mapper::addKeyframe, then
//     the journal hook (before the keyframe is acknowledged), then publishDue.
//   refine(now): one Mapper::refine pass unless converged, then publishDue.
//   publishDue(now): the publisher's next version, journaled before it is returned (a
//     restarted mapper never re-uses a version).
//   onReceipt(r): the tracker's receipt (MapPublisher::onReceipt). When the receipt shows the
//     tracker can no longer send the keyframe the intake waits for (keyframes_sendable_from
//     beyond it: the journal lost acknowledged keyframes older than the tracker retains),
//     the intake skips to where the tracker can start, counting the keyframes skipped: the
//     map goes on without them rather than wait for ever. A mapper that lost its whole
//     journal (no map yet) takes the map id from such a receipt when keyframes of that map
//     wait in its queue.
//   adopt(map_id, next_id): before anything else, for a mapper started from a map file: the
//     map is 'map_id', keyframes below next_id are integrated (the file's), and the first
//     publication is a snapshot.
//   restore(journal contents): before anything else: re-integrates the journaled keyframes
//     (ids increasing; gaps are keyframes skipped before) and continues the versions after
//     the last journaled one (the first is a snapshot).
// Threads: offer() and onReceipt() may come from one thread (the transport's) while another
// (the worker) calls integrateNext / refine / publishDue / waitForWork; the mapper and its
// map belong to the worker. interrupt() is set while the next keyframe waits, so refinement
// stops early for it.
// Time: 'now_us' from the caller's monotonic clock [us].
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "rgbdslam/mapping/mapper.h"
#include "rgbdslam/sync/map_publisher.h"
#include "rgbdslam/util/expected.h"

namespace rgbdslam {

// A keyframe as received: the decoded content and, where a transport carries it, the
// message's bytes (what the journal keeps; empty in rgbd-slam).
struct IncomingKeyframe {
  KeyframeData keyframe;
  std::vector<uint8_t> encoded;
};

// Where the mapper persists what it acknowledges and publishes (procs/common/map_journal.h
// on disk; tests keep it in memory). Each call returns once the record is durable.
class KeyframeJournal {
 public:
  virtual ~KeyframeJournal() = default;
  virtual Status appendKeyframe(const IncomingKeyframe& keyframe) = 0;
  virtual Status appendVersion(int64_t version) = 0;
  // Keyframes the mapper culled, before any publication says so.
  virtual Status appendCulled(const std::vector<KeyframeId>& ids) = 0;
};

struct MapperSyncOptions {
  int max_queued_keyframes = 64;  // keyframes held waiting for an earlier one, at most
  MapPublisherOptions publisher;
};

enum class IntakeVerdict {
  kQueued,      // waits for integration (perhaps for an earlier keyframe)
  kDuplicate,   // integrated or queued already: re-acknowledged with the next publication
  kForeignMap,  // another map than the one this mapper holds, or a map id <= 0
  kQueueFull,   // dropped; the tracker re-sends it
};
const char* toString(IntakeVerdict verdict);

// What integrateNext() did.
struct IntegrationStep {
  KeyframeId id = -1;
  MapperResult result;
  std::string journal_error;  // non-empty: the keyframe is integrated but not persisted
};

class MapperSync {
 public:
  MapperSync(Mapper* mapper, const MapperSyncOptions& options, KeyframeJournal* journal = nullptr);

  // Re-integrates journaled keyframes (in order), removes the journaled culls ('culled') and
  // continues after last_version.
  Status restore(const std::vector<IncomingKeyframe>& journaled, int64_t last_version,
                 const std::vector<KeyframeId>& culled = {});
  void adopt(int64_t map_id, KeyframeId next_id);

  // Transport thread.
  IntakeVerdict offer(IncomingKeyframe keyframe);
  ReceiptVerdict onReceipt(const MapReceipt& receipt);

  // Worker thread.
  std::optional<IntegrationStep> integrateNext();
  bool refine();               // true when the map changed; false when converged
  std::optional<MapUpdate> publishDue(int64_t now_us, std::string* journal_error = nullptr);
  // Waits until the next keyframe is here, the map is not yet converged, or 'timeout' passed
  // or stop() was called; returns whether there is work.
  bool waitForWork(std::chrono::milliseconds timeout);
  void stop();
  bool converged() const { return converged_; }
  const Mapper& mapper() const { return *mapper_; }

  struct Counters {
    long queued = 0, duplicates = 0, out_of_order = 0, foreign = 0, dropped_queue_full = 0,
         integrated = 0, refused = 0, restored = 0, journal_errors = 0, maps_published = 0,
         snapshots_published = 0, snapshots_asked = 0, snapshots_skipped = 0, receipts_implausible = 0,
         versions_caught_up = 0, keyframes_skipped = 0;
  };
  Counters counters() const;
  int64_t mapId() const;
  int64_t version() const;
  size_t queueLength() const;

 private:
  bool nextReadyLocked() const { return queue_.count(next_id_) > 0; }
  void dropForeignLocked();
  void skipUnsendableLocked(const MapReceipt& receipt);
  MapChanges takeChangesJournaled();

  Mapper* mapper_;
  MapperSyncOptions options_;
  KeyframeJournal* journal_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  // Under mutex_:
  std::map<KeyframeId, IncomingKeyframe> queue_;
  int64_t map_id_ = 0;        // 0 until keyframe 0 (or the journal) names the map
  KeyframeId next_id_ = 0;    // the next keyframe to integrate
  KeyframeId integrating_ = -1;  // taken from the queue by integrateNext, -1 between: a
                                 // re-send of it meanwhile is a duplicate, not queued again
  MapPublisher publisher_;
  Counters counters_;
  bool stopping_ = false;
  // Worker only:
  bool converged_ = true;
  std::atomic<bool> interrupt_{false};
  std::atomic<long> culled_journal_errors_{0};
};

}  // namespace rgbdslam
