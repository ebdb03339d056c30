// lcm-link-relay (test tool): the delay of a radio link, which this kernel cannot add (no
// netem). Subscribes to the channels matching --channels (an LCM regex) on --from and
// republishes each message, unchanged and in arrival order, on --to once --delay-ms has
// passed since it arrived.
//
// Used in the onboard namespace of tests/integration/link.sh: one instance local bus -> link
// for what the tracker sends (SLAM_KEYFRAME|SLAM_STATUS), one link -> local bus for what the
// mapper sends (SLAM_MAP|MAPPER_STATUS), each adding the link's one-way delay.
//
// Echo: the relay never hears its own output, because it publishes on --to and listens on
// --from, two different URLs (refused if equal). The second instance, going the other way,
// does listen on this one's --to, so the two directions must carry disjoint channel sets
// (assumed, not checked: a channel matching both regexes would circulate until dropped).
//
// One thread: handleTimeout() on --from, waking when the oldest message is due. The delay
// is fixed, so arrival order is release order and a FIFO is the time-ordered queue. The
// queue is bounded (--max-queue messages, --max-queue-mb bytes): when full, the new message
// is dropped and counted, as a full radio buffer would. On SIGINT/SIGTERM, or after
// --timeout seconds, it prints its counts and exits 0 (messages still queued are counted
// as pending, not sent); 1 if receiving fails, 2 on bad usage.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <deque>
#include <iostream>
#include <vector>

#include "common/cli.h"
#include "common/process.h"

using namespace rgbdslam;

namespace {

struct Held {
  int64_t release_utime;  // host clock [us]
  std::string channel;
  std::vector<uint8_t> bytes;
};

class Relay {
 public:
  Relay(lcm::LCM* to, int64_t delay_us, size_t max_messages, size_t max_bytes)
      : to_(to), delay_us_(delay_us), max_messages_(max_messages), max_bytes_(max_bytes) {}

  void onMessage(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
    ++received_;
    if (queue_.size() >= max_messages_ || queued_bytes_ + buffer->data_size > max_bytes_) {
      ++dropped_;
      return;
    }
    const auto* data = static_cast<const uint8_t*>(buffer->data);
    queue_.push_back(Held{utimeNow() + delay_us_, channel,
                          std::vector<uint8_t>(data, data + buffer->data_size)});
    queued_bytes_ += buffer->data_size;
  }

  // Publishes every message whose time has come; returns the wait until the next one [ms]
  // (at most 'idle_ms').
  int releaseDue(int idle_ms) {
    const int64_t now = utimeNow();
    while (!queue_.empty() && queue_.front().release_utime <= now) {
      Held& held = queue_.front();
      if (to_->publish(held.channel, held.bytes.data(), static_cast<unsigned>(held.bytes.size())) == 0) ++forwarded_;
      else ++publish_errors_;
      queued_bytes_ -= held.bytes.size();
      queue_.pop_front();
    }
    if (queue_.empty()) return idle_ms;
    const int64_t wait_us = queue_.front().release_utime - now;
    return static_cast<int>(std::min<int64_t>(idle_ms, (wait_us + 999) / 1000));
  }

  void printCounts(const std::string& name) const {
    std::printf("%s: received %ld forwarded %ld dropped_full %ld publish_errors %ld pending %zu\n",
                name.c_str(), received_, forwarded_, dropped_, publish_errors_, queue_.size());
    std::fflush(stdout);
  }

 private:
  lcm::LCM* to_;
  int64_t delay_us_;
  size_t max_messages_, max_bytes_;
  std::deque<Held> queue_;
  size_t queued_bytes_ = 0;
  long received_ = 0, forwarded_ = 0, dropped_ = 0, publish_errors_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  CommandLine cli("lcm-link-relay",
                  "Test tool: republishes channels from one LCM URL on another after a fixed delay.");
  cli.option("from", "URL", "LCM URL to listen on");
  cli.option("to", "URL", "LCM URL to publish on (must differ from --from)");
  cli.option("channels", "REGEX", "channels to relay (LCM regex, e.g. 'SLAM_KEYFRAME|SLAM_STATUS')");
  cli.option("delay-ms", "MS", "delay added to every message [ms]", "50");
  cli.option("max-queue", "N", "most messages held at once; more are dropped", "10000");
  cli.option("max-queue-mb", "MB", "most bytes held at once [MiB]; more are dropped", "64");
  cli.option("timeout", "S", "exit after this many seconds (0: run until SIGINT/SIGTERM)", "0");
  cli.option("name", "TEXT", "name in the printed counts", "lcm-link-relay");
  if (Status s = cli.parse(argc, argv); !s) return usageError("lcm-link-relay", s.error());
  if (cli.helpRequested()) return std::cout << cli.helpText(), 0;
  for (const char* name : {"from", "to", "channels"}) {
    if (!cli.has(name)) return usageError("lcm-link-relay", std::string("--") + name + " is required");
  }
  if (cli.get("from") == cli.get("to")) {
    return usageError("lcm-link-relay", "--from and --to are the same URL: the relay would hear its own output");
  }
  const auto delay_ms = cli.getDouble("delay-ms");
  const auto max_queue = cli.getInt("max-queue");
  const auto max_queue_mb = cli.getDouble("max-queue-mb");
  const auto timeout_s = cli.getDouble("timeout");
  if (!delay_ms || *delay_ms < 0) return usageError("lcm-link-relay", "--delay-ms must be >= 0");
  if (!max_queue || *max_queue < 1) return usageError("lcm-link-relay", "--max-queue must be >= 1");
  if (!max_queue_mb || !(*max_queue_mb > 0)) return usageError("lcm-link-relay", "--max-queue-mb must be > 0");
  if (!timeout_s || *timeout_s < 0) return usageError("lcm-link-relay", "--timeout must be >= 0");

  auto from = openLcm(cli.get("from"));
  if (!from) return usageError("lcm-link-relay", "--from: " + from.error());
  auto to = openLcm(cli.get("to"));
  if (!to) return usageError("lcm-link-relay", "--to: " + to.error());
  Relay relay(to->get(), static_cast<int64_t>(*delay_ms * 1000),
              static_cast<size_t>(*max_queue), static_cast<size_t>(*max_queue_mb * 1024 * 1024));
  // LCM's own per-subscription queue (30 messages by default) must not drop before ours.
  // LCM anchors a subscription as "^REGEX$", which binds to the first and last alternatives
  // only: 'SLAM_MAP|MAPPER_STATUS' would also take SLAM_MAP_RECEIPT (the relay the other way
  // then sends the receipts round for ever). The group anchors every alternative.
  auto subscription = subscribeRaw(from->get(), "(" + cli.get("channels") + ")", &relay, &Relay::onMessage);
  subscription->setQueueCapacity(static_cast<int>(std::min<long>(*max_queue, 1000000)));
  std::cerr << "lcm-link-relay: " << cli.get("channels") << " from " << cli.get("from") << " to "
            << cli.get("to") << " after " << *delay_ms << " ms\n";

  const std::atomic<bool>& stop = installStopHandlers();
  const int64_t deadline = *timeout_s > 0 ? utimeNow() + static_cast<int64_t>(*timeout_s * 1e6) : INT64_MAX;
  constexpr int kIdleMs = 100;  // longest wait, so a stop request is seen promptly
  int wait_ms = kIdleMs;
  bool failed = false;
  while (!stop && utimeNow() < deadline) {
    if ((*from)->handleTimeout(wait_ms) < 0 && !stop) {  // a signal interrupts it too
      std::cerr << "lcm-link-relay: error: receiving on " << cli.get("from") << " failed\n";
      failed = true;
      break;
    }
    wait_ms = relay.releaseDue(kIdleMs);
  }
  relay.printCounts(cli.get("name"));
  return failed ? 1 : 0;
}
