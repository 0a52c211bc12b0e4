#!/usr/bin/env bash
# The test command: installs what is missing, builds, runs the kernel tests under
# AddressSanitizer + UndefinedBehaviorSanitizer, then every test suite of the Release build.
# The shared meshes must be at ../shared/data beside the checkout.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh

echo "== kernel tests under AddressSanitizer + UndefinedBehaviorSanitizer"
cmake -S . -B build-sanitize -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DGATEKEEPER_SANITIZE=ON \
  -DGATEKEEPER_BUILD_BENCHMARKS=OFF > /dev/null
cmake --build build-sanitize -j "$(nproc)" --target kernel_tests
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ./build-sanitize/tests/kernel_tests --gtest_brief=1

echo "== all tests, Release build"
bash scripts/build.sh
ctest --test-dir build --output-on-failure -j "$(nproc)"
