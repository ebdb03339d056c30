#pragma once
// One thread that runs submitted jobs in the order given; a job's result is read through
// the shared_future submit returns, which waits for it when it is not done yet. Used where
// work must leave the per-frame path but its result may be needed later (a keyframe's
// surface samples and features in the tracker): the result does not depend on timing, only
// how long a reader waits does, so a run stays deterministic.
//
// The thread starts with the first job (a worker that is never used costs nothing). The
// destructor drops the jobs not started (their futures report broken_promise), waits for
// the running one and joins.
#include <condition_variable>
#include <deque>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <thread>
#include <type_traits>

namespace rgbdslam {

class BackgroundWorker {
 public:
  BackgroundWorker() = default;
  ~BackgroundWorker();
  BackgroundWorker(const BackgroundWorker&) = delete;
  BackgroundWorker& operator=(const BackgroundWorker&) = delete;

  template <class Job>
  std::shared_future<std::invoke_result_t<Job>> submit(Job job) {
    using Result = std::invoke_result_t<Job>;
    // A promise, not a packaged_task: the future's shared state then holds only the result,
    // and what the job captured goes when the job has run (a packaged_task's state keeps
    // the job, and with it every image it captured, as long as any future lives).
    auto promise = std::make_shared<std::promise<Result>>();
    std::shared_future<Result> result = promise->get_future().share();
    enqueue([promise, job = std::move(job)]() mutable {
      try {
        if constexpr (std::is_void_v<Result>) {
          job();
          promise->set_value();
        } else {
          promise->set_value(job());
        }
      } catch (...) {
        promise->set_exception(std::current_exception());
      }
    });
    return result;
  }

  // Jobs submitted and not finished (waiting or running).
  size_t pending() const;

 private:
  void enqueue(std::function<void()> job);
  void loop();

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::function<void()>> jobs_;
  bool running_job_ = false;
  bool stop_ = false;
  std::thread thread_;
};

}  // namespace rgbdslam
