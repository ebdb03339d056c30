#include "common/allocator.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "common/process.h"

#if defined(RGBDSLAM_JEMALLOC)
#include <jemalloc/jemalloc.h>
#endif

namespace rgbdslam {
namespace {

#if defined(RGBDSLAM_JEMALLOC)
template <typename T>
T readControl(const char* name) {
  T value{};
  size_t size = sizeof(value);
  EXPECT_EQ(mallctl(name, &value, &size, nullptr, 0), 0) << name;
  return value;
}

// The processes link jemalloc so that it serves every malloc (the libraries' and
// operator new's too), not only calls made to it by name: a link order that left glibc's
// malloc in front would build and run, with none of the measured effect.
TEST(Allocator, MallocAndNewAreJemallocs) {
  EXPECT_EQ(allocatorName(), "jemalloc");
  const uint64_t before = readControl<uint64_t>("thread.allocated");
  [[maybe_unused]] static void* volatile escaped;  // so that the compiler keeps malloc and new
  void* block = std::malloc(1 << 20);
  escaped = block;
  EXPECT_GE(readControl<uint64_t>("thread.allocated") - before, uint64_t{1} << 20) << "malloc is jemalloc's";
  std::free(block);
  auto object = std::make_unique<char[]>(1 << 20);
  escaped = object.get();
  EXPECT_GE(readControl<uint64_t>("thread.allocated") - before, uint64_t{2} << 20) << "operator new is jemalloc's";
}

// allocator.cpp's malloc_conf was read (background_thread:true), and freed pages go back to
// the system while this thread allocates nothing: the purging runs on jemalloc's background
// thread, not in the next malloc of whichever thread comes by. The test's arena decays in
// 0.2 s instead of 10 s, to keep the test short, and is set back after.
TEST(Allocator, FreedPagesGoBackToTheSystemWithoutFurtherMallocs) {
  ASSERT_TRUE(readControl<bool>("opt.background_thread")) << "allocator.cpp's malloc_conf was not read";
  ASSERT_TRUE(readControl<bool>("background_thread"));
  const unsigned arena = readControl<unsigned>("thread.arena");
  const std::string decay = "arena." + std::to_string(arena) + ".dirty_decay_ms";
  const ssize_t old_decay = readControl<ssize_t>(decay.c_str());
  ssize_t short_decay = 200;
  ASSERT_EQ(mallctl(decay.c_str(), nullptr, nullptr, &short_decay, sizeof(short_decay)), 0);

  // 64 MB in 64 kB blocks: small enough to come from the arena, not a mapping of their own.
  constexpr size_t kBlock = 64 << 10, kBlocks = 1024;
  std::vector<char*> blocks(kBlocks);
  for (char*& block : blocks) {
    block = static_cast<char*>(std::malloc(kBlock));
    std::memset(block, 1, kBlock);  // touched, so resident
  }
  const int64_t held_kb = memoryUsage().rss_kb;
  for (char* block : blocks) std::free(block);
  int64_t rss_kb = held_kb;
  for (int i = 0; i < 100 && held_kb - rss_kb < 48 * 1024; ++i) {  // at most 10 s
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    rss_kb = memoryUsage().rss_kb;
  }
  EXPECT_GE(held_kb - rss_kb, 48 * 1024) << "resident " << held_kb << " kB with the blocks, " << rss_kb
                                         << " kB 10 s after they were freed";
  ssize_t restored = old_decay;
  EXPECT_EQ(mallctl(decay.c_str(), nullptr, nullptr, &restored, sizeof(restored)), 0);
}
#else
TEST(Allocator, NamedInTheBuildsWithoutJemalloc) {
#if defined(__SANITIZE_ADDRESS__)
  EXPECT_EQ(allocatorName(), "sanitizer");
  EXPECT_EQ(heapInUseKb(), -1);
#else
  EXPECT_EQ(allocatorName(), "glibc");
  EXPECT_GT(heapInUseKb(), 0);
#endif
}
#endif

}  // namespace
}  // namespace rgbdslam
