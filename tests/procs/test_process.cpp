#include "common/process.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <thread>

namespace rgbdslam {
namespace {

TEST(MemoryUsage, ReadsTheResidentPeakAndHeapMemoryOfThisProcess) {
  const MemoryUsage before = memoryUsage();
  ASSERT_GT(before.rss_kb, 1000) << "a gtest binary holds more than 1 MB";
  EXPECT_GE(before.peak_rss_kb, before.rss_kb);
#if defined(RGBDSLAM_JEMALLOC)
  EXPECT_GT(before.heap_kb, 0);
#endif
  constexpr size_t kBytes = 64u << 20;
  {
    auto block = std::make_unique<char[]>(kBytes);
    std::memset(block.get(), 1, kBytes);  // touched, so resident
    const MemoryUsage during = memoryUsage();
    EXPECT_GE(during.rss_kb - before.rss_kb, 60 * 1024);
    EXPECT_GE(during.peak_rss_kb, during.rss_kb);
    if (before.heap_kb >= 0) {  // not under AddressSanitizer (process.h)
      EXPECT_GE(during.heap_kb - before.heap_kb, 63 * 1024) << "the block is the program's heap";
    }
    volatile char sink = block[kBytes / 2];
    (void)sink;
  }
  const MemoryUsage after = memoryUsage();
  EXPECT_GE(after.peak_rss_kb - before.rss_kb, 60 * 1024) << "the peak keeps the 64 MB";
  if (before.heap_kb >= 0) {
    EXPECT_LT(after.heap_kb - before.heap_kb, 1024) << "the heap gave the block back";
  }
}

// Run in a thread of its own, so that the test's thread keeps its policy. Where the system
// refuses (no root, CAP_SYS_NICE or RLIMIT_RTPRIO), the refusal must say why, the thread
// stays as it was, and the rest cannot be checked: skipped.
TEST(RealtimePriority, TheCallingThreadAndTheThreadsItStartsAsAsked) {
  std::string error;
  int own = -1, started_reset = -1, started_inherit = -1;
  std::thread([&] {
    const Status set = setRealtimePriority(3, /*reset_on_fork=*/false);
    if (!set) {
      error = set.error();
      own = realtimePriority();
      return;
    }
    own = realtimePriority();
    std::thread([&] { started_inherit = realtimePriority(); }).join();
    ASSERT_TRUE(setRealtimePriority(3, /*reset_on_fork=*/true));
    std::thread([&] { started_reset = realtimePriority(); }).join();
  }).join();
  EXPECT_EQ(realtimePriority(), 0) << "the test's own thread is untouched";
  if (!error.empty()) {
    EXPECT_EQ(own, 0);
    EXPECT_NE(error.find("refused"), std::string::npos) << error;
    GTEST_SKIP() << "SCHED_FIFO not permitted here (" << error << "): the refusal was checked";
  }
  EXPECT_EQ(own, 3);
  EXPECT_EQ(started_inherit, 3) << "without SCHED_RESET_ON_FORK a started thread inherits the policy";
  EXPECT_EQ(started_reset, 0) << "with SCHED_RESET_ON_FORK a started thread runs at the normal priority";
}

TEST(RealtimePriority, APriorityOutsideTheRangeIsAnError) {
  for (int priority : {0, -1, 100}) {
    const Status set = setRealtimePriority(priority);
    ASSERT_FALSE(set) << priority;
    EXPECT_NE(set.error().find("outside SCHED_FIFO's 1-99"), std::string::npos) << set.error();
  }
  EXPECT_EQ(realtimePriority(), 0);
}

}  // namespace
}  // namespace rgbdslam
