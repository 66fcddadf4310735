#!/usr/bin/env bash
# Installs the Debian 12 packages crumble needs (only those missing), then configures and
# builds crumble in ./build (binary: build/crumble). Run as root on a fresh machine, or as a
# user when the packages are already there.
#
#   bash scripts/setup.sh [--target NAME]... [cmake configure arguments]...
#
# Without --target everything is built (the crumble binary and every test program: what
# `ctest` needs); `--target crumble` builds only the binary (the README's first command).
# python3-matplotlib draws the PNG figures of a run (scripts/crumble_plot.py); without it a
# run still writes every CSV.
set -euo pipefail
cd "$(dirname "$0")/.."

targets=()
configure=()
while [ $# -gt 0 ]; do
  case "$1" in
    --target)
      [ $# -ge 2 ] || { echo "setup: --target needs a name (e.g. --target crumble)" >&2; exit 2; }
      targets+=(--target "$2"); shift 2 ;;
    --target=*) targets+=(--target "${1#--target=}"); shift ;;
    *) configure+=("$1"); shift ;;
  esac
done

packages=(g++ cmake make pkg-config libbullet-dev libode-dev libeigen3-dev libcgal-dev
          nlohmann-json3-dev libgtest-dev libcli11-dev python3-matplotlib)
# Only the test suite reads the ParaView files back (tests/integration/paraview); python3-vtk9
# pulls in Qt, so a build of selected targets (the README's run command) goes without it.
[ ${#targets[@]} -eq 0 ] && packages+=(python3-vtk9)
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
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release ${configure[@]+"${configure[@]}"} >/dev/null
cmake --build build -j"$jobs" ${targets[@]+"${targets[@]}"}
