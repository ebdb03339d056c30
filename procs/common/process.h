#pragma once
// The shared process skeleton: signal handling that only sets an atomic flag, the host clock,
// and opening LCM with a clear error. Every main has the same shape:
//   parse arguments -> load and validate configuration (print it) -> build the algorithm ->
//   subscribe handlers -> while (!stop) lcm.handleTimeout(...).
#include <atomic>
#include <cstdint>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <string>

#include "rgbdslam/io/trajectory_io.h"
#include "rgbdslam/mapping/loop_closer.h"
#include "rgbdslam/mapping/mapper.h"
#include "rgbdslam/mapping/map_maintenance.h"
#include "rgbdslam/util/expected.h"
#include "rgbdslam/tracking/keyframe_store.h"

namespace rgbdslam {

// Installs SIGINT/SIGTERM handlers that set the returned flag (and nothing else).
std::atomic<bool>& installStopHandlers();

// Host clock, microseconds since the epoch.
int64_t utimeNow();

// This process's resident memory: now (VmRSS) and its peak so far (VmHWM), from
// /proc/self/status [kB]; -1 where it cannot be read (not Linux, /proc not mounted). Every
// process reports both in its status messages (rss_kb, peak_rss_kb) and prints peak_rss_mb
// at exit, so memory over a long flight can be followed from the ground. heap_kb is what
// the program holds from malloc now (common/allocator.h, heapInUseKb): RSS growing while it
// stays flat is memory the allocator keeps, not the program's data (-1 under the sanitizers).
struct MemoryUsage {
  int64_t rss_kb = -1;
  int64_t peak_rss_kb = -1;
  int64_t heap_kb = -1;
};
MemoryUsage memoryUsage();
// Prints "peak_rss_mb X.X" (or "peak_rss_mb unknown") on stdout, the exit summary's form,
// and "heap_mb X.X", malloc's bytes in use now (what the program holds at exit).
void printPeakRss();
// keyframes_kept_<reason> lines on stdout: why the mapper's keyframes stay (map_maintenance.h).
void printKeyframesKept(const KeyframesKept& kept);
// loop_* and loops_* lines on stdout: the loop closer's counters (loop_closer.h).
void printLoopClosures(const LoopClosureCounters& loops);
// The mapper's parts (mapper.h, "Parts"): started, joined by the loop closer, in the map now.
void printMapParts(const MapParts& parts);
// keyframes_placed_by_anchor, _by_stand_in, keyframes_anchor_missing, _refused (mapper.h).
void printAnchors(const AnchorCounts& anchors);
// The map's keyframes at their poses now, in time order: the final map's trajectory (loops
// closed and parts joined count; each unjoined part in its own frame), as ORB-SLAM2 writes
// KeyFrameTrajectory.txt. rgbd-mapper --keyframes-out and rgbd-slam's ate_keyframes_rmse_m: all
// parts under one alignment, so metres while one is unjoined (map_parts beside it says so).
Trajectory keyframeTrajectory(const Map& map);

// A warning on stderr when the tracker's keyframe store is on tmpfs or ramfs, where its
// bytes are memory after all (tracker.local_map_store_dir). Nothing for a null store.
void warnIfStoreInMemory(const std::string& program, const KeyframeStore* store);

// Puts the calling thread under SCHED_FIFO at 'priority' (1-99). With 'reset_on_fork' the
// threads it starts later run under the normal policy (SCHED_RESET_ON_FORK: an encoder or
// worker thread must not take the core from the thread it serves); without, they inherit it
// (LCM's receive threads, which carry every frame to the tracking thread). Why: on a shared
// flight computer a frame's latency is mostly its wait for a core, not its work
// (docs/design.md, "Threads"). The kernel's real-time throttling (sched_rt_runtime_us, 0.95 s
// a second by default) keeps a runaway thread from locking the machine. An error names the
// system's reason (no root, CAP_SYS_NICE or RLIMIT_RTPRIO): the caller goes on at the normal
// priority.
Status setRealtimePriority(int priority, bool reset_on_fork = true);
// The calling thread's SCHED_FIFO or SCHED_RR priority; 0 under a normal policy.
int realtimePriority();

// Opens LCM at 'url'; an error (not an abort) if the URL is bad or the network unusable.
Expected<std::unique_ptr<lcm::LCM>> openLcm(const std::string& url);

// Subscribes object->method to a channel through LCM's C API, returning the subscription
// (kept by the caller for as long as it may be called; its destructor unsubscribes).
// Used instead of lcm-cpp's member-function subscribe: with liblcm 1.3.1 that path handed
// every process's callback a corrupt handler pointer (AddressSanitizer: heap-buffer-overflow
// in the callback; pose-logger, rgbd-tracker, rgbd-mapper alike), while this one runs clean
// under AddressSanitizer.
class RawSubscription {
 public:
  using Handler = std::function<void(const lcm::ReceiveBuffer*, const std::string&)>;
  RawSubscription(lcm::LCM* lcm, const std::string& channel, Handler handler);
  ~RawSubscription();
  // Messages LCM holds for this subscription before it drops (LCM's default: 30).
  void setQueueCapacity(int messages);
  RawSubscription(const RawSubscription&) = delete;
  RawSubscription& operator=(const RawSubscription&) = delete;

 private:
  lcm::LCM* lcm_;
  Handler handler_;
  lcm_subscription_t* subscription_ = nullptr;
};

template <typename T>
std::unique_ptr<RawSubscription> subscribeRaw(lcm::LCM* lcm, const std::string& channel, T* object,
                                              void (T::*method)(const lcm::ReceiveBuffer*, const std::string&)) {
  return std::make_unique<RawSubscription>(
      lcm, channel, [object, method](const lcm::ReceiveBuffer* buffer, const std::string& name) {
        (object->*method)(buffer, name);
      });
}

// Prints "program: error: message" to stderr and returns the exit status for bad usage (2).
int usageError(const std::string& program, const std::string& message);

}  // namespace rgbdslam
