#!/usr/bin/env bash
# Engine time per step with concave grains as convex pieces against their hulls
# (engine.concave_shapes), measured by resuming one checkpoint of a Bullet run for STEPS steps
# in each mode, ROUNDS times, alternated (docs/performance.md, "Concave grains as convex pieces").
#
#   bash scripts/bench-concave-shapes.sh RUN_DIR SCENARIO [STEPS] [ROUNDS]
#
# RUN_DIR holds the run's checkpoint (it is copied, never changed); SCENARIO is the file the run
# was started from (with its --set options, if any, written into it). Binary: build/crumble
# (CRUMBLE). Prints, per run, the engine seconds of the resumed steps (summary.json
# time_breakdown_s) and the concave shapes and pieces Bullet built.
set -euo pipefail
cd "$(dirname "$0")/.."
run=${1:?run folder with checkpoint.json}
scenario=${2:?scenario file of that run}
steps=${3:-15}
rounds=${4:-2}
crumble=${CRUMBLE:-./build/crumble}
at=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['state']['step'])" "$run/checkpoint.json")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for round in $(seq "$rounds"); do
  for mode in convex_pieces convex_hull; do
    d="$tmp/$mode.$round"
    cp -r "$run" "$d"
    "$crumble" run "$scenario" --out "$d" --resume --threads 1 --quiet \
      --set simulation.max_steps=$((at + steps)) --set engine.concave_shapes=$mode 2>/dev/null || true
    python3 - "$d" "$mode" "$steps" <<'PY'
import json, sys
s = json.load(open(sys.argv[1] + "/summary.json"))
e = s["time_breakdown_s"]["engine"]
print(f"{sys.argv[2]:14s} engine {e:8.2f} s for {sys.argv[3]} steps ({e / int(sys.argv[3]):.2f} s/step); "
      f"compound shapes {s.get('engine_compound_shapes', 0):.0f}, pieces {s.get('engine_compound_pieces', 0):.0f}")
PY
    rm -rf "$d"
  done
done
