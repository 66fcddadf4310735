#!/usr/bin/env bash
# Regenerates the option tables of docs/scenarios.md from the registry: every block
#   <!-- options:NAME -->
#   ...
#   <!-- /options -->
# gets the output of `crumble list --options NAME --markdown` (the option table NAME declares
# in the code). The test OptionDocs.* (tests/integration/option_docs) fails when a block
# disagrees with the code; run this after building build/crumble to refresh them.
#
#   scripts/update-option-docs.sh [DOC]        (default docs/scenarios.md; CRUMBLE=path/to/crumble)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bin=${CRUMBLE:-$root/build/crumble}
doc=${1:-$root/docs/scenarios.md}
[[ -x $bin ]] || { echo "update-option-docs: $bin not found; build it first (cmake --build build --target crumble)" >&2; exit 2; }

open_re='^<!-- options:([A-Za-z0-9_]+) -->$'
close='<!-- /options -->'
out=$(mktemp)
trap 'rm -f "$out"' EXIT
in_block=0
n=0
while IFS= read -r line || [[ -n $line ]]; do
  n=$((n + 1))
  if [[ $line =~ $open_re ]]; then
    ((in_block)) && { echo "update-option-docs: $doc:$n: options block inside another" >&2; exit 2; }
    printf '%s\n' "$line" >>"$out"
    if ! "$bin" list --options "${BASH_REMATCH[1]}" --markdown >>"$out"; then
      echo "update-option-docs: $doc:$n: no table for '${BASH_REMATCH[1]}' (not compiled in?); $doc left unchanged" >&2
      exit 2
    fi
    in_block=1
  elif [[ $line == "$close" ]]; then
    printf '%s\n' "$line" >>"$out"
    in_block=0
  elif ((!in_block)); then
    printf '%s\n' "$line" >>"$out"
  fi
done <"$doc"
((in_block)) && { echo "update-option-docs: $doc: an options block has no $close" >&2; exit 2; }
if cmp -s "$out" "$doc"; then
  echo "update-option-docs: $doc is up to date"
else
  cp "$out" "$doc"
  echo "update-option-docs: $doc updated"
fi
