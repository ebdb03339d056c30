#pragma once
// rgbd-mapper's node: converts messages for the mapper's end of the map protocol
// (lib sync/mapper_sync.h, docs/design.md "Map protocol") and publishes what it returns.
//   LCM thread: SLAM_KEYFRAME -> MapperSync::offer (with the message's bytes, for the
//   journal); SLAM_MAP_RECEIPT (the tracker's receipts) -> MapperSync::onReceipt; publishes
//   what the worker posted.
//   Worker thread: integrateNext / refine / publishDue (SLAM_MAP), MAPPER_STATUS every
//   status_period_s. Only the LCM thread calls LCM: the worker hands its messages over
//   through an outbox.
#include <atomic>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "common/map_journal.h"
#include "common/process_options.h"
#include "common/samples.h"
#include "rgbdslam/map/map_file.h"
#include "rgbdslam/mapping/mapper.h"
#include "rgbdslam/sync/mapper_sync.h"

namespace rgbdslam {

struct MapperNodeOptions {
  ChannelOptions channels;       // config section "channels"
  MapperProcessOptions process;  // config section "mapper_node"
  MapperSyncOptions sync;        // config section "sync"
  std::string state_dir;         // journal folder; empty: nothing persisted
};

class MapperNode {
 public:
  MapperNode(lcm::LCM* lcm, const PinholeCamera& camera, const MapperOptions& mapper_options,
             SlamMode mode, MapperNodeOptions options);
  ~MapperNode();
  // Before run(): starts from a map file's content as map 'map_id' (rgbd-mapper --load-map;
  // the tracker loads the same file with the same id), then opens the journal and
  // re-integrates what it holds (after a restart: the keyframes added to the loaded map);
  // an error if it cannot be opened or holds keyframes of another map.
  Status restore(const LoadedMap* start_map = nullptr, int64_t map_id = 0);
  // Subscribes, runs the worker, and returns when 'stop' becomes true.
  void run(const std::atomic<bool>& stop);
  void printSummary() const;
  const Map& map() const { return mapper_.map(); }  // after run()

 private:
  void onKeyframe(const lcm::ReceiveBuffer* buffer, const std::string& channel);
  void onReceipt(const lcm::ReceiveBuffer* buffer, const std::string& channel);
  void workerLoop();
  void publish(int64_t now_us);
  void publishStatus();
  void post(const std::string& channel, std::vector<uint8_t> bytes);  // worker -> LCM thread
  void flushOutbox();                                                // LCM thread

  lcm::LCM* lcm_;
  MapperNodeOptions options_;
  Mapper mapper_;
  std::optional<MapJournal> journal_;
  std::unique_ptr<MapperSync> sync_;

  std::mutex outbox_mutex_;
  std::vector<std::pair<std::string, std::vector<uint8_t>>> outbox_;  // under outbox_mutex_
  std::atomic<bool> stopping_{false};
  std::string state_ = "waiting";  // worker only
  RecentSamples integrate_ms_, local_ba_ms_, refine_ms_;  // worker only
  std::atomic<long> received_{0}, bad_messages_{0}, bad_receipts_{0}, map_bytes_{0};
  std::thread worker_;
};

}  // namespace rgbdslam
