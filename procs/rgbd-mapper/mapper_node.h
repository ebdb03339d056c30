#pragma once
// rgbd-mapper's node: the ground side of the map protocol (docs/design.md, "Map protocol").
//   LCM thread: decodes SLAM_KEYFRAME messages and queues them by id (duplicates and
//   keyframes of another map are counted and answered or refused, never queued).
//   Worker thread: integrates queued keyframes strictly in id order (journaling each one
//   before it is acknowledged), refines the map in between (a newly queued next keyframe
//   interrupts refinement), and publishes SLAM_MAP: a delta at once after each integrated
//   keyframe (the acknowledgement), deltas of refinement at most every map_period_s, a full snapshot right after a (re)start, when the tracker is stuck behind
//   (below), and every snapshot_period_s as a fallback; every map message carries the list
//   of integrated keyframes (the acknowledgement). Versions continue across restarts
//   (journaled before publication). MAPPER_STATUS every status_period_s.
//   SLAM_STATUS (the tracker's, link): its map_version is the tracker's acknowledgement of
//   map versions. When two reports in a row show the same version below the published one,
//   a delta was lost (the tracker cannot apply later ones): the next publication is a
//   snapshot. So a lossy link costs one snapshot per loss, not a snapshot every few seconds.
// Only the LCM thread touches LCM: the worker hands what it publishes to it through an
// outbox, so no LCM call ever races another.
#include <atomic>
#include <condition_variable>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "common/map_journal.h"
#include "common/samples.h"
#include "rgbdslam/map/map_diff.h"
#include "rgbdslam/mapping/mapper.h"

namespace rgbdslam {

struct MapperNodeOptions {
  std::string keyframe_channel = "SLAM_KEYFRAME";
  std::string map_channel = "SLAM_MAP";
  std::string status_channel = "MAPPER_STATUS";
  std::string state_dir;            // journal folder; empty: nothing persisted
  double map_period_s = 1.0;        // refinement deltas at most this often [s]
  std::string tracker_status_channel = "SLAM_STATUS";
  double snapshot_period_s = 30.0;  // full snapshots at least this often [s]
  double status_period_s = 1.0;     // MAPPER_STATUS period [s]
  int max_queued_keyframes = 64;    // keyframes held waiting for an earlier one, at most
  MapDiffOptions diff;
};

class MapperNode {
 public:
  MapperNode(lcm::LCM* lcm, const PinholeCamera& camera, const MapperOptions& mapper_options,
             SlamMode mode, MapperNodeOptions options);
  ~MapperNode();
  // Opens the journal and re-integrates what it holds; an error if it cannot be opened.
  Status restore();
  // Subscribes, runs the worker, and returns when 'stop' becomes true.
  void run(const std::atomic<bool>& stop);
  void printSummary() const;

 private:
  using Clock = std::chrono::steady_clock;
  void onKeyframe(const lcm::ReceiveBuffer* buffer, const std::string& channel);
  void onTrackerStatus(const lcm::ReceiveBuffer* buffer, const std::string& channel);
  void workerLoop();
  bool integrateNext();
  void publishIfDue(Clock::time_point now);
  void publishStatus();
  void post(const std::string& channel, std::vector<uint8_t> bytes);  // worker -> LCM thread
  void flushOutbox();                                                // LCM thread

  lcm::LCM* lcm_;
  MapperNodeOptions options_;
  Mapper mapper_;
  MapDiffer differ_;
  std::optional<MapJournal> journal_;

  // Shared between the LCM thread and the worker (under mutex_).
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  struct Queued {
    KeyframeData keyframe;
    std::vector<uint8_t> bytes;  // as received, for the journal
  };
  std::map<KeyframeId, Queued> queue_;
  std::vector<std::pair<std::string, std::vector<uint8_t>>> outbox_;
  int64_t map_id_ = 0;           // 0 until keyframe 0 (or the journal) names the map
  KeyframeId next_id_ = 0;       // the next keyframe to integrate
  bool ack_due_ = false;         // a duplicate arrived: re-acknowledge soon
  bool snapshot_requested_ = false;  // the tracker is stuck behind a lost delta
  int64_t tracker_version_ = -1;     // the tracker's map version in its last report
  int64_t published_version_ = 0;    // version_, for the LCM thread
  bool stopping_ = false;
  std::atomic<bool> interrupt_{false};

  // Worker-only state.
  int64_t version_ = 0;          // last published map version
  bool dirty_ = false, snapshot_due_ = true, converged_ = true, integrated_unpublished_ = false;
  Clock::time_point last_publish_{}, last_snapshot_{}, last_status_{};
  RecentSamples integrate_ms_, local_ba_ms_, refine_ms_;
  std::string state_ = "waiting";

  // Counters (atomics: written by either thread, read for status).
  struct Counters {
    std::atomic<long> received{0}, integrated{0}, duplicates{0}, out_of_order{0}, foreign{0},
        bad_messages{0}, bad_keyframes{0}, dropped_queue_full{0}, maps_published{0},
        snapshots_published{0}, snapshots_requested{0}, map_bytes{0}, restored{0},
        journal_errors{0}, bad_status_messages{0};
  };
  Counters counters_;
  std::thread worker_;
};

}  // namespace rgbdslam
