#include "rgbdslam/util/background_worker.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <stdexcept>
#include <vector>

namespace rgbdslam {
namespace {

TEST(BackgroundWorker, RunsJobsInOrderAndGivesEachItsResult) {
  BackgroundWorker worker;
  std::vector<int> order;  // written by the worker thread only, read after the last get()
  std::vector<std::shared_future<int>> results;
  for (int i = 0; i < 20; ++i) {
    results.push_back(worker.submit([i, &order] {
      order.push_back(i);
      return i * i;
    }));
  }
  for (int i = 0; i < 20; ++i) EXPECT_EQ(results[i].get(), i * i);
  ASSERT_EQ(order.size(), 20u);
  for (int i = 0; i < 20; ++i) EXPECT_EQ(order[i], i);
}

TEST(BackgroundWorker, KeepsAJobsExceptionForItsReader) {
  BackgroundWorker worker;
  std::shared_future<int> failed = worker.submit([]() -> int { throw std::runtime_error("no depth"); });
  std::shared_future<int> next = worker.submit([] { return 7; });
  EXPECT_THROW(failed.get(), std::runtime_error);
  EXPECT_EQ(next.get(), 7);  // the worker goes on after a failed job
}

// The tracker's jobs capture a keyframe's images: they must go once the job has run, not
// live as long as the future that holds the result.
TEST(BackgroundWorker, ReleasesWhatAJobCapturedOnceItHasRun) {
  BackgroundWorker worker;
  auto image = std::make_shared<std::vector<float>>(1000, 1.f);
  std::weak_ptr<std::vector<float>> watch = image;
  std::shared_future<size_t> size = worker.submit([image] { return image->size(); });
  image.reset();
  EXPECT_EQ(size.get(), 1000u);
  // The worker drops the job just after it sets the result: wait for that, bounded.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (worker.pending() > 0 && std::chrono::steady_clock::now() < deadline) std::this_thread::yield();
  EXPECT_EQ(worker.pending(), 0u);
  EXPECT_TRUE(watch.expired());
}

TEST(BackgroundWorker, DestructionDropsJobsNotStartedAndTellsTheirReaders) {
  std::atomic<int> ran{0};
  std::shared_future<void> last;
  std::promise<void> release;
  std::thread opener;
  {
    BackgroundWorker worker;
    std::promise<void> started;
    std::shared_future<void> gate = release.get_future().share();
    worker.submit([gate, &started, &ran] {  // holds the thread until the gate opens
      started.set_value();
      gate.wait();
      ++ran;
    });
    for (int i = 0; i < 5; ++i) last = worker.submit([&ran] { ++ran; });
    started.get_future().wait();
    // The gate opens while the destructor waits for the running job.
    opener = std::thread([&release] {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      release.set_value();
    });
  }
  opener.join();
  EXPECT_GE(ran.load(), 1);  // the running job was finished, not abandoned
  // Jobs run in order, so unless all ran (the destructor came after 50 ms) the last was
  // dropped, and its reader is told so instead of waiting for ever.
  if (ran.load() < 6) {
    EXPECT_THROW(last.get(), std::future_error);
  }
}

}  // namespace
}  // namespace rgbdslam
