#include "common/process.h"

#include <gtest/gtest.h>

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
#if !defined(__SANITIZE_ADDRESS__)
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

// Run in a thread of its own, so that the test's thread keeps its policy. As root (CI) the
// thread runs under SCHED_FIFO and a thread it starts does not; elsewhere the refusal says
// why and the thread stays as it was.
TEST(RealtimePriority, TheCallingThreadOnlyAndNotTheThreadsItStarts) {
  std::string error;
  int own = -1, child = -1;
  std::thread([&] {
    const Status set = setRealtimePriority(3);
    if (!set) error = set.error();
    own = realtimePriority();
    std::thread([&] { child = realtimePriority(); }).join();
  }).join();
  EXPECT_EQ(realtimePriority(), 0) << "the test's own thread is untouched";
  EXPECT_EQ(child, 0) << "SCHED_RESET_ON_FORK: a started thread runs at the normal priority";
  if (error.empty()) {
    EXPECT_EQ(own, 3);
  } else {
    std::printf("not permitted here (%s): the refusal is checked\n", error.c_str());
    EXPECT_EQ(own, 0);
    EXPECT_NE(error.find("refused"), std::string::npos) << error;
  }
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
