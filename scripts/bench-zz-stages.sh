#!/usr/bin/env bash
# The full Zhu & Zhao 2019 §5 run (scenarios/oedometer_zhu_zhao.json: 720 grains to 30 MPa) in
# stages of wall time: each call runs (or resumes) it for at most BUDGET seconds, stops it
# cleanly (SIGTERM: every output and a checkpoint written), and prints the stage table of
# `crumble stages`: per MPa the wall time, grains, analyses, breaking analyses, mean analysis
# time and engine time per step, with the power-law fits and the time extrapolated to 30 MPa.
# Call it again to go further; it resumes where the last call stopped.
#
#   bash scripts/bench-zz-stages.sh [BUDGET_S] [OUT] [extra crumble run arguments]
#
# Defaults: BUDGET_S 3600, OUT out/zz_stages, 2 threads (THREADS), binary build/crumble (CRUMBLE).
set -euo pipefail
cd "$(dirname "$0")/.."
budget=${1:-3600}
out=${2:-out/zz_stages}
shift $(( $# > 2 ? 2 : $# )) || true
threads=${THREADS:-2}
crumble=${CRUMBLE:-./build/crumble}
args=(run scenarios/oedometer_zhu_zhao.json --out "$out" --threads "$threads" --quiet "$@")
[ -f "$out/checkpoint.json" ] && args+=(--resume)
echo "bench-zz-stages: $(date -u +%FT%TZ) load $(cut -d' ' -f1-3 /proc/loadavg), budget ${budget} s: $crumble ${args[*]}" >&2
status=0
timeout --signal=TERM --kill-after=600 "$budget" "$crumble" "${args[@]}" || status=$?
# 0: the run reached 30 MPa; 124 (timeout) or 143 (SIGTERM): stopped cleanly, resumable.
case $status in 0|124|143) ;; *) echo "bench-zz-stages: crumble exited with $status" >&2; exit $status ;; esac
"$crumble" stages "$out" --to 30
