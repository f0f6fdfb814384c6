#!/usr/bin/env bash
# One command from a fresh Debian 12 machine to the running GUI: installs what is missing,
# builds, and starts flexirob on its default (simulated KUKA LWR IV in the thesis' setup I).
# Arguments are passed to flexirob (e.g. --robot arm9 --scene arm9_areas).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/scripts/install-deps.sh"
"$root/scripts/build.sh"
gui="${FLEXIROB_BUILD_DIR:-$root/build}/ui/flexirob"
if [ -z "${DISPLAY:-}" ] && [ -z "${WAYLAND_DISPLAY:-}" ]; then
  echo "run: no display found; starting flexirob inside a virtual X server (xvfb-run)" >&2
  exec xvfb-run -a -s "-screen 0 1280x800x24" "$gui" "$@"
fi
exec "$gui" "$@"
