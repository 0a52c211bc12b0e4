// A caller's request to stop long work (a gRPC deadline that passed, a cancelled call, a
// cancelled audit): loops that can run for seconds ask it between units of work and return an
// ErrorCode::kStopped error, so nobody computes an answer nobody waits for.
#pragma once

#include <functional>
#include <utility>

namespace gk {

class StopToken {
 public:
  StopToken() = default;  // never asks to stop
  explicit StopToken(std::function<bool()> should_stop) : should_stop_(std::move(should_stop)) {}
  bool stop_requested() const { return should_stop_ && should_stop_(); }

 private:
  std::function<bool()> should_stop_;
};

}  // namespace gk
