#include "common/process.h"

#include <gtest/gtest.h>

#include <malloc.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <vector>

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

// In a child process that runs this test alone ("threadsafe": the binary again), so that the
// test binary keeps glibc's defaults and no free block left by other tests serves the 1 MB. First what the option
// is for: glibc's threshold rises to a freed 2 MB block, and the next 1 MB block comes from
// the arena (exit 1 if not: then this glibc behaves otherwise and the test says so); with
// the threshold fixed at 128 kB the arena gives its free top back, and the next 1 MB block
// gets its own mapping again (exit 2 if not).
TEST(MallocMmapThreshold, LargeBlocksGetTheirOwnMappingsAgain) {
#if defined(__SANITIZE_ADDRESS__)
  EXPECT_FALSE(setMallocMmapThreshold(128));
  GTEST_SKIP() << "AddressSanitizer's malloc has no mmap threshold: the refusal was checked";
#else
  auto mapped_blocks_with = [](size_t bytes) {
    [[maybe_unused]] static void* volatile escaped;  // so that the compiler cannot leave malloc and free out
    char* block = static_cast<char*>(std::malloc(bytes));
    escaped = block;
    std::memset(block, 1, bytes);
    const size_t mapped = mallinfo2().hblks;
    std::free(block);
    return mapped;
  };
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        const size_t none = mallinfo2().hblks;
        (void)mapped_blocks_with(2u << 20);  // freed: glibc's threshold rises to 2 MB
        if (mapped_blocks_with(1u << 20) != none) std::exit(1);
        if (!setMallocMmapThreshold(128)) std::exit(3);
        (void)mapped_blocks_with(1u << 20);  // from the arena's free top, which its free gives back
        std::exit(mapped_blocks_with(1u << 20) == none + 1 ? 0 : 2);
      },
      testing::ExitedWithCode(0), "");
#endif
}

// tracker_node.malloc_arena_max: with at most one arena, threads that allocate share the
// main arena (malloc_info lists one heap); without the limit, glibc gives them their own.
// Each case in a child process: arenas, once made, stay.
TEST(MallocArenaMax, ThreadsShareTheArenasAllowed) {
#if defined(__SANITIZE_ADDRESS__)
  EXPECT_FALSE(setMallocArenaMax(1));
  GTEST_SKIP() << "AddressSanitizer's malloc has no arenas: the refusal was checked";
#else
  auto heaps_after_threads = [] {
    std::vector<std::thread> threads;
    for (int i = 0; i < 3; ++i) {
      threads.emplace_back([] {
        [[maybe_unused]] static void* volatile escaped;
        void* block = std::malloc(4096);
        escaped = block;
        std::free(block);
      });
    }
    for (std::thread& t : threads) t.join();
    char* text = nullptr;
    size_t size = 0;
    FILE* out = open_memstream(&text, &size);
    malloc_info(0, out);
    std::fclose(out);
    int heaps = 0;
    for (const char* at = text; (at = std::strstr(at, "<heap nr=")) != nullptr; ++at) ++heaps;
    std::free(text);
    return heaps;
  };
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        if (!setMallocArenaMax(1)) std::exit(3);
        std::exit(heaps_after_threads() == 1 ? 0 : 2);
      },
      testing::ExitedWithCode(0), "");
  EXPECT_EXIT(std::exit(heaps_after_threads() > 1 ? 0 : 2), testing::ExitedWithCode(0), "")
      << "glibc's default gives threads arenas of their own";
  EXPECT_TRUE(setMallocArenaMax(0));  // changes nothing
  const Status negative = setMallocArenaMax(-1);
  ASSERT_FALSE(negative);
  EXPECT_NE(negative.error().find("arenas"), std::string::npos) << negative.error();
#endif
}

TEST(MallocMmapThreshold, ZeroKeepsTheDefaultAndAnOutOfRangeThresholdIsAnError) {
  EXPECT_TRUE(setMallocMmapThreshold(0));
  for (int kb : {-1, 40000}) {
    const Status set = setMallocMmapThreshold(kb);
    ASSERT_FALSE(set) << kb;
    EXPECT_NE(set.error().find("mmap threshold"), std::string::npos) << set.error();
  }
}

}  // namespace
}  // namespace rgbdslam
