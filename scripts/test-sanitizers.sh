#!/usr/bin/env bash
# The test suite again under sanitizers (docs/RELIABILITY.md):
#   asan: every test (GUI excepted) built with AddressSanitizer + UndefinedBehaviorSanitizer,
#         any report aborts the test (halt_on_error, -fno-sanitize-recover);
#   tsan: the libraries and the non-process test suites of the layers that own threads (robot:
#         FRI backend and simulation; app: control thread, recorder, learning thread, hand-off
#         queues; learning; planning) under ThreadSanitizer. Every test of those executables
#         runs, so a threaded test added later is covered without being listed here.
# Usage: scripts/test-sanitizers.sh [asan|tsan|all]   (build dirs build-asan, build-tsan, or
# $FLEXIROB_ASAN_BUILD_DIR / $FLEXIROB_TSAN_BUILD_DIR). Exit status non-zero on any report.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
which="${1:-all}"
jobs="${FLEXIROB_JOBS:-$(nproc)}"
suppressions="$root/scripts/sanitizer-suppressions"

# -O1 keeps the sanitized builds fast to compile and the stack traces readable; -g1 gives
# file:line in reports at a fraction of the full debug information. The benchmark peers (KDL,
# OMPL) are left out: prebuilt against glibc's allocator, they mix Eigen ABIs with an ASan build
# (app/cli/CMakeLists.txt); this also builds the CLI the way a machine without them does.
common_flags=(-G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG"
              "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" -DFLEXIROB_BUILD_GUI=OFF
              -DFLEXIROB_BUILD_BENCHMARKS=OFF -DFLEXIROB_BENCH_PEERS=OFF)

stage() { echo "== $(date -u +%H:%M:%S) $*" >&2; }

run_asan() {
  local dir="${FLEXIROB_ASAN_BUILD_DIR:-$root/build-asan}"
  stage "asan: configure and build ($dir)"
  # Set before building: test discovery runs the sanitized test executables.
  export ASAN_OPTIONS="halt_on_error=1:abort_on_error=1:detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1"
  export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:suppressions=$suppressions/ubsan.supp"
  export LSAN_OPTIONS="suppressions=$suppressions/lsan.supp:print_suppressions=0"
  cmake -S "$root" -B "$dir" "${common_flags[@]}" -DFLEXIROB_SANITIZE=address,undefined >&2
  cmake --build "$dir" -j "$jobs" >&2
  stage "asan: ctest"
  (cd "$dir" && ctest --output-on-failure -j "$jobs" --timeout 900)
  stage "asan: done"
}

run_tsan() {
  local dir="${FLEXIROB_TSAN_BUILD_DIR:-$root/build-tsan}"
  stage "tsan: configure and build ($dir)"
  export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$suppressions/tsan.supp"
  cmake -S "$root" -B "$dir" "${common_flags[@]}" -DFLEXIROB_SANITIZE=thread >&2
  cmake --build "$dir" -j "$jobs" --target robot_tests app_tests learning_tests planning_tests >&2
  stage "tsan: ctest"
  (cd "$dir" && ctest --output-on-failure -j "$jobs" --timeout 900 -L '^(robot|app|learning|planning)_tests$')
  stage "tsan: done"
}

case "$which" in
  asan) run_asan ;;
  tsan) run_tsan ;;
  all) run_asan; run_tsan ;;
  *) echo "usage: $0 [asan|tsan|all]" >&2; exit 2 ;;
esac
