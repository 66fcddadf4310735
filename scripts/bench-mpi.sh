#!/usr/bin/env bash
# Speed-up of `crumble run` with its breakage analyses over MPI ranks (parallel/, docs/performance.md),
# measured in one script on one machine: the same scenario and seed with 1 thread, with N threads,
# and under `mpirun -np N` (one thread per rank); checks that the three give the same results
# (events.csv without its wall-time column, series.csv, the final grains) and prints a Markdown
# table with the machine's load before and after.
#
#   bash scripts/bench-mpi.sh [SCENARIO]      (default: scenarios/oedometer_zhu_zhao_quick.json)
#   env: STRESS (Pa, default 5e6: the run stops at this platen stress, at the scenario's loading
#   rate), RANKS (default 2), CRUMBLE (default build-mpi/crumble: scripts/setup.sh --mpi).
set -euo pipefail
cd "$(dirname "$0")/.."
scenario=${1:-scenarios/oedometer_zhu_zhao_quick.json}
bin=${CRUMBLE:-build-mpi/crumble}
stress=${STRESS:-5e6}
ranks=${RANKS:-2}
[ -x "$bin" ] || { echo "bench-mpi: $bin not found (bash scripts/setup.sh --mpi)" >&2; exit 2; }
command -v mpirun >/dev/null || { echo "bench-mpi: mpirun not found (apt-get install openmpi-bin)" >&2; exit 2; }
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
# The scenario's loading rate, stopped early: ramp_time scaled with max_stress.
read -r max ramp < <(python3 -c "import json,sys; l=json.load(open(sys.argv[1]))['loading']; print(l['max_stress'], l['ramp_time'])" "$scenario")
ramp=$(python3 -c "print($ramp * $stress / $max)")
sets=(--set "loading.max_stress=$stress" --set "loading.ramp_time=$ramp" --set output.plots=false
      --set output.vtk_every=0 --set output.vtk_final=false --set "output.psd_at_stress=[]" --quiet)
out=${OUT:-$(mktemp -d)}
load_before=$(cut -d' ' -f1-3 /proc/loadavg)
"$bin" run "$scenario" --out "$out/threads1" --threads 1 "${sets[@]}"
"$bin" run "$scenario" --out "$out/threads$ranks" --threads "$ranks" "${sets[@]}"
mpirun --oversubscribe -np "$ranks" "$bin" run "$scenario" --out "$out/ranks$ranks" --threads 1 "${sets[@]}"
load_after=$(cut -d' ' -f1-3 /proc/loadavg)
python3 - "$out" "$ranks" "$load_before" "$load_after" "$(nproc)" "$scenario" "$stress" <<'PY'
import csv, json, sys, os
out, n, lb, la, cores, scenario, stress = sys.argv[1:]
runs = [("1 thread", "threads1"), (f"{n} threads", f"threads{n}"), (f"mpirun -np {n}", f"ranks{n}")]
def events(d):
    rows = list(csv.reader(open(os.path.join(out, d, "events.csv"))))
    w = rows[0].index("wall_ms")
    return [r[:w] + r[w + 1:] for r in rows]
ref = runs[0][1]
same = all(events(d) == events(ref) and
           open(os.path.join(out, d, "series.csv")).read() == open(os.path.join(out, ref, "series.csv")).read() and
           open(os.path.join(out, d, "checkpoint.json")).read() == open(os.path.join(out, ref, "checkpoint.json")).read()
           for _, d in runs[1:])
s = {d: json.load(open(os.path.join(out, d, "summary.json"))) for _, d in runs}
base = s[ref]
print(f"scenario {scenario} to {float(stress)/1e6:g} MPa: {base['analyses']} analyses, {base['breakage_events']} "
      f"breakage events, {base['grains_final']} grains at the end; {cores} cores, load average {lb} before, {la} after; "
      f"results identical in the three runs: {'yes' if same else 'NO'}")
print()
print("| run | wall s | loop s (engine + analyses + fragments + rest) | analyses s | fragments s | engine s | analysis share of the loop (1-thread run) | speed-up (wall) | speed-up (analyses) |")
print("|---|---|---|---|---|---|---|---|---|")
def parts(t):  # the seconds of the parts: output_by_writer is inside output, fragments_per_event a rate
    return sum(v for k, v in t.items() if isinstance(v, (int, float)) and k != "fragments_per_event")
for label, d in runs:
    t = s[d]["time_breakdown_s"]
    loop = parts(t)
    b = base["time_breakdown_s"]
    print(f"| {label} | {s[d]['wall_seconds']:.1f} | {loop:.1f} | {t['analyses']:.1f} | {t['fragments']:.1f} | {t['engine']:.1f} | "
          f"{b['analyses'] / parts(b):.2f} | {base['wall_seconds'] / s[d]['wall_seconds']:.2f} | "
          f"{b['analyses'] / t['analyses']:.2f} |")
r = s[f"ranks{n}"]
print()
print("analyses per rank (mpirun run): " + ", ".join(f"rank {i}: {a} ({t:.1f} s)" for i, (a, t) in
      enumerate(zip(r["analyses_per_rank"], r["analysis_seconds_per_rank"]))))
sys.exit(0 if same else 1)
PY
