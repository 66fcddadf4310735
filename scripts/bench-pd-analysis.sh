#!/usr/bin/env bash
# Time of one peridynamics analysis of the 2 mm grain of Zhu & Zhao 2019 (scenarios/single_grain_pd.json)
# for one or more crumble binaries, run one after the other in this script, so that their ratio
# is measured under the same machine load. Per binary: analyses, mean wall time and explicit
# steps per analysis (events.csv), the crushing force, and the user CPU time of the whole run.
#   scripts/bench-pd-analysis.sh [BINARY...]        (default: build/crumble)
#   EVERY_STRESS=0.1e6 scripts/bench-pd-analysis.sh (default 0.2e6 Pa: 13 analyses)
set -euo pipefail
cd "$(dirname "$0")/.."
every=${EVERY_STRESS:-0.2e6}
[ $# -gt 0 ] || set -- build/crumble
TIMEFORMAT='%U %R'
for bin in "$@"; do
  out=$(mktemp -d -u)
  t=$( { time "$bin" run scenarios/single_grain_pd.json --quiet --threads 1 --out "$out" \
           --set schedule.every_stress="$every" >/dev/null 2>&1; } 2>&1 )
  awk -F, -v b="$bin" -v t="$t" -v load="$(cut -d' ' -f1 /proc/loadavg)" '
    NR == 1 { for (k = 1; k <= NF; ++k) col[$k] = k; next }
    { n++; ms += $col["wall_ms"]; st += $col["steps"]; if ($col["outcome"] == "split") f = $col["force_at_split_N"] }
    END { split(t, u, " ");
          printf "{\"binary\":\"%s\",\"analyses\":%d,\"mean_wall_ms\":%.1f,\"mean_steps\":%.0f,\"crushing_force_N\":%s,\"user_s\":%s,\"wall_s\":%s,\"load_1min\":%s}\n",
                 b, n, ms / n, st / n, f == "" ? "null" : f, u[1], u[2], load }' "$out/events.csv"
  rm -rf "$out"
done
