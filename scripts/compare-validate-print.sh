#!/usr/bin/env bash
# Behaviour check for a refactoring: `crumble validate FILE --print` (stdout, stderr and exit
# status) of two binaries on every shipped scenario, as shipped and with the other engines,
# models, builders and a preset set. Prints each difference and a count; exits 1 if any.
#
#   scripts/compare-validate-print.sh OLD_CRUMBLE NEW_CRUMBLE
set -uo pipefail
[ $# -eq 2 ] || { echo "usage: $0 OLD_CRUMBLE NEW_CRUMBLE" >&2; exit 2; }
old=$1 new=$2
cd "$(dirname "$0")/.."
variants=("" "engine.type=ode" "engine.type=lsdem" "breakage.type=stress" "breakage.type=peridynamics"
          "breakage.type=bonded_particles" "breakage.type=block_beam" "fragments.type=level_set" "fidelity=fast")
n=0 differ=0
for f in scenarios/*.json; do
  for v in "${variants[@]}"; do
    set_args=()
    [ -n "$v" ] && set_args=(--set "$v")
    a=$("$old" validate "$f" --print "${set_args[@]}" 2>&1; echo "exit $?")
    b=$("$new" validate "$f" --print "${set_args[@]}" 2>&1; echo "exit $?")
    n=$((n + 1))
    if [ "$a" != "$b" ]; then
      differ=$((differ + 1))
      echo "differs: $f ${v:+--set $v}"
      diff <(echo "$a") <(echo "$b") | head -8
    fi
  done
done
echo "compared $n, differing $differ"
[ "$differ" -eq 0 ]
