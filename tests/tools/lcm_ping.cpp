// lcm-ping (test tool): numbered datagrams for checking a link: what arrives, what is lost,
// and how late. Sender and receiver must share a clock (same host, any namespaces).
//   lcm-ping send --count N [--start S] [--rate HZ] [--size BYTES] [--channel C] [--lcm-url URL]
//       publishes N messages numbered S..S+N-1: int64 seq, int64 send time [us], zero
//       padding up to --size; prints "sent N" and "publish_errors E" (publish() != 0).
//   lcm-ping recv --count N [--timeout S] [--idle S] [--ready FILE] [--channel C] [--lcm-url URL]
//       counts them until all N arrived, --timeout seconds passed, or nothing arrived for
//       --idle seconds after the first; counts numbers 0..N-1 (others are ignored) and prints
//         received R / expected N / lost_pct P / duplicates D / delay_ms_min, _median, _max
//       and, on stderr, the missing numbers as ranges ("lcm-ping: missing 0-99").
//       exit 0 once it has counted (whatever arrived), 1 if receiving fails, 2 on bad usage.
// The payload is raw bytes, not an lcmtype: only this tool reads it.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <thread>
#include <vector>

#include "common/cli.h"
#include "common/process.h"

using namespace rgbdslam;

namespace {

constexpr size_t kHeaderBytes = 16;  // seq and send time, int64 each, host byte order

class PingCounter {
 public:
  explicit PingCounter(long expected) : seen_(static_cast<size_t>(expected), false) {}
  void onMessage(const lcm::ReceiveBuffer* buffer, const std::string&) {
    last_utime_ = utimeNow();
    if (buffer->data_size < kHeaderBytes) return;
    int64_t seq = 0, sent = 0;
    std::memcpy(&seq, buffer->data, 8);
    std::memcpy(&sent, static_cast<const char*>(buffer->data) + 8, 8);
    if (seq < 0 || static_cast<size_t>(seq) >= seen_.size()) return;
    if (seen_[static_cast<size_t>(seq)]) {
      ++duplicates_;
      return;
    }
    seen_[static_cast<size_t>(seq)] = true;
    ++received_;
    delays_ms_.push_back((last_utime_ - sent) * 1e-3);
  }
  // The missing sequence numbers as ranges "a-b", at most 'limit' of them.
  std::string missingRanges(size_t limit) const {
    std::string out;
    size_t ranges = 0;
    for (size_t i = 0; i < seen_.size() && ranges < limit; ++i) {
      if (seen_[i]) continue;
      size_t j = i;
      while (j + 1 < seen_.size() && !seen_[j + 1]) ++j;
      out += (out.empty() ? "" : " ") + std::to_string(i) + (j > i ? "-" + std::to_string(j) : "");
      ++ranges, i = j;
    }
    return out;
  }
  long received_ = 0, duplicates_ = 0;
  int64_t last_utime_ = 0;  // 0 until the first message
  std::vector<double> delays_ms_;

 private:
  std::vector<bool> seen_;
};

int send(lcm::LCM& lcm, const CommandLine& cli) {
  const long count = *cli.getInt("count");
  const size_t size = std::max<size_t>(kHeaderBytes, static_cast<size_t>(*cli.getInt("size")));
  const auto period = std::chrono::microseconds(static_cast<int64_t>(1e6 / *cli.getDouble("rate")));
  std::vector<char> bytes(size, 0);
  long errors = 0;
  auto next = std::chrono::steady_clock::now();
  const int64_t start = *cli.getInt("start");
  for (int64_t seq = start; seq < start + count; ++seq) {
    const int64_t now = utimeNow();
    std::memcpy(bytes.data(), &seq, 8);
    std::memcpy(bytes.data() + 8, &now, 8);
    if (lcm.publish(cli.get("channel"), bytes.data(), static_cast<unsigned>(bytes.size())) != 0) ++errors;
    next += period;
    std::this_thread::sleep_until(next);
  }
  std::cout << "sent " << count << "\npublish_errors " << errors << std::endl;
  return 0;
}

int receive(lcm::LCM& lcm, const CommandLine& cli) {
  const long count = *cli.getInt("count");
  PingCounter counter(count);
  // LCM drops messages for a subscription after 30 queued by default; on a busy machine
  // that would count as link loss.
  auto subscription = subscribeRaw(&lcm, cli.get("channel"), &counter, &PingCounter::onMessage);
  subscription->setQueueCapacity(100000);
  if (cli.has("ready")) std::ofstream(cli.get("ready")) << "ready\n";
  const int64_t deadline = utimeNow() + static_cast<int64_t>(*cli.getDouble("timeout") * 1e6);
  const int64_t idle_us = static_cast<int64_t>(*cli.getDouble("idle") * 1e6);
  const std::atomic<bool>& stop = installStopHandlers();
  while (!stop && counter.received_ < count && utimeNow() < deadline &&
         (counter.last_utime_ == 0 || utimeNow() - counter.last_utime_ < idle_us)) {
    if (lcm.handleTimeout(50) < 0 && !stop) {  // a signal interrupts it too
      std::cerr << "lcm-ping: error: receiving failed\n";
      return 1;
    }
  }
  std::vector<double> delays = counter.delays_ms_;
  std::sort(delays.begin(), delays.end());
  const double lost_pct = count > 0 ? 100.0 * (count - counter.received_) / count : 0.0;
  std::printf("received %ld\nexpected %ld\nlost_pct %.2f\nduplicates %ld\n", counter.received_, count,
              lost_pct, counter.duplicates_);
  if (counter.received_ < count) std::cerr << "lcm-ping: missing " << counter.missingRanges(10) << "\n";
  if (!delays.empty()) {
    std::printf("delay_ms_min %.3f\ndelay_ms_median %.3f\ndelay_ms_max %.3f\n", delays.front(),
                delays[delays.size() / 2], delays.back());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CommandLine cli("lcm-ping", "Test tool: numbered datagrams to measure loss and delay.");
  cli.positional("MODE", "send or recv");
  cli.option("channel", "NAME", "channel", "LINK_PING");
  cli.option("count", "N", "messages to send / expect", "100");
  cli.option("start", "S", "send: number of the first message", "0");
  cli.option("rate", "HZ", "send: messages per second", "500");
  cli.option("size", "BYTES", "send: message size (at least 16)", "64");
  cli.option("timeout", "S", "recv: give up after this many seconds", "30");
  cli.option("idle", "S", "recv: stop when nothing arrived for this long after the first", "2");
  cli.option("ready", "FILE", "recv: file created once subscribed");
  addLcmUrlOption(cli);
  if (Status s = cli.parse(argc, argv); !s) return usageError("lcm-ping", s.error());
  if (cli.helpRequested()) return std::cout << cli.helpText(), 0;
  const std::string mode = cli.positionalValue(0);
  if (mode != "send" && mode != "recv") return usageError("lcm-ping", "MODE must be send or recv");
  for (const char* name : {"count", "size", "start"}) {
    if (!cli.getInt(name) || *cli.getInt(name) < 0) return usageError("lcm-ping", std::string("--") + name + " must be >= 0");
  }
  for (const char* name : {"rate", "timeout", "idle"}) {
    if (!cli.getDouble(name) || !(*cli.getDouble(name) > 0)) return usageError("lcm-ping", std::string("--") + name + " must be > 0");
  }
  auto lcm = openLcm(cli.get("lcm-url"));
  if (!lcm) return usageError("lcm-ping", lcm.error());
  return mode == "send" ? send(**lcm, cli) : receive(**lcm, cli);
}
