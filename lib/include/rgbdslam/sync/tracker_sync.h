#pragma once
// The tracker's end of the map protocol (docs/design.md, "Map protocol"), with no transport:
// the caller converts messages, calls this, and sends what it returns.
//   send(id, message, now): a new keyframe, which the caller sends now; kept and re-sent
//     (resendsDue) until a map message acknowledges it (KeyframeOutbox).
//   receive(update, now, apply): a map message. Its acknowledgements count whenever it is of
//     this map; its content is applied through 'apply' only when MapFollower says so.
//     An applied message that acknowledges fewer keyframes than the tracker had seen
//     acknowledged comes from a mapper that lost some (its journal was cut short): the
//     retained ones are sent again (KeyframeOutbox::resendFrom), and from then on only
//     messages at least that new acknowledge anything (an older one still on its way speaks
//     for the mapper before the loss).
//   receipt(now): what the tracker holds, for the mapper (sent every receipt period).
// Time: 'now_us' from the caller's monotonic clock [us]. Threads: not thread-safe.
#include <algorithm>
#include <vector>

#include "rgbdslam/sync/keyframe_outbox.h"
#include "rgbdslam/sync/map_follower.h"

namespace rgbdslam {

struct MapReceiveResult {
  MapVerdict verdict = MapVerdict::kForeignMap;
  bool applied = false;
  bool unknown_keyframes = false;       // applied, but entries named keyframes it lacks
  int resent_after_loss = 0;            // the mapper lost acknowledged keyframes: sent again
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
  // A tracker started from a map file: keyframes below 'next_id' exist (they are the file's,
  // which the mapper loaded too), so receipts say so.
  void startAfter(KeyframeId next_id) { keyframes_created_ = std::max<int64_t>(keyframes_created_, next_id); }

  // 'apply(update)' applies the content to the replica and returns false when entries named
  // keyframes the replica lacks (they are skipped).
  template <typename Apply>
  MapReceiveResult receive(const MapUpdate& update, int64_t now_us, Apply&& apply) {
    MapReceiveResult result;
    result.verdict = follower_.judge(update);
    if (result.verdict == MapVerdict::kForeignMap || result.verdict == MapVerdict::kImplausible) {
      return result;
    }
    // A map cannot acknowledge keyframes this tracker never sent: one that does is forged or
    // corrupt, and believing it would empty the outbox and mark the replica's provisional
    // keyframes acknowledged for good.
    if (update.acked_below > keyframes_created_) {
      result.verdict = MapVerdict::kImplausible;
      return result;
    }
    if (update.version < acks_from_version_) return result;
    const KeyframeId acked_below = update.acked_below;
    if (result.verdict == MapVerdict::kApply && acked_below < acked_below_) {
      result.resent_after_loss = outbox_.resendFrom(acked_below, now_us);
      acks_from_version_ = update.version;
      acked_below_ = acked_below;
      ++mapper_losses_;
    }
    result.ack_latencies_s = outbox_.acknowledgeBelow(acked_below, now_us);
    acked_below_ = std::max(acked_below_, acked_below);
    if (result.verdict != MapVerdict::kApply) return result;
    result.unknown_keyframes = !apply(update);
    follower_.applied(update);
    result.applied = true;
    return result;
  }

  MapReceipt receipt(int64_t utime) const {
    MapReceipt r = follower_.receipt(utime, keyframes_created_, static_cast<int64_t>(outbox_.size()));
    r.keyframes_sendable_from = outbox_.oldestSendable(keyframes_created_);
    return r;
  }
  // Times a mapper was seen to have lost acknowledged keyframes.
  long mapperLosses() const { return mapper_losses_; }
  const KeyframeOutbox<Message>& outbox() const { return outbox_; }
  void setSpill(OutboxSpill<Message>* spill) { outbox_.setSpill(spill); }  // KeyframeOutbox::setSpill
  const MapFollower& follower() const { return follower_; }

 private:
  KeyframeOutbox<Message> outbox_;
  MapFollower follower_;
  int64_t keyframes_created_ = 0;
  KeyframeId acked_below_ = 0;      // every keyframe below was acknowledged
  int64_t acks_from_version_ = 0;   // messages older than this acknowledge nothing
  long mapper_losses_ = 0;
};

}  // namespace rgbdslam
