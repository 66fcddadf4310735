#!/usr/bin/env bash
# Speed of crumble's LPS peridynamics kernel as a ratio against LAMMPS peri/lps on the same
# lattice (the examples/peri cylinder, 3487 points), both on one core, in one script.
# Needs: build/crumble, and LAMMPS (apt-get install lammps). Prints one JSON line.
#
#   scripts/bench-pd-vs-lammps.sh [ROUNDS]      # ROUNDS (default 3): LAMMPS then crumble, alternated
#
# On a shared virtual machine one run of either program varies by up to 40 %: a neighbour's
# burst lands on one side and not the other. So both run ROUNDS times, alternated, and the
# ratio is given of the fastest run of each (the run least disturbed; the usual estimator of a
# benchmark's own cost) and of the medians. Every run's time is in the JSON line.
set -euo pipefail
cd "$(dirname "$0")/.."
steps=1000
rounds=${1:-3}
[[ "$rounds" =~ ^[1-9][0-9]*$ ]] || { echo "bench: ROUNDS must be a positive integer, not '$rounds'" >&2; exit 2; }
input=${LAMMPS_INPUT:-scripts/bench/in.lps_kernel}
command -v lmp >/dev/null || { echo "bench: LAMMPS not installed (apt-get install lammps)" >&2; exit 2; }
[ -f "$input" ] || { echo "bench: LAMMPS input $input not found" >&2; exit 2; }
[ -x build/crumble ] || { echo "bench: build/crumble not built (bash scripts/setup.sh --target crumble)" >&2; exit 2; }
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
cp "$input" "$dir/in.lps_kernel"
lammps=() crumble=()
crumble_json=
for ((r = 0; r < rounds; ++r)); do
  s=$(cd "$dir" && OMP_NUM_THREADS=1 lmp -in in.lps_kernel -log none 2>/dev/null |
      sed -n 's/^Loop time of \([0-9.e+-]*\) on 1 procs.*/\1/p')
  [ -n "$s" ] || { echo "bench: could not read LAMMPS loop time" >&2; exit 1; }
  lammps+=("$s")
  crumble_json=$(OMP_NUM_THREADS=1 ./build/crumble bench pd-kernel --steps "$steps" --threads 1)
  s=$(printf '%s' "$crumble_json" | sed -n 's/.*"wall_seconds":\([0-9.e+-]*\).*/\1/p')
  [ -n "$s" ] || { echo "bench: could not read crumble's wall_seconds" >&2; exit 1; }
  crumble+=("$s")
done
# min and median of a list of numbers
stat() { printf '%s\n' "$@" | sort -g | awk '{ v[NR] = $1 } END { printf "%s %s", v[1], (NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2) }'; }
read -r lmin lmed <<<"$(stat "${lammps[@]}")"
read -r cmin cmed <<<"$(stat "${crumble[@]}")"
join() { local IFS=,; printf '%s' "$*"; }
printf '{"steps":%s,"rounds":%s,"lammps_peri_lps_seconds":[%s],"crumble_seconds":[%s],' \
  "$steps" "$rounds" "$(join "${lammps[@]}")" "$(join "${crumble[@]}")"
printf '"speedup_of_fastest":%s,"speedup_of_medians":%s,"load_average":"%s","crumble_last":%s}\n' \
  "$(awk -v a="$lmin" -v b="$cmin" 'BEGIN { printf "%.1f", a / b }')" \
  "$(awk -v a="$lmed" -v b="$cmed" 'BEGIN { printf "%.1f", a / b }')" \
  "$(cut -d' ' -f1-3 /proc/loadavg)" "$crumble_json"
