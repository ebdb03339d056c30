#include "common/allocator.h"

#if defined(RGBDSLAM_JEMALLOC)
#include <jemalloc/jemalloc.h>

#include <cstdio>

namespace {
// Purging on jemalloc's background threads instead of inside whichever malloc or free
// crosses the decay's deadline, the tracking thread's among them. Turned on through the
// "background_thread" control, which jemalloc(3) gives as the reliable way (the option of
// the same name, read as jemalloc starts, "may cause crash or deadlock during
// initialization"). This runs during static initialisation, on the main thread before main:
// jemalloc's first background thread is created here, and it creates the others itself, so
// none of them inherits the SCHED_FIFO the tracking thread takes later
// (tracker_node.realtime_priority).
bool startBackgroundPurging() {
  bool on = true;
  if (mallctl("background_thread", nullptr, nullptr, &on, sizeof(on)) == 0) return true;
  // jemalloc 5.3 leaves the control on when a thread could not be created (pthread_create
  // refused: a limit on threads), and with it on the program's own threads never purge:
  // turned off again, they do.
  bool off = false;
  mallctl("background_thread", nullptr, nullptr, &off, sizeof(off));
  std::fprintf(stderr, "warning: jemalloc's background purging did not start: freed memory goes back to the "
                       "system from the threads that allocate and free\n");
  return false;
}
}  // namespace

// Named in the link of every program that links procs/common (procs/CMakeLists.txt,
// --undefined), so that the linker takes this file from the archive, and with it the
// initialisation above, even where nothing else in the program calls into it.
extern "C" {
extern const bool rgbdslam_allocator_configured;
const bool rgbdslam_allocator_configured = startBackgroundPurging();
}

namespace {
// jemalloc's statistics are a snapshot taken when the epoch advances.
bool refreshStatistics() {
  uint64_t epoch = 1;
  size_t size = sizeof(epoch);
  return mallctl("epoch", &epoch, &size, &epoch, size) == 0;
}
}  // namespace
#endif

namespace rgbdslam {

bool allocatorPurgesInBackground() {
#if defined(RGBDSLAM_JEMALLOC)
  bool on = false;
  size_t size = sizeof(on);
  if (!rgbdslam_allocator_configured || mallctl("background_thread", &on, &size, nullptr, 0) != 0 || !on) return false;
  size_t threads = 0;
  size = sizeof(threads);
  return refreshStatistics() &&
         mallctl("stats.background_thread.num_threads", &threads, &size, nullptr, 0) == 0 && threads > 0;
#else
  return false;
#endif
}

int64_t heapInUseKb() {
#if defined(RGBDSLAM_JEMALLOC)
  if (!refreshStatistics()) return -1;
  size_t allocated = 0;
  size_t size = sizeof(allocated);
  if (mallctl("stats.allocated", &allocated, &size, nullptr, 0) != 0) return -1;
  return static_cast<int64_t>(allocated / 1024);
#else
  return -1;  // the sanitizers' allocators do not say
#endif
}

}  // namespace rgbdslam
