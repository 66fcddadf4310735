#!/usr/bin/env bash
# Speed of crumble's LPS peridynamics kernel as a ratio against LAMMPS peri/lps on the same
# lattice (the examples/peri cylinder, 3487 points), both on one core, in one script.
# Needs: build/crumble, and LAMMPS (apt-get install lammps). Prints one JSON line.
set -euo pipefail
cd "$(dirname "$0")/.."
steps=1000
input=${LAMMPS_INPUT:-../shared/bench/lammps/in.lps_kernel}
command -v lmp >/dev/null || { echo "bench: LAMMPS not installed (apt-get install lammps)" >&2; exit 2; }
[ -f "$input" ] || { echo "bench: LAMMPS input $input not found" >&2; exit 2; }
dir=$(mktemp -d)
cp "$input" "$dir/in.lps_kernel"
lammps_s=$(cd "$dir" && OMP_NUM_THREADS=1 lmp -in in.lps_kernel -log none 2>/dev/null |
           sed -n 's/^Loop time of \([0-9.e+-]*\) on 1 procs.*/\1/p')
rm -rf "$dir"
[ -n "$lammps_s" ] || { echo "bench: could not read LAMMPS loop time" >&2; exit 1; }
crumble_json=$(OMP_NUM_THREADS=1 ./build/crumble bench pd-kernel --steps "$steps" --threads 1)
crumble_s=$(printf '%s' "$crumble_json" | sed -n 's/.*"wall_seconds":\([0-9.e+-]*\).*/\1/p')
ratio=$(awk -v a="$lammps_s" -v b="$crumble_s" 'BEGIN { printf "%.1f", a / b }')
printf '{"steps":%s,"lammps_peri_lps_seconds":%s,"crumble_seconds":%s,"speedup":%s,"crumble":%s}\n' \
  "$steps" "$lammps_s" "$crumble_s" "$ratio" "$crumble_json"
