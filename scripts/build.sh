#!/usr/bin/env bash
# Configures and builds FlexIRob into build/ (or $FLEXIROB_BUILD_DIR). Extra arguments go to
# CMake's configure step.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${FLEXIROB_BUILD_DIR:-$root/build}"
jobs="${FLEXIROB_JOBS:-$(nproc)}"

# Line tables only (-g1) in the default RelWithDebInfo build: backtraces and profiles keep
# file:line, and the build takes about a third less time than with full debug information.
cmake -S "$root" -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE="${FLEXIROB_BUILD_TYPE:-RelWithDebInfo}" \
  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG" "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG" "$@" >&2
cmake --build "$build_dir" -j "$jobs" >&2
