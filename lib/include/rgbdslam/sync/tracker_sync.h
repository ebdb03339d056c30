#pragma once
// The tracker's end of the map protocol (docs/design.md, "Map protocol"), with no transport:
// the caller converts messages, calls this, and sends what it returns.
//   send(id, message, now): a new keyframe, which the caller sends now; kept and re-sent
//     (resendsDue) until a map message acknowledges it (KeyframeOutbox).
//   receive(update, now, apply): a map message. Its acknowledgements count whenever it is of
//     this map; its content is applied through 'apply' only when MapFollower says so.
//   receipt(now): what the tracker holds, for the mapper (sent every receipt period).
// Time: 'now_us' from the caller's monotonic clock [us]. Threads: not thread-safe.
#include <vector>

#include "rgbdslam/sync/keyframe_outbox.h"
#include "rgbdslam/sync/map_follower.h"

namespace rgbdslam {

struct MapReceiveResult {
  MapVerdict verdict = MapVerdict::kForeignMap;
  bool applied = false;
  bool unknown_keyframes = false;       // applied, but entries named keyframes it lacks
  std::vector<double> ack_latencies_s;  // keyframes newly acknowledged: time since first send
};

template <typename Message>
class TrackerSync {
 public:
  TrackerSync(int64_t map_id, const KeyframeOutboxOptions& options)
      : outbox_(options), follower_(map_id) {}

  void send(KeyframeId id, Message message, int64_t now_us) {
    outbox_.sent(id, std::move(message), now_us);
    keyframes_created_ = std::max<int64_t>(keyframes_created_, id + 1);
  }
  std::vector<const Message*> resendsDue(int64_t now_us) { return outbox_.resendsDue(now_us); }

  // 'apply(update)' applies the content to the replica and returns false when entries named
  // keyframes the replica lacks (they are skipped).
  template <typename Apply>
  MapReceiveResult receive(const MapUpdate& update, int64_t now_us, Apply&& apply) {
    MapReceiveResult result;
    result.verdict = follower_.judge(update);
    if (result.verdict == MapVerdict::kForeignMap || result.verdict == MapVerdict::kImplausible) {
      return result;
    }
    result.ack_latencies_s = outbox_.acknowledge(update.acked_keyframes, now_us);
    if (result.verdict != MapVerdict::kApply) return result;
    result.unknown_keyframes = !apply(update);
    follower_.applied(update);
    result.applied = true;
    return result;
  }

  MapReceipt receipt(int64_t utime) const {
    return follower_.receipt(utime, keyframes_created_, static_cast<int64_t>(outbox_.size()));
  }
  const KeyframeOutbox<Message>& outbox() const { return outbox_; }
  const MapFollower& follower() const { return follower_; }

 private:
  KeyframeOutbox<Message> outbox_;
  MapFollower follower_;
  int64_t keyframes_created_ = 0;
};

}  // namespace rgbdslam
