#!/usr/bin/env bash
# Builds the libFuzzer targets of fuzz/ with clang (ASan + UBSan + coverage) and runs each one
# for a bounded time on its committed seed corpus (docs/RELIABILITY.md).
#
# Usage: scripts/fuzz.sh [seconds per target, default 25] [target ...]
# Targets: urdf mesh scene fri model_file itm_file session number_list (default: all).
# FLEXIROB_FUZZ_SEED=N fixes libFuzzer's random seed: every run with the same seed mutates the
# same inputs in the same order, so a gate (CI) checks a reproducible prefix of one sequence,
# which a longer local run with that seed has already covered. Unset: a new seed per run, for
# exploration.
# A crash stops with a non-zero status; its input is copied to fuzz/regressions/<target>/ so
# that, once fixed, CTest replays it in every build (fuzz_regression_<target>). New inputs the
# run finds go to the build directory, not into the committed corpus (merge them by hand with
# -merge=1 when they add coverage worth keeping).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
dir="${FLEXIROB_FUZZ_BUILD_DIR:-$root/build-fuzz}"
jobs="${FLEXIROB_JOBS:-$(nproc)}"
seconds="${1:-25}"
seed_option=()
[ -n "${FLEXIROB_FUZZ_SEED:-}" ] && seed_option=("-seed=$FLEXIROB_FUZZ_SEED")
shift || true
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  targets=(urdf mesh scene fri model_file itm_file session number_list)
fi
cc="${FLEXIROB_FUZZ_CC:-clang-14}"
cxx="${FLEXIROB_FUZZ_CXX:-clang++-14}"

stage() { echo "== $(date -u +%H:%M:%S) $*" >&2; }

stage "fuzz: configure and build ($dir, $cxx)"
cmake -S "$root" -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" \
  -DCMAKE_C_COMPILER="$cc" -DCMAKE_CXX_COMPILER="$cxx" -DFLEXIROB_BUILD_FUZZERS=ON \
  -DFLEXIROB_BUILD_TESTS=OFF -DFLEXIROB_BUILD_GUI=OFF -DFLEXIROB_BUILD_BENCHMARKS=OFF >&2
cmake --build "$dir" -j "$jobs" --target "${targets[@]/#/fuzz_}" >&2

export ASAN_OPTIONS="halt_on_error=1:abort_on_error=1:detect_leaks=1:allocator_may_return_null=0"
export LSAN_OPTIONS="suppressions=$root/scripts/sanitizer-suppressions/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
export FLEXIROB_RESOURCES="$root/resources"
status=0
for target in "${targets[@]}"; do
  stage "fuzz: $target for ${seconds}s"
  work="$dir/fuzz-work/$target"
  artifacts="$dir/fuzz-artifacts/$target/"
  rm -rf "$artifacts"  # only this run's findings are copied to fuzz/regressions
  mkdir -p "$work" "$artifacts"
  # -rss_limit_mb and -malloc_limit_mb: an input that makes a parser allocate more than 2 GB
  # is a finding (absurd sizes must be refused before allocating), not an out-of-memory kill.
  # The regression inputs join the seed corpus: every input that once crashed is run again
  # under ASan and UBSan, and mutated further.
  corpora=("$root/fuzz/corpus/$target")
  [ -d "$root/fuzz/regressions/$target" ] && corpora+=("$root/fuzz/regressions/$target")
  # Each run starts from the committed corpora alone, so that a seeded run is the same
  # everywhere (inputs found by earlier runs on this machine would change the sequence).
  rm -rf "$work"
  mkdir -p "$work"
  if ! "$dir/fuzz/fuzz_$target" "$work" "${corpora[@]}" -max_total_time="$seconds" "${seed_option[@]}" \
      -rss_limit_mb=2560 -malloc_limit_mb=2048 -timeout=10 -max_len=131072 -print_final_stats=1 \
      -artifact_prefix="$artifacts" 2>"$dir/fuzz-$target.log"; then
    status=1
    tail -n 60 "$dir/fuzz-$target.log" >&2
    mkdir -p "$root/fuzz/regressions/$target"
    cp "$artifacts"* "$root/fuzz/regressions/$target/" 2>/dev/null || true
    echo "fuzz: $target crashed; inputs copied to fuzz/regressions/$target/" >&2
  else
    grep -E "stat::number_of_executed_units|stat::peak_rss_mb|cov:" "$dir/fuzz-$target.log" | tail -n 3 >&2 || true
  fi
done
stage "fuzz: done"
exit $status
