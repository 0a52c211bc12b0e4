// Pauses LeakSanitizer's accounting for the allocations made while an instance lives (in builds
// with AddressSanitizer; nothing otherwise). Only for allocations a library keeps for the life of
// the process by design, so that the leak check stays on for everything else.
#pragma once

#if defined(__SANITIZE_ADDRESS__)
#define GK_LEAK_CHECKED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define GK_LEAK_CHECKED 1
#endif
#endif

#ifdef GK_LEAK_CHECKED
#include <sanitizer/lsan_interface.h>
#endif

namespace gk::occt {

class LeakCheckPause {
 public:
#ifdef GK_LEAK_CHECKED
  LeakCheckPause() { __lsan_disable(); }
  ~LeakCheckPause() { __lsan_enable(); }
#else
  LeakCheckPause() {}   // user-provided: an instance is never an unused variable
  ~LeakCheckPause() {}
#endif
  LeakCheckPause(const LeakCheckPause&) = delete;
  LeakCheckPause& operator=(const LeakCheckPause&) = delete;
};

}  // namespace gk::occt
