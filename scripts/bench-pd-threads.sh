#!/usr/bin/env bash
# One peridynamics analysis of the 2 mm grain (`crumble bench pd-analysis`: the analysis that
# crushes it, Zhu & Zhao 2019 §4.2) on one and on two threads, for one or more binaries,
# alternated ROUNDS times in this script so that every ratio is measured under the same load.
# Prints one JSON line per run, then per binary and thread count the fastest and the median
# of the per-run means, and the crushing force (the same for every run: results do not depend
# on the thread count).
#   scripts/bench-pd-threads.sh [ROUNDS] [BINARY...]     (defaults: 5, build/crumble)
# On a virtual machine the second core is not always there: a run whose CPU time is about
# twice its wall time but whose wall time did not drop ran two threads on one core's worth.
set -euo pipefail
cd "$(dirname "$0")/.."
rounds=${1:-5}
shift || true
[ $# -gt 0 ] || set -- build/crumble
log=$(mktemp)
for ((r = 1; r <= rounds; ++r)); do
  for bin in "$@"; do
    for t in 1 2; do
      "$bin" bench pd-analysis --steps 3 --threads "$t" |
        python3 -c 'import json,sys; d=json.loads(sys.stdin.read()); d["binary"]=sys.argv[1]; print(json.dumps(d))' "$bin" |
        tee -a "$log"
    done
  done
done
python3 - "$log" <<'PY'
import json, statistics, sys
runs = [json.loads(l) for l in open(sys.argv[1])]
keys = sorted({(r["binary"], r["threads"]) for r in runs})
for b, t in keys:
    rs = [r for r in runs if r["binary"] == b and r["threads"] == t]
    w = [r["wall_s_per_analysis"] for r in rs]
    c = [r["cpu_s_per_analysis"] for r in rs]
    print(json.dumps({"binary": b, "threads": t, "runs": len(rs), "wall_s_fastest": round(min(w), 4),
                      "wall_s_median": round(statistics.median(w), 4), "cpu_s_median": round(statistics.median(c), 4),
                      "force_at_split_N": sorted({r["force_at_split_N"] for r in rs}), "steps": sorted({r["steps"] for r in rs})}))
PY
rm -f "$log"
