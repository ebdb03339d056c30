#include "rgbdslam/util/background_worker.h"

namespace rgbdslam {

BackgroundWorker::~BackgroundWorker() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
    jobs_.clear();
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

size_t BackgroundWorker::pending() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return jobs_.size() + (running_job_ ? 1 : 0);
}

void BackgroundWorker::enqueue(std::function<void()> job) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    jobs_.push_back(std::move(job));
    if (!thread_.joinable()) thread_ = std::thread([this] { loop(); });
  }
  wake_.notify_one();
}

void BackgroundWorker::loop() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return stop_ || !jobs_.empty(); });
    if (stop_) return;
    std::function<void()> job = std::move(jobs_.front());
    jobs_.pop_front();
    running_job_ = true;
    lock.unlock();
    job();  // never throws: an exception is kept in the promise for the reader
    job = nullptr;  // what it captured goes now, outside the lock
    lock.lock();
    running_job_ = false;
  }
}

}  // namespace rgbdslam
