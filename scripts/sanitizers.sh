#!/usr/bin/env bash
# The sanitizer sweep, longer than CI's budget allows (CI runs the kernel suite under ASan+UBSan
# and the fuzzers; docs/FUZZING.md):
#  - AddressSanitizer + UndefinedBehaviorSanitizer on every test suite (the daemon the end-to-end
#    suites start is the sanitized one);
#  - ThreadSanitizer on the scene audit (its threads) and on the server's shared structures
#    (tests/server/server_concurrency_test.cpp). The daemon itself is not run under TSan: Debian's
#    gRPC is not instrumented, and TSan then reports thousands of races inside gRPC's own call
#    machinery, which would bury any of ours.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh

echo "== every suite under AddressSanitizer + UndefinedBehaviorSanitizer"
cmake -S . -B build-sanitize -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DGATEKEEPER_SANITIZE=ON \
  -DGATEKEEPER_BUILD_BENCHMARKS=OFF > /dev/null
cmake --build build-sanitize -j "$(nproc)"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir build-sanitize --output-on-failure -j "$(nproc)" --timeout 1800

echo "== scene audit and server structures under ThreadSanitizer"
cmake -S . -B build-tsan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DGATEKEEPER_SANITIZE_THREAD=ON \
  -DGATEKEEPER_BUILD_BENCHMARKS=OFF > /dev/null
cmake --build build-tsan -j "$(nproc)" --target scene_audit_tests server_concurrency_tests
TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1 ./build-tsan/tests/server_concurrency_tests --gtest_brief=1
TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1 ./build-tsan/tests/scene_audit_tests --gtest_brief=1
echo "sanitizers.sh: every suite clean under ASan+UBSan; scene audit and server structures clean under TSan"
