#include "common/process.h"

#include "common/allocator.h"

#include <sched.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>

namespace rgbdslam {
namespace {
std::atomic<bool> g_stop{false};  // the only global: written by the signal handler
extern "C" void onStopSignal(int) { g_stop.store(true); }
}  // namespace

std::atomic<bool>& installStopHandlers() {
  struct sigaction action {};
  action.sa_handler = onStopSignal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  return g_stop;
}

Status setRealtimePriority(int priority, bool reset_on_fork) {
  const int lowest = sched_get_priority_min(SCHED_FIFO), highest = sched_get_priority_max(SCHED_FIFO);
  if (priority < lowest || priority > highest) {
    return Error{"real-time priority " + std::to_string(priority) + " is outside SCHED_FIFO's " +
                 std::to_string(lowest) + "-" + std::to_string(highest)};
  }
  sched_param param{};
  param.sched_priority = priority;
  // pid 0: the calling thread (Linux schedules threads, not processes).
  if (sched_setscheduler(0, SCHED_FIFO | (reset_on_fork ? SCHED_RESET_ON_FORK : 0), &param) != 0) {
    const int error = errno;
    return Error{"SCHED_FIFO priority " + std::to_string(priority) + " refused: " + std::strerror(error) +
                 (error == EPERM ? " (needs root, CAP_SYS_NICE or an RLIMIT_RTPRIO of at least that)" : "")};
  }
  return Status{};
}

int realtimePriority() {
  const int policy = sched_getscheduler(0) & ~SCHED_RESET_ON_FORK;
  if (policy != SCHED_FIFO && policy != SCHED_RR) return 0;
  sched_param param{};
  return sched_getparam(0, &param) == 0 ? param.sched_priority : 0;
}

MemoryUsage memoryUsage() {
  MemoryUsage usage;
  std::ifstream status("/proc/self/status");
  std::string key;
  int64_t value = 0;
  // Lines "VmHWM:\t   12345 kB"; the value stays -1 if a line is missing or malformed.
  while (status >> key) {
    int64_t* target = key == "VmRSS:" ? &usage.rss_kb : key == "VmHWM:" ? &usage.peak_rss_kb : nullptr;
    if (target && status >> value) *target = value;
    status.ignore(1 << 12, '\n');
  }
  usage.heap_kb = heapInUseKb();
  return usage;
}

void printPeakRss() {
  const MemoryUsage usage = memoryUsage();
  if (usage.peak_rss_kb < 0) {
    std::printf("peak_rss_mb unknown\n");
  } else {
    std::printf("peak_rss_mb %.1f\n", usage.peak_rss_kb / 1024.0);
  }
  if (usage.heap_kb >= 0) std::printf("heap_mb %.1f\n", usage.heap_kb / 1024.0);
}

void printKeyframesKept(const KeyframesKept& kept) {
  std::printf("keyframes_kept_gauge %ld\nkeyframes_kept_young %ld\nkeyframes_kept_few_points %ld\n"
              "keyframes_kept_not_redundant %ld\nkeyframes_kept_bridge %ld\nkeyframes_kept_redundant %ld\n",
              kept.gauge, kept.young, kept.few_points, kept.not_redundant, kept.bridge, kept.redundant);
}

void printMapParts(const MapParts& parts) {
  std::printf("map_parts_started %ld\nmap_parts_joined %ld\nmap_parts %d\n", parts.started, parts.joined, parts.now);
}

void printAnchors(const AnchorCounts& anchors) {
  std::printf("keyframes_placed_by_anchor %ld\nkeyframes_placed_by_stand_in %ld\nkeyframes_anchor_missing %ld\n"
              "keyframes_anchor_refused %ld\n",
              anchors.placed, anchors.stand_in, anchors.missing, anchors.refused);
}

Trajectory keyframeTrajectory(const Map& map) {
  Trajectory trajectory;
  for (const auto& [id, kf] : map.keyframes()) trajectory.push_back(TimedPose{static_cast<double>(kf->utime) * 1e-6, kf->T_w_c});
  std::stable_sort(trajectory.begin(), trajectory.end(), [](const TimedPose& a, const TimedPose& b) { return a.t < b.t; });
  return trajectory;
}

void printLoopClosures(const LoopClosureCounters& loops) {
  std::printf("loop_queries %ld\nloops_recognised %ld\nloops_agreed %ld\nloops_closed %ld\nloops_refused %ld\n"
              "loops_beyond_drift %ld\nloops_ambiguous %ld\n",
              loops.queries, loops.recognised, loops.agreed, loops.closed, loops.refused, loops.beyond_drift,
              loops.ambiguous);
}

void warnIfStoreInMemory(const std::string& program, const KeyframeStore* store) {
  if (!store || !store->inMemory()) return;
  std::cerr << program << ": warning: the keyframe store is on a RAM file system (tmpfs): cold keyframes "
            << "take memory there; set tracker.local_map_store_dir to a directory on storage\n";
}

int64_t utimeNow() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

Expected<std::unique_ptr<lcm::LCM>> openLcm(const std::string& url) {
  auto lcm = std::make_unique<lcm::LCM>(url);
  if (!lcm->good()) {
    return Error{"cannot open LCM at '" + url +
                 "' (bad URL, or no multicast route: try 'ip route add 224.0.0.0/4 dev lo')"};
  }
  return lcm;
}

RawSubscription::RawSubscription(lcm::LCM* lcm, const std::string& channel, Handler handler)
    : lcm_(lcm), handler_(std::move(handler)) {
  subscription_ = lcm_subscribe(
      lcm_->getUnderlyingLCM(), channel.c_str(),
      [](const lcm_recv_buf_t* rbuf, const char* name, void* self) {
        const lcm::ReceiveBuffer buffer{rbuf->data, rbuf->data_size, rbuf->recv_utime};
        static_cast<RawSubscription*>(self)->handler_(&buffer, name);
      },
      this);
}

void RawSubscription::setQueueCapacity(int messages) {
  if (subscription_) lcm_subscription_set_queue_capacity(subscription_, messages);
}

RawSubscription::~RawSubscription() {
  if (subscription_) lcm_unsubscribe(lcm_->getUnderlyingLCM(), subscription_);
}

int usageError(const std::string& program, const std::string& message) {
  std::cerr << program << ": error: " << message << "\n";
  return 2;
}

}  // namespace rgbdslam
