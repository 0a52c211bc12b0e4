// ValidateStep answers shared by every callback thread. Each thread has its own validator (and
// its memo), so a repeated question can land on a thread that has not seen it: this cache, keyed
// by the exact request bytes, the machine and its state, answers it from any thread.
#pragma once

#include "gatekeeper/v1/gatekeeper.pb.h"

#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>

namespace gk::server {

class AnswerCache {
 public:
  explicit AnswerCache(std::size_t capacity = 100000) : capacity_(capacity) {}

  std::optional<::gatekeeper::v1::ValidateStepResponse> find(const std::string& key) const {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = answers_.find(key);
    if (it == answers_.end()) return std::nullopt;
    return it->second;
  }

  void store(const std::string& key, const ::gatekeeper::v1::ValidateStepResponse& answer) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (answers_.size() >= capacity_) answers_.clear();  // simple and bounded; misses only cost time
    answers_[key] = answer;
  }

 private:
  std::size_t capacity_;
  mutable std::mutex mutex_;
  std::unordered_map<std::string, ::gatekeeper::v1::ValidateStepResponse> answers_;
};

}  // namespace gk::server
