#!/usr/bin/env bash
# One command from a fresh Debian 12 machine to a full test run: installs what is missing,
# builds everything, and runs every test suite with CTest.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${FLEXIROB_BUILD_DIR:-$root/build}"
"$root/scripts/install-deps.sh"
"$root/scripts/build.sh"
cd "$build_dir"
# The GUI tests need an X server; without one they run inside a virtual one (Mesa llvmpipe).
if [ -z "${DISPLAY:-}" ]; then
  exec xvfb-run -a -s "-screen 0 1280x800x24" ctest --output-on-failure -j "$(nproc)" --timeout 600
fi
exec ctest --output-on-failure -j "$(nproc)" --timeout 600
