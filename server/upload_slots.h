// Open upload streams, bounded in number and in idle time: each holds a file descriptor and a
// temporary file, so 1,100 idle header-only streams once exhausted the descriptors and stalled
// health checks. A stream beyond the cap is refused; one idle longer than the limit is cancelled.
#pragma once

#include <grpcpp/grpcpp.h>

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <mutex>
#include <thread>

namespace gk::server {

class UploadSlots {
 public:
  UploadSlots(std::size_t max_open, std::chrono::milliseconds idle_limit) : max_open_(max_open), idle_limit_(idle_limit) {
    reaper_ = std::thread([this] { reap(); });
  }
  ~UploadSlots() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
    }
    wake_.notify_all();
    reaper_.join();
  }
  UploadSlots(const UploadSlots&) = delete;
  UploadSlots& operator=(const UploadSlots&) = delete;

  // A slot for the stream, or 0 when max_open are taken.
  std::uint64_t open(grpc::CallbackServerContext* ctx) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (open_.size() >= max_open_) return 0;
    const std::uint64_t token = next_++;
    open_[token] = {ctx, Clock::now()};
    return token;
  }
  void touch(std::uint64_t token) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = open_.find(token);
    if (it != open_.end()) it->second.last = Clock::now();
  }
  std::size_t open_count() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return open_.size();
  }
  // Before the stream's context goes away (the reaper never touches a released one).
  void release(std::uint64_t token) {
    std::lock_guard<std::mutex> lock(mutex_);
    open_.erase(token);
  }

 private:
  using Clock = std::chrono::steady_clock;
  struct Open {
    grpc::CallbackServerContext* ctx;
    Clock::time_point last;
  };

  void reap() {
    std::unique_lock<std::mutex> lock(mutex_);
    while (!stopping_) {
      wake_.wait_for(lock, std::chrono::milliseconds(250));
      const auto now = Clock::now();
      for (auto it = open_.begin(); it != open_.end();) {
        if (now - it->second.last > idle_limit_) {
          it->second.ctx->TryCancel();  // the stream ends CANCELLED; its reactor releases the slot
          it = open_.erase(it);
        } else {
          ++it;
        }
      }
    }
  }

  const std::size_t max_open_;
  const std::chrono::milliseconds idle_limit_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::map<std::uint64_t, Open> open_;
  std::uint64_t next_ = 1;
  bool stopping_ = false;
  std::thread reaper_;
};

}  // namespace gk::server
