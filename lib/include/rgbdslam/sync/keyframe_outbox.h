#pragma once
// The tracker's side of keyframe delivery (docs/design.md, "Map protocol"): every keyframe
// the tracker creates is kept until a map message acknowledges it, and re-sent meanwhile.
// A keyframe is first re-sent resend_period_s after it was sent, then at doubling intervals
// up to resend_max_period_s (a slow or absent mapper is not flooded). Only the oldest
// resend_max waiting keyframes are re-sent; the others wait their turn, which comes as the
// oldest are acknowledged (and then at once, their first interval long past). Why: the
// mapper integrates in id order and queues later keyframes that arrive, so what it waits for
// is the oldest; and re-sending every waiting keyframe each resend_max_period_s grows
// without bound in an outage (the link cut for 300 s of a ten-minute flight: 155 keyframes
// waiting, 8616 sends, 3.2 Mbit/s against a budget of 1). Now an outage costs resend_max
// keyframes per resend_max_period_s (2 per 4 s: about 0.1 Mbit/s at 30 kB each), as TCP
// re-sends only its oldest segment on a timeout.
// 'Message' is what goes on the wire: the encoded keyframe_t in rgbd-tracker (encoding once,
// re-sending the bytes), the KeyframeData itself in rgbd-slam.
// Time: 'now_us' from the caller's monotonic clock [us]; the outbox reads no clock itself.
// Acknowledged keyframes: the newest 'retained' of them are kept too, for a mapper that
// loses acknowledged keyframes (its journal cut short by a corrupt record): resendFrom()
// puts them back in line. What is older is gone for good; oldestSendable() tells the mapper
// (in the receipt) where the tracker can still start, so it skips what nobody can send.
// Memory: one Message per unacknowledged keyframe (during a link outage it grows by one per
// keyframe; the mapper's intake bounds nothing here), plus 'retained' acknowledged ones.
// Threads: not thread-safe; one thread calls everything.
#include <algorithm>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "rgbdslam/map/map_types.h"

namespace rgbdslam {

struct KeyframeOutboxOptions {
  double resend_period_s = 1.0;      // first re-send of an unacknowledged keyframe after this [s]
  double resend_max_period_s = 4.0;  // the doubling re-send interval grows to this at most [s]
  int resend_max = 2;                // only the oldest this many waiting keyframes are re-sent
  int retained = 64;                 // acknowledged keyframes kept for a mapper that loses them
};

template <typename Message>
class KeyframeOutbox {
 public:
  explicit KeyframeOutbox(const KeyframeOutboxOptions& options = {}) : options_(options) {}

  // A keyframe the caller has just sent for the first time; kept until acknowledged.
  void sent(KeyframeId id, Message message, int64_t now_us) {
    Entry entry{std::move(message), now_us, now_us + toUs(options_.resend_period_s),
                options_.resend_period_s, 1};
    entries_[id] = std::move(entry);
  }

  // The keyframes to re-send now: those of the oldest resend_max that are due, oldest first;
  // each is rescheduled.
  std::vector<const Message*> resendsDue(int64_t now_us) {
    std::vector<const Message*> due;
    int oldest = 0;
    for (auto& [id, entry] : entries_) {
      if (oldest++ >= options_.resend_max) break;
      if (now_us < entry.next_send_us) continue;
      entry.interval_s = std::min(2 * entry.interval_s,
                                  std::max(options_.resend_max_period_s, options_.resend_period_s));
      entry.next_send_us = now_us + toUs(entry.interval_s);
      ++entry.sends;
      due.push_back(&entry.message);
    }
    return due;
  }

  // Drops every waiting keyframe with an id below 'below'; returns, for each one dropped,
  // the time from its first send to now [s] (the acknowledgement latency).
  std::vector<double> acknowledgeBelow(KeyframeId below, int64_t now_us) {
    std::vector<double> ages_s;
    for (auto it = entries_.begin(); it != entries_.end() && it->first < below; it = entries_.erase(it)) {
      ages_s.push_back((now_us - it->second.first_sent_us) * 1e-6);
      if (options_.retained > 0) retained_[it->first] = std::move(it->second.message);
    }
    while (static_cast<int>(retained_.size()) > std::max(options_.retained, 0)) retained_.erase(retained_.begin());
    return ages_s;
  }

  // The mapper lost the acknowledged keyframes from 'first' on: the retained ones go back in
  // line, due at once (the oldest resend_max now, each next as one before it is
  // acknowledged). Returns how many.
  int resendFrom(KeyframeId first, int64_t now_us) {
    int count = 0;
    for (auto it = retained_.lower_bound(first); it != retained_.end(); it = retained_.erase(it)) {
      entries_[it->first] = Entry{std::move(it->second), now_us, now_us, options_.resend_period_s / 2, 0};
      ++count;
    }
    return count;
  }

  // The oldest keyframe this tracker can still send ('none': the caller's next id).
  KeyframeId oldestSendable(KeyframeId none) const {
    KeyframeId oldest = none;
    if (!entries_.empty()) oldest = std::min(oldest, entries_.begin()->first);
    if (!retained_.empty()) oldest = std::min(oldest, retained_.begin()->first);
    return oldest;
  }

  size_t size() const { return entries_.size(); }
  bool empty() const { return entries_.empty(); }
  // Sends of a waiting keyframe so far (0 when it is not waiting).
  int sends(KeyframeId id) const {
    const auto it = entries_.find(id);
    return it == entries_.end() ? 0 : it->second.sends;
  }

 private:
  static int64_t toUs(double seconds) { return static_cast<int64_t>(seconds * 1e6); }
  struct Entry {
    Message message;
    int64_t first_sent_us = 0, next_send_us = 0;
    double interval_s = 0.0;  // until the next re-send [s]
    int sends = 0;
  };
  KeyframeOutboxOptions options_;
  std::map<KeyframeId, Entry> entries_;  // ordered: oldest first
  std::map<KeyframeId, Message> retained_;  // acknowledged, newest 'retained'
};

}  // namespace rgbdslam
