// A caller's request to stop long work (a gRPC deadline that passed, a cancelled call, a
// cancelled audit): loops that can run for seconds ask it between units of work and return an
// ErrorCode::kStopped error, so nobody computes an answer nobody waits for.
#pragma once

#include <functional>
#include <utility>

namespace gk {

// Traversals ask a StopToken at their first node pair and then once every kStopCheckMask + 1 of
// them (well under a millisecond of work): often enough to stop at once, rarely enough to cost
// nothing measurable.
inline constexpr unsigned long long kStopCheckMask = 4095;

class StopToken {
 public:
  StopToken() = default;  // never asks to stop
  explicit StopToken(std::function<bool()> should_stop) : should_stop_(std::move(should_stop)) {}
  bool stop_requested() const { return should_stop_ && should_stop_(); }

 private:
  std::function<bool()> should_stop_;
};

}  // namespace gk
