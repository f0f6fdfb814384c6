#!/usr/bin/env bash
# Installs the Debian packages FlexIRob needs to build, test and run. Idempotent: packages
# already present are not touched, and nothing is fetched when all are there.
# Runs apt-get directly as root, through sudo otherwise.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev liburdfdom-dev libassimp-dev libbullet-dev libyaml-cpp-dev
  libopenscenegraph-dev libosmesa6-dev
  qt6-base-dev libqt6opengl6-dev qt6-charts-dev qt6-multimedia-dev
  libcli11-dev nlohmann-json3-dev libspdlog-dev libsqlite3-dev libnanoflann-dev zlib1g-dev
  libgtest-dev libgmock-dev libbenchmark-dev liborocos-kdl-dev libompl-dev
  libboost-serialization-dev libboost-filesystem-dev libboost-system-dev
  xvfb xauth fonts-dejavu-core fonts-wqy-microhei
  clang-14 libclang-rt-14-dev
)

missing=()
for package in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$package")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present" >&2
  exit 0
fi

if [ "$(id -u)" -eq 0 ]; then
  as_root=()
elif command -v sudo >/dev/null 2>&1; then
  as_root=(sudo)
else
  echo "install-deps: missing packages (${missing[*]}) and neither root nor sudo" >&2
  exit 1
fi

echo "install-deps: installing ${missing[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
"${as_root[@]}" apt-get update -qq
"${as_root[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
