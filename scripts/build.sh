#!/usr/bin/env bash
# Configures and builds FlexIRob into build/ (or $FLEXIROB_BUILD_DIR). Extra arguments go to
# CMake's configure step.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${FLEXIROB_BUILD_DIR:-$root/build}"
jobs="${FLEXIROB_JOBS:-$(nproc)}"

cmake -S "$root" -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE="${FLEXIROB_BUILD_TYPE:-RelWithDebInfo}" "$@" >&2
cmake --build "$build_dir" -j "$jobs" >&2
