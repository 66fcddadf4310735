#!/usr/bin/env bash
# Speed of crumble's lsdem engine as a ratio against YADE's level-set DEM on the same scene
# (YADE's examples/levelSet/discharge.py: 1000 superellipsoids, 2000 nodes each), both on
# one core, in one script. YADE's loose phase (steps 20–220) is timed here; its settled
# phase (≈ 82 ms/step at ≈ 2500 overlaps, after ~1 h of simulation) is the figure recorded in
# docs/performance.md. Needs build/crumble and YADE (apt-get install yade).
set -euo pipefail
cd "$(dirname "$0")/.."
steps=${STEPS:-200}
src=/usr/share/doc/yade/examples/levelSet
command -v yade >/dev/null || { echo "bench: YADE not installed (apt-get install yade)" >&2; exit 2; }
dir=$(mktemp -d)
for f in discharge.py ramFP.py spaceRot.py; do
  if [ -f "$src/$f" ]; then cp "$src/$f" "$dir/"; else zcat "$src/$f.gz" > "$dir/$f"; fi
done
python3 - "$dir/discharge.py" "$steps" <<'PY'
import sys
p, n = sys.argv[1], int(sys.argv[2])
s = open(p).read()
run = "O.run()  # or O.run(nIter+1,True)\nplot.plot()"
if run not in s:
    sys.exit("bench: discharge.py changed; cannot insert the timer")
s = s.replace(run, f"""import time as _t
O.run(20, True)
_t0 = _t.time()
O.run({n}, True)
print('YADE_LOOSE_MS_PER_STEP %.6f' % ((_t.time() - _t0) / {n} * 1e3))
""")
open(p, "w").write(s)
PY
yade_ms=$(cd "$dir" && OMP_NUM_THREADS=1 yade -j1 -n -x discharge.py 2>/dev/null | sed -n 's/^YADE_LOOSE_MS_PER_STEP //p')
rm -rf "$dir"
[ -n "$yade_ms" ] || { echo "bench: could not time YADE" >&2; exit 1; }
crumble_json=$(OMP_NUM_THREADS=1 OMP_WAIT_POLICY=passive ./build/crumble bench lsdem --scenario scenarios/lsdem_discharge.json --steps "$steps" --threads 1)
loose_ms=$(python3 -c 'import json,sys; print(json.loads(sys.argv[1])["loose"]["ms_per_step"])' "$crumble_json")
settled_ms=$(python3 -c 'import json,sys; print(json.loads(sys.argv[1])["settled"]["ms_per_step"])' "$crumble_json")
python3 - "$yade_ms" "$loose_ms" "$settled_ms" "$crumble_json" <<'PY'
import json, sys
y, l, s, c = float(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3]), json.loads(sys.argv[4])
print(json.dumps({"yade_loose_ms_per_step": y, "crumble_loose_ms_per_step": l, "speedup_loose": round(y / l, 1),
                  "yade_settled_ms_per_step_recorded": 82.0, "crumble_settled_ms_per_step": s,
                  "speedup_settled_vs_recorded": round(82.0 / s, 1), "crumble": c}))
PY
