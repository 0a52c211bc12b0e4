// Whether this test binary was built with AddressSanitizer (scripts/test.sh, stage sanitize): the
// code runs three to ten times slower, so wall-clock budgets in tests are scaled, and a result
// whose quality depends on a server-side time budget is not judged there.
#pragma once

namespace gk::testing {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kSanitizedBuild = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kSanitizedBuild = true;
#else
inline constexpr bool kSanitizedBuild = false;
#endif
#else
inline constexpr bool kSanitizedBuild = false;
#endif

// Multiplier for deadlines a test sets on its own calls.
inline constexpr int kTimeScale = kSanitizedBuild ? 8 : 1;

}  // namespace gk::testing
