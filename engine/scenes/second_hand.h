// A second thread for one drag session's frames: a frame whose exact checks are several hands it
// part of them and does the rest itself, then waits for it; a frame with one heavy neighbour lends
// it to that pair's distance query (kernel/core/spare_thread.h), which finishes on both. On a
// machine with a core to spare such a frame takes about half the time. One per session, started
// on first use; it only ever runs one job at a time, for the frame that gave it.
#pragma once

#include "kernel/core/spare_thread.h"

#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <utility>

namespace gk::engine {

class SecondHand final : public SpareThread {
 public:
  SecondHand() = default;
  SecondHand(const SecondHand&) = delete;
  SecondHand& operator=(const SecondHand&) = delete;
  ~SecondHand() override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      quit_ = true;
    }
    changed_.notify_all();
    if (thread_.joinable()) thread_.join();
  }

  // Runs job on the second thread; wait() must be called before the next start.
  void start(std::function<void()> job) override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      job_ = std::move(job);
      pending_ = true;
      failure_ = nullptr;
      if (!thread_.joinable()) thread_ = std::thread([this] { run(); });
    }
    changed_.notify_all();
  }

  // Returns once the job has finished; what it threw is thrown here.
  void wait() override {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [this] { return !pending_; });
    if (failure_) std::rethrow_exception(std::exchange(failure_, nullptr));
  }

 private:
  void run() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      changed_.wait(lock, [this] { return quit_ || (pending_ && job_); });
      if (quit_) return;
      std::function<void()> job = std::move(job_);
      job_ = nullptr;
      lock.unlock();
      std::exception_ptr failure;
      try {
        job();
      } catch (...) {
        failure = std::current_exception();
      }
      lock.lock();
      failure_ = failure;
      pending_ = false;
      changed_.notify_all();
    }
  }

  std::mutex mutex_;
  std::condition_variable changed_;
  std::thread thread_;
  std::function<void()> job_;
  bool pending_ = false, quit_ = false;
  std::exception_ptr failure_;
};

}  // namespace gk::engine
