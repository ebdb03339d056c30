#include "common/allocator.h"

#if defined(RGBDSLAM_JEMALLOC)
#include <jemalloc/jemalloc.h>

// jemalloc reads its options from this symbol as it starts, before main (jemalloc(3),
// "TUNING"): purging freed pages runs on jemalloc's own background thread instead of inside
// whichever malloc or free crosses the decay's deadline, the tracking thread's among them.
// The background thread starts before main, so it keeps the normal scheduling policy when the
// tracking thread later takes SCHED_FIFO (tracker_node.realtime_priority).
extern "C" {
const char* malloc_conf = "background_thread:true";
}
#else
#include <malloc.h>
#endif

namespace rgbdslam {

std::string allocatorName() {
#if defined(RGBDSLAM_JEMALLOC)
  return "jemalloc";
#elif defined(__SANITIZE_ADDRESS__)
  return "sanitizer";
#else
  return "glibc";
#endif
}

int64_t heapInUseKb() {
#if defined(RGBDSLAM_JEMALLOC)
  // jemalloc's statistics are a snapshot taken when the epoch advances.
  uint64_t epoch = 1;
  size_t size = sizeof(epoch);
  if (mallctl("epoch", &epoch, &size, &epoch, size) != 0) return -1;
  size_t allocated = 0;
  size = sizeof(allocated);
  if (mallctl("stats.allocated", &allocated, &size, nullptr, 0) != 0) return -1;
  return static_cast<int64_t>(allocated / 1024);
#elif defined(__SANITIZE_ADDRESS__)
  return -1;  // ASan's allocator is not glibc's: mallinfo2 does not see it
#else
  const struct mallinfo2 heap = mallinfo2();  // summed over every arena
  return static_cast<int64_t>((heap.uordblks + heap.hblkhd) / 1024);
#endif
}

}  // namespace rgbdslam
