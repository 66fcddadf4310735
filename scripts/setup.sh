#!/usr/bin/env bash
# Installs the Debian 12 packages crumble needs (only those missing), then configures and
# builds crumble in ./build (binary: build/crumble). Run as root on a fresh machine, or as a
# user when the packages are already there.
#
#   bash scripts/setup.sh [--mpi] [--target NAME]... [cmake configure arguments]...
#
# --mpi: also install Open MPI (libopenmpi-dev, openmpi-bin) and build with -DCRUMBLE_MPI=ON in
# ./build-mpi instead (binary build-mpi/crumble; `mpirun -np N build-mpi/crumble run ...` spreads
# the breakage analyses over N ranks, docs/performance.md). The default build needs no MPI.
#
# Without --target everything is built (the crumble binary and every test program: what
# `ctest` needs); `--target crumble` builds only the binary (the README's first command).
# python3-matplotlib draws the PNG figures of a run (scripts/crumble_plot.py); without it a
# run still writes every CSV. pybind11-dev, python3-dev, python3-numpy and python3-pandas give
# the Python package (build/python, docs/python.md; `--target crumble_python` builds only it);
# without them the C++ build goes on and says how to get it.
set -euo pipefail
cd "$(dirname "$0")/.."

targets=()
configure=()
mpi=0
while [ $# -gt 0 ]; do
  case "$1" in
    --mpi) mpi=1; shift ;;
    --target)
      [ $# -ge 2 ] || { echo "setup: --target needs a name (e.g. --target crumble)" >&2; exit 2; }
      targets+=(--target "$2"); shift 2 ;;
    --target=*) targets+=(--target "${1#--target=}"); shift ;;
    *) configure+=("$1"); shift ;;
  esac
done

packages=(g++ cmake make pkg-config libbullet-dev libode-dev libeigen3-dev libcgal-dev
          nlohmann-json3-dev libgtest-dev libcli11-dev zlib1g-dev python3-matplotlib
          pybind11-dev python3-dev python3-numpy python3-pandas)
# Only the test suite reads the ParaView files back (tests/integration/paraview); python3-vtk9
# pulls in Qt, so a build of selected targets (the README's run command) goes without it.
# python3-pytest runs the Python suite (ctest -L python).
[ ${#targets[@]} -eq 0 ] && packages+=(python3-vtk9 python3-pytest)
builddir=build
if [ "$mpi" -eq 1 ]; then
  packages+=(libopenmpi-dev openmpi-bin)
  builddir=build-mpi
  configure+=(-DCRUMBLE_MPI=ON)
fi
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
cmake -S . -B "$builddir" -DCMAKE_BUILD_TYPE=Release ${configure[@]+"${configure[@]}"} >/dev/null
cmake --build "$builddir" -j"$jobs" ${targets[@]+"${targets[@]}"}
