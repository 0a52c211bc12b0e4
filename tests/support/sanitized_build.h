// Whether this test binary was built with AddressSanitizer (scripts/test.sh, stage sanitize): the
// code runs three to ten times slower, so wall-clock budgets in tests are scaled, a result whose
// quality depends on a server-side time budget is not judged there, and randomised property tests
// draw fewer samples.
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

// Randomised property tests run every sample in the Release suite; under AddressSanitizer (which
// looks for memory errors, not for rare geometry) a quarter of them, so that CI stays in budget.
// Counts a test asserts on are scaled the same way.
inline constexpr int kSampleDivisor = kSanitizedBuild ? 4 : 1;
inline constexpr int samples(int n) { return n / kSampleDivisor > 0 ? n / kSampleDivisor : 1; }

}  // namespace gk::testing
