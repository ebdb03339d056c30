#include "common/allocator.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#if defined(RGBDSLAM_JEMALLOC)
#include <fcntl.h>
#include <jemalloc/jemalloc.h>
#include <unistd.h>

#include <cstdio>
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

// Resident memory [kB] from /proc/self/statm, read without allocating.
int64_t residentKb() {
  char text[128] = {};
  const int fd = open("/proc/self/statm", O_RDONLY);
  if (fd < 0) return -1;
  const ssize_t n = read(fd, text, sizeof(text) - 1);
  close(fd);
  long size_pages = 0, resident_pages = 0;
  if (n <= 0 || std::sscanf(text, "%ld %ld", &size_pages, &resident_pages) != 2) return -1;
  return resident_pages * (sysconf(_SC_PAGESIZE) / 1024);
}

// allocator.cpp turned the background threads on (the assertion), and freed pages go back to
// the system while the program goes on. The test's arena decays in 0.2 s instead of 10 s,
// and straight to the system (muzzy decay 0, whatever MALLOC_CONF says), to keep the test
// short; both are set back after. A background thread asleep when the decay time changes
// sleeps out the old one (10 s), so each 0.1 s the test advances its arena's decay epoch
// ("arena.N.decay"), which with background threads on wakes them instead of purging on the
// calling thread. The memory's fall alone would not tell who purged (with the threads off,
// the calling thread would): the assertion on the threads does.
TEST(Allocator, FreedPagesGoBackToTheSystemAsTheProgramGoesOn) {
  ASSERT_TRUE(allocatorPurgesInBackground()) << "allocator.cpp did not start jemalloc's background threads";
  const std::string arena = "arena." + std::to_string(readControl<unsigned>("thread.arena"));
  const std::string dirty = arena + ".dirty_decay_ms", muzzy = arena + ".muzzy_decay_ms";
  const ssize_t old_dirty = readControl<ssize_t>(dirty.c_str()), old_muzzy = readControl<ssize_t>(muzzy.c_str());
  ssize_t short_dirty = 200, no_muzzy = 0;
  ASSERT_EQ(mallctl(dirty.c_str(), nullptr, nullptr, &short_dirty, sizeof(short_dirty)), 0);
  ASSERT_EQ(mallctl(muzzy.c_str(), nullptr, nullptr, &no_muzzy, sizeof(no_muzzy)), 0);

  // 64 MB in 64 kB blocks: above the thread cache's sizes, below a mapping of their own.
  constexpr size_t kBlock = 64 << 10, kBlocks = 1024;
  std::vector<char*> blocks(kBlocks);
  for (char*& block : blocks) {
    block = static_cast<char*>(std::malloc(kBlock));
    std::memset(block, 1, kBlock);  // touched, so resident
  }
  const int64_t held_kb = residentKb();
  for (char* block : blocks) std::free(block);
  int64_t rss_kb = held_kb;
  const std::string decay_now = arena + ".decay";
  for (int i = 0; i < 100 && held_kb - rss_kb < 48 * 1024; ++i) {  // at most 10 s
    mallctl(decay_now.c_str(), nullptr, nullptr, nullptr, 0);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    rss_kb = residentKb();
  }
  EXPECT_GE(held_kb - rss_kb, 48 * 1024) << "resident " << held_kb << " kB with the blocks, " << rss_kb
                                         << " kB 10 s after they were freed";
  ssize_t restore_dirty = old_dirty, restore_muzzy = old_muzzy;
  EXPECT_EQ(mallctl(dirty.c_str(), nullptr, nullptr, &restore_dirty, sizeof(restore_dirty)), 0);
  EXPECT_EQ(mallctl(muzzy.c_str(), nullptr, nullptr, &restore_muzzy, sizeof(restore_muzzy)), 0);
}
#else
TEST(Allocator, SaysNothingInTheInstrumentedBuilds) {
  EXPECT_FALSE(allocatorPurgesInBackground());
  EXPECT_EQ(heapInUseKb(), -1);
}
#endif

}  // namespace
}  // namespace rgbdslam
