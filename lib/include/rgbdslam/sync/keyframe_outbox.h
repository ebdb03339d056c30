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
// Memory: one Message per unacknowledged keyframe, plus 'retained' acknowledged ones. During
// a link outage the unacknowledged grow by one per keyframe (on the ten-minute flight about
// 65 a minute of 30 kB each); with a spill (setSpill) at most 'in_memory' of them stay in
// memory, the newest wait in the spill (rgbd-tracker: the flight computer's storage,
// procs/common/store_spill.h), and each is read back when it is among the oldest resend_max, which are
// the ones sent. A spill that refuses a message (storage full) leaves it in memory: a
// keyframe is never dropped for memory. A message the spill cannot give back (a read error,
// other bytes) is lost: counted (spillErrors), and the mapper skips it as it skips what
// nobody can send (oldestSendable).
// Threads: not thread-safe; one thread calls everything.
#include <algorithm>
#include <cstdint>
#include <iterator>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include "rgbdslam/map/map_types.h"

namespace rgbdslam {

struct KeyframeOutboxOptions {
  double resend_period_s = 1.0;      // first re-send of an unacknowledged keyframe after this [s]
  double resend_max_period_s = 4.0;  // the doubling re-send interval grows to this at most [s]
  int resend_max = 2;                // only the oldest this many waiting keyframes are re-sent
  int retained = 64;                 // acknowledged keyframes kept for a mapper that loses them
  int in_memory = 32;                // with a spill: unacknowledged keyframes in memory at most
};

// Where unacknowledged keyframes beyond KeyframeOutboxOptions::in_memory wait.
template <typename Message>
class OutboxSpill {
 public:
  virtual ~OutboxSpill() = default;
  // False when it cannot take the message (storage full): the outbox keeps it in memory.
  virtual bool put(KeyframeId id, const Message& message) = 0;
  // The message, which the spill then forgets; nullopt when it cannot give it back.
  virtual std::optional<Message> take(KeyframeId id) = 0;
  virtual void drop(KeyframeId id) = 0;
};

template <typename Message>
class KeyframeOutbox {
 public:
  explicit KeyframeOutbox(const KeyframeOutboxOptions& options = {}) : options_(options) {}
  ~KeyframeOutbox() {
    if (!spill_) return;
    for (const auto& [id, entry] : entries_) {
      if (entry.spilled) spill_->drop(id);
    }
  }
  KeyframeOutbox(const KeyframeOutbox&) = delete;
  KeyframeOutbox& operator=(const KeyframeOutbox&) = delete;

  // Unacknowledged keyframes beyond options.in_memory wait in 'spill' (owned by the caller,
  // alive as long as this outbox; null: all in memory).
  void setSpill(OutboxSpill<Message>* spill) {
    spill_ = spill;
    spillBeyondMemory();
  }

  // A keyframe the caller has just sent for the first time; kept until acknowledged.
  void sent(KeyframeId id, Message message, int64_t now_us) {
    Entry entry{std::move(message), now_us, now_us + toUs(options_.resend_period_s),
                options_.resend_period_s, 1};
    forget(id);
    entries_[id] = std::move(entry);
    ++in_memory_;
    spillBeyondMemory();
  }

  // The keyframes to re-send now: those of the oldest resend_max that are due, oldest first;
  // each is rescheduled (one waiting in the spill is read back first).
  std::vector<const Message*> resendsDue(int64_t now_us) {
    std::vector<const Message*> due;
    int oldest = 0;
    for (auto it = entries_.begin(); it != entries_.end() && oldest < options_.resend_max;) {
      Entry& entry = it->second;
      if (now_us < entry.next_send_us) {
        ++it, ++oldest;
        continue;
      }
      if (entry.spilled && !unspill(it->first, &entry)) {
        it = entries_.erase(it);  // lost (counted): the next one takes its turn
        continue;
      }
      entry.interval_s = std::min(2 * entry.interval_s,
                                  std::max(options_.resend_max_period_s, options_.resend_period_s));
      entry.next_send_us = now_us + toUs(entry.interval_s);
      ++entry.sends;
      due.push_back(&entry.message);
      ++it, ++oldest;
    }
    return due;
  }

  // Drops every waiting keyframe with an id below 'below'; returns, for each one dropped,
  // the time from its first send to now [s] (the acknowledgement latency).
  // Of those, only the newest 'retained' are kept (a spilled one read back for it; one the
  // spill cannot give back is not retained, and not lost: the mapper has it).
  std::vector<double> acknowledgeBelow(KeyframeId below, int64_t now_us) {
    std::vector<double> ages_s;
    const auto end = entries_.lower_bound(below);
    const auto acknowledged = std::distance(entries_.begin(), end);
    auto not_kept = acknowledged - std::max(options_.retained, 0);  // the oldest of them
    for (auto it = entries_.begin(); it != end; it = entries_.erase(it), --not_kept) {
      ages_s.push_back((now_us - it->second.first_sent_us) * 1e-6);
      if (not_kept > 0) {
        forget(it->first, &it->second);
        continue;
      }
      if (it->second.spilled) {
        std::optional<Message> message = spill_->take(it->first);
        if (message) retained_[it->first] = std::move(*message);
        continue;
      }
      --in_memory_;
      retained_[it->first] = std::move(it->second.message);
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
      forget(it->first);
      entries_[it->first] = Entry{std::move(it->second), now_us, now_us, options_.resend_period_s / 2, 0};
      ++in_memory_;
      ++count;
    }
    spillBeyondMemory();
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
  size_t inMemory() const { return in_memory_; }      // unacknowledged, in memory
  size_t spilled() const { return entries_.size() - in_memory_; }  // ...in the spill
  int64_t spillErrors() const { return spill_errors_; }  // messages the spill could not give back
  // Sends of a waiting keyframe so far (0 when it is not waiting).
  int sends(KeyframeId id) const {
    const auto it = entries_.find(id);
    return it == entries_.end() ? 0 : it->second.sends;
  }

 private:
  static int64_t toUs(double seconds) { return static_cast<int64_t>(seconds * 1e6); }
  struct Entry {
    Message message;  // empty while spilled
    int64_t first_sent_us = 0, next_send_us = 0;
    double interval_s = 0.0;  // until the next re-send [s]
    int sends = 0;
    bool spilled = false;
  };

  // The newest in-memory entries go to the spill until at most in_memory are left; the
  // oldest resend_max stay (they are the ones re-sent).
  void spillBeyondMemory() {
    if (!spill_ || options_.in_memory < 0) return;
    int from_oldest = static_cast<int>(entries_.size());
    for (auto it = entries_.rbegin(); it != entries_.rend() && in_memory_ > static_cast<size_t>(options_.in_memory);
         ++it) {
      if (--from_oldest < options_.resend_max) break;
      if (it->second.spilled) continue;
      if (!spill_->put(it->first, it->second.message)) break;  // storage full: it stays here
      it->second.message = Message{};
      it->second.spilled = true;
      --in_memory_;
    }
  }
  // Reads a spilled entry back; false (counted) when the spill cannot give it.
  bool unspill(KeyframeId id, Entry* entry) {
    std::optional<Message> message = spill_->take(id);
    if (!message) {
      ++spill_errors_;
      return false;
    }
    entry->message = std::move(*message);
    entry->spilled = false;
    ++in_memory_;
    return true;
  }
  // An entry about to be replaced or dropped: its spilled copy goes, or it leaves memory.
  void forget(KeyframeId id, const Entry* entry = nullptr) {
    if (!entry) {
      const auto it = entries_.find(id);
      if (it == entries_.end()) return;
      entry = &it->second;
    }
    if (entry->spilled) spill_->drop(id);
    else --in_memory_;
  }

  KeyframeOutboxOptions options_;
  std::map<KeyframeId, Entry> entries_;  // ordered: oldest first
  std::map<KeyframeId, Message> retained_;  // acknowledged, newest 'retained'
  OutboxSpill<Message>* spill_ = nullptr;
  size_t in_memory_ = 0;  // entries not spilled
  int64_t spill_errors_ = 0;
};

}  // namespace rgbdslam
