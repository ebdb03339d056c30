#pragma once
// rgbd-tracker's unacknowledged keyframes beyond sync.unacked_in_memory wait on the flight
// computer's storage (KeyframeOutbox's spill, sync/keyframe_outbox.h), in a keyframe store
// of their own (tracking/keyframe_store.h: an unnamed file under
// tracker.local_map_store_dir, CRC-checked). Why: a link outage is when keyframes pile up,
// about 65 a minute of 30 kB each on the ten-minute flight, and it can last as long as the
// flight; onboard memory must not grow with it (issue 10), and no keyframe may be dropped.
// Threads: as the outbox, one thread.
#include <cstdint>
#include <optional>
#include <vector>

#include "rgbdslam/sync/keyframe_outbox.h"
#include "rgbdslam/tracking/keyframe_store.h"

namespace rgbdslam {

class StoreSpill : public OutboxSpill<std::vector<uint8_t>> {
 public:
  explicit StoreSpill(KeyframeStore* store) : store_(store) {}
  bool put(KeyframeId id, const std::vector<uint8_t>& bytes) override {
    return store_->put(id, KeyframeStore::Kind::kMessage, bytes);
  }
  std::optional<std::vector<uint8_t>> take(KeyframeId id) override {
    Expected<std::vector<uint8_t>> bytes = store_->get(id, KeyframeStore::Kind::kMessage);
    if (!bytes) return std::nullopt;  // counted by the store and the outbox
    store_->remove(id, KeyframeStore::Kind::kMessage);
    return std::move(*bytes);
  }
  void drop(KeyframeId id) override { store_->remove(id, KeyframeStore::Kind::kMessage); }

 private:
  KeyframeStore* store_;
};

}  // namespace rgbdslam
