#include "common/process.h"

#include <gtest/gtest.h>

#include <cstring>
#include <memory>

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

}  // namespace
}  // namespace rgbdslam
