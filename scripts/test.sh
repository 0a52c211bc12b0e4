#!/usr/bin/env bash
# The test command: installs what is missing, then
#  1. builds the Release tree and runs every test suite in it;
#  2. builds every suite with AddressSanitizer + UndefinedBehaviorSanitizer (float-cast-overflow
#     included) and runs them — the end-to-end suites against the sanitized daemon — but for the
#     volume oracles named below, which run in Release only;
#  3. builds the scene audit's and the server structures' suites with ThreadSanitizer and runs them.
# The daemon itself is not run under TSan: Debian's gRPC is not instrumented, and TSan then reports
# thousands of races inside gRPC's own call machinery, which would bury any of ours (docs/FUZZING.md).
# Compiler outputs go through ccache (CMakeLists.txt), so the three builds cost little once the cache is warm.
# The shared meshes must be at ../shared/data beside the checkout.
#   scripts/test.sh [release|sanitize|thread ...]   (default: all three, in this order)
set -euo pipefail
cd "$(dirname "$0")/.."
STAGES=("$@")
[ ${#STAGES[@]} -gt 0 ] || STAGES=(release sanitize thread)
bash scripts/install_deps.sh

JOBS="$(nproc)"

for stage in "${STAGES[@]}"; do
  case "$stage" in
    release)
      echo "== every suite, Release build"
      bash scripts/build.sh
      ctest --test-dir build --output-on-failure -j "$JOBS"
      ;;
    sanitize)
      echo "== every suite under AddressSanitizer + UndefinedBehaviorSanitizer"
      cmake -S . -B build-sanitize -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DGATEKEEPER_SANITIZE=ON \
        -DGATEKEEPER_BUILD_BENCHMARKS=OFF > /dev/null
      cmake --build build-sanitize -j "$JOBS"
      # The sanitizers look for memory errors and undefined behaviour on code paths; the Release
      # stage checks every answer. So the P4 oracle's random steps are a quarter of Release's 3,000
      # here, and the volume oracles below run in Release only: each repeats, hundreds of times, paths
      # that shorter tests of the same suite run here (measured under the sanitizers: the first eleven
      # took 1,185 of 2,275 s, the fixture session's brute-force frames about 130 s;
      # SceneAudit.TileCheckpointsResume... keeps the resume path covered).
      VOLUME_ORACLES='^(ObjectNeighbours\.EveryMoveListsExactlyTheNeighboursTheAllPairsOracleFinds'
      VOLUME_ORACLES+='|LayoutSession\.EveryFrameEqualsAssessingEveryStaticObject'
      VOLUME_ORACLES+='|CadDepth\.TheReportedDepthFreesTheExactSolids'
      VOLUME_ORACLES+='|PenetrationDepth\.NonConvexPartsGetACertifiedBoundNoWorseThanSampling'
      VOLUME_ORACLES+='|P4Figures\.TheClearanceBracketHoldsTheDenselySampledMinimum'
      VOLUME_ORACLES+='|P4Safety\.(ValidatorAgreesWithPlainAdvancementOnTheWholeBody|ConservativeAdvancementAgreesWithTheOcctSweptSolid'
      VOLUME_ORACLES+='|HullLevelOfDetailNeverClearsWhatTheExactSweepReaches|VerticalPrismHullNeverClearsWhatARotationReaches)'
      VOLUME_ORACLES+='|CadVerdictE2E\.RealCadPartsAtSubDeflectionGapsAgreeWithOcctOrAreInconclusive'
      VOLUME_ORACLES+='|AuditE2E\.AnAuditStoppedPartWayResumesFromItsTilesAndEqualsAnUninterruptedOne'
      VOLUME_ORACLES+='|AssemblySession\.EveryFrameReportsExactlyTheElementsBruteForceFindsInContact)$'
      P4_ORACLE_CASES=750 ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
        ctest --test-dir build-sanitize --output-on-failure -j "$JOBS" --timeout 1800 -E "$VOLUME_ORACLES"
      ;;
    thread)
      echo "== scene audit and server structures under ThreadSanitizer"
      cmake -S . -B build-tsan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DGATEKEEPER_SANITIZE_THREAD=ON \
        -DGATEKEEPER_BUILD_BENCHMARKS=OFF > /dev/null
      cmake --build build-tsan -j "$JOBS" --target scene_audit_tests engine_concurrency_tests
      TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1 ./build-tsan/tests/engine_concurrency_tests --gtest_brief=1
      TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1 ./build-tsan/tests/scene_audit_tests --gtest_brief=1
      ;;
    *)
      echo "test.sh: unknown stage '$stage' (release, sanitize, thread)" >&2
      exit 2
      ;;
  esac
done
echo "test.sh: ${STAGES[*]}: all passed"
