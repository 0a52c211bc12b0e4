// A second thread a caller lends to one query: the kernel starts no threads of its own. A caller
// with a core to spare (a drag session: engine/scenes/second_hand.h) passes one, and a query
// whose work turns out large enough finishes on both (kernel/query/mesh_distance.cpp).
#pragma once

#include <functional>

namespace gk {

class SpareThread {
 public:
  virtual ~SpareThread() = default;
  // Runs job on the other thread; wait() is called before the next start.
  virtual void start(std::function<void()> job) = 0;
  // Returns once the job has finished; what it threw is thrown here.
  virtual void wait() = 0;
};

}  // namespace gk
