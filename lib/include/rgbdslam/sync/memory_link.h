#pragma once
// An in-memory stand-in for the radio link between tracker and mapper, for tests and for
// rgbd-slam's simulated link (--link-loss, --link-delay-ms): each message sent is lost with
// probability 'loss', else delivered delay_ms later plus a uniform jitter (jitter larger than
// the gap between sends reorders), and duplicated with probability 'duplicate'. Outages lose
// everything sent, or due to arrive, within them. Seeded: the same sends give the same
// deliveries. Thread-safe (one mutex), so a sender and a receiver may be different threads.
// Time: the callers' clock [us]. Memory: the messages in flight.
#include <cstdint>
#include <map>
#include <mutex>
#include <random>
#include <utility>
#include <vector>

namespace rgbdslam {

struct LinkOptions {
  double loss = 0.0;        // probability that a message is lost [0, 1]
  double delay_ms = 0.0;    // delivery delay [ms]
  double jitter_ms = 0.0;   // plus uniform [0, jitter_ms) per message [ms]
  double duplicate = 0.0;   // probability that a delivered message arrives twice [0, 1]
  uint32_t seed = 1;
  std::vector<std::pair<int64_t, int64_t>> outages_us;  // [start, end) windows [us]

  // Whether this link does anything but deliver every message at once.
  bool imperfect() const {
    return loss > 0 || delay_ms > 0 || jitter_ms > 0 || duplicate > 0 || !outages_us.empty();
  }
};

template <typename Message>
class MemoryLink {
 public:
  explicit MemoryLink(const LinkOptions& options = {}) : options_(options), rng_(options.seed) {}

  void send(const Message& message, int64_t now_us) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++sent_;
    if (inOutage(now_us) || chance(options_.loss)) {
      ++lost_;
      return;
    }
    const int copies = chance(options_.duplicate) ? 2 : 1;
    for (int i = 0; i < copies; ++i) {
      const double jitter_ms = options_.jitter_ms > 0 ? uniform_(rng_) * options_.jitter_ms : 0.0;
      const auto arrival = now_us + static_cast<int64_t>((options_.delay_ms + jitter_ms) * 1000.0);
      in_flight_.emplace(std::make_pair(arrival, order_++), message);
    }
  }

  // Every message due by now_us, in order of arrival.
  std::vector<Message> receive(int64_t now_us) {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<Message> out;
    while (!in_flight_.empty() && in_flight_.begin()->first.first <= now_us) {
      auto it = in_flight_.begin();
      if (inOutage(it->first.first)) ++lost_;
      else out.push_back(std::move(it->second));
      in_flight_.erase(it);
    }
    return out;
  }

  long sent() const { std::lock_guard<std::mutex> l(mutex_); return sent_; }
  long lost() const { std::lock_guard<std::mutex> l(mutex_); return lost_; }
  size_t inFlight() const { std::lock_guard<std::mutex> l(mutex_); return in_flight_.size(); }

 private:
  bool chance(double p) { return p > 0 && uniform_(rng_) < p; }
  bool inOutage(int64_t t_us) const {
    for (const auto& [start, end] : options_.outages_us) {
      if (t_us >= start && t_us < end) return true;
    }
    return false;
  }
  LinkOptions options_;
  mutable std::mutex mutex_;
  std::mt19937 rng_;
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  std::multimap<std::pair<int64_t, uint64_t>, Message> in_flight_;  // (arrival, send order)
  uint64_t order_ = 0;
  long sent_ = 0, lost_ = 0;
};

}  // namespace rgbdslam
