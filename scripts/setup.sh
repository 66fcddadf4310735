#!/usr/bin/env bash
# Installs the Debian 12 packages crumble needs (only those missing), then configures and
# builds crumble in ./build (binary: build/crumble). Run as root on a fresh machine, or as a
# user when the packages are already there. Extra arguments go to cmake's configure step.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(g++ cmake make pkg-config libbullet-dev libode-dev libeigen3-dev libcgal-dev
          nlohmann-json3-dev libgtest-dev libcli11-dev
          python3-vtk9)  # python3-vtk9: the suite reads the ParaView files back (tests/integration/paraview)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  if [ "$(id -u)" -ne 0 ]; then
    echo "setup: missing packages and not root; run: sudo apt-get install ${missing[*]}" >&2
    exit 1
  fi
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

jobs=$(nproc 2>/dev/null || echo 2)
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build build -j"$jobs"
