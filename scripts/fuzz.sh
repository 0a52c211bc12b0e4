#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, AddressSanitizer + UndefinedBehaviorSanitizer) and runs
# each for a bounded time: first over the regression inputs of earlier findings
# (tests/fuzz/regressions/<target>/), then fuzzing from the seed corpora (tests/fuzz/seeds and a
# few small files of ../shared/data). Any crash, leak, sanitizer report or timeout fails the run;
# its input is left in build-fuzz/artifacts/<target>/ (add it to tests/fuzz/regressions once fixed).
#   scripts/fuzz.sh [seconds per target, default 20] [targets...]
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_PER_TARGET="${1:-20}"
shift || true
TARGETS=("$@")
[ ${#TARGETS[@]} -gt 0 ] || TARGETS=(mesh_file_fuzzer shape_file_fuzzer bvh_cache_fuzzer machine_model_fuzzer step_request_fuzzer)
SHARED="../shared/data"
bash scripts/install_deps.sh  # clang and libFuzzer on a fresh machine

cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ -DGATEKEEPER_FUZZ=ON \
  -DGATEKEEPER_BUILD_TESTS=OFF -DGATEKEEPER_BUILD_BENCHMARKS=OFF > /dev/null
cmake --build build-fuzz -j "$(nproc)" --target "${TARGETS[@]}"

# A seed file with the selector byte the target reads first (see tests/fuzz/fuzz_input.h).
seed_with_selector() {  # selector source destination
  [ -f "$2" ] || return 0
  { printf "\\x$(printf %02x "$1")"; cat "$2"; } > "$3"
}

export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:allocator_may_return_null=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
for target in "${TARGETS[@]}"; do
  name="${target%_fuzzer}"
  corpus="build-fuzz/corpus/$name"
  artifacts="build-fuzz/artifacts/$name/"
  rm -rf "$artifacts"
  mkdir -p "$corpus" "$artifacts"
  [ -d "tests/fuzz/seeds/$name" ] && cp tests/fuzz/seeds/"$name"/* "$corpus"/
  max_len=65536
  case "$name" in
    mesh_file)
      seed_with_selector 1 "$SHARED/meshes/fcl/rob.obj" "$corpus/rob.obj.seed"
      seed_with_selector 0 "$SHARED/meshes/robots/ur5/collision/base.stl" "$corpus/ur5_base.stl.seed" ;;
    shape_file)
      max_len=262144
      seed_with_selector 0 "$SHARED/step/occt/screw.step" "$corpus/screw.step.seed"
      seed_with_selector 1 "$SHARED/step/occt/Pump_TopCover.brep" "$corpus/pump_top_cover.brep.seed" ;;
    bvh_cache)
      GK_FUZZ_SEED_OUT="$corpus/tetra.bvh.seed" "build-fuzz/tests/fuzz/$target" -runs=0 > /dev/null 2>&1 ;;
  esac
  log="build-fuzz/fuzz-$name.log"
  if [ "$name" = shape_file ]; then
    # OCCT's readers crash on some malformed CAD files; the daemon reads every CAD file in a child
    # process first (engine/parts/cad_sandbox.h, tested end to end by HostileClientE2E), so such a crash
    # is contained. The fuzzer keeps going past them (-fork, -ignore_crashes) and the run fails
    # only when a crash's innermost frame is outside OCCT's libraries (libTK*): ours.
    echo "== $target: fuzzing for ${SECONDS_PER_TARGET} s (crashes inside OCCT are counted, not fatal)"
    "build-fuzz/tests/fuzz/$target" -fork=1 -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1 \
      -max_total_time="$SECONDS_PER_TARGET" -timeout=30 -rss_limit_mb=4096 -max_len="$max_len" \
      -artifact_prefix="$artifacts" "$corpus" > "$log" 2>&1 || true
    # Each crash is replayed alone to see where it happened.
    occt=0 ours=0 unreproduced=0
    for crash in "$artifacts"crash-*; do
      [ -e "$crash" ] || continue
      where=$(timeout 120 "build-fuzz/tests/fuzz/$target" "$crash" 2>&1 | grep "^SUMMARY: " | head -1 || true)
      if [ -z "$where" ]; then unreproduced=$((unreproduced + 1))
      elif echo "$where" | grep -q "(/lib/x86_64-linux-gnu/libTK"; then occt=$((occt + 1))
      else ours=$((ours + 1)); echo "$crash: $where" >&2
      fi
    done
    slow=$(ls "$artifacts" | grep -c "^timeout-" || true)
    grep -E "^#[0-9]+: cov:" "$log" | tail -1 || true
    echo "   inputs that crash OCCT's readers (contained by the child process): $occt; slower than 30 s (the child's" \
      "time limit refuses them): $slow; not reproduced alone: $unreproduced; crashes outside OCCT: $ours"
    if [ "$ours" -gt 0 ]; then
      echo "fuzz.sh: $target crashed outside OCCT: see $log and $artifacts" >&2
      exit 1
    fi
    continue
  fi
  if [ -d "tests/fuzz/regressions/$name" ] && [ -n "$(ls -A "tests/fuzz/regressions/$name")" ]; then
    echo "== $target: regression inputs"
    "build-fuzz/tests/fuzz/$target" -timeout=30 tests/fuzz/regressions/"$name"/*
  fi
  echo "== $target: fuzzing for ${SECONDS_PER_TARGET} s"
  "build-fuzz/tests/fuzz/$target" -max_total_time="$SECONDS_PER_TARGET" -timeout=30 -rss_limit_mb=4096 \
    -max_len="$max_len" -artifact_prefix="$artifacts" -print_final_stats=1 "$corpus" > "$log" 2>&1 || true
  grep -E "stat::number_of_executed_units|stat::peak_rss_mb|^SUMMARY|Test unit written" "$log" || true
  # Any artifact is a finding (crash, leak, timeout, out of memory, slow unit).
  if [ -n "$(ls -A "$artifacts")" ]; then
    grep -A40 "ERROR: " "$log" | head -60 >&2 || true
    echo "fuzz.sh: $target found a failing input: $(ls "$artifacts") (log: $log)" >&2
    exit 1
  fi
done
echo "fuzz.sh: ${#TARGETS[@]} targets, ${SECONDS_PER_TARGET} s each, no findings"
