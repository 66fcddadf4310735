#!/usr/bin/env bash
# Regenerates the blocks of the docs that the code declares:
#   <!-- options:NAME -->  ...  <!-- /options -->   (docs/scenarios.md)
# gets the output of `crumble list --options NAME --markdown` (the option table NAME declares
# in the code), and
#   <!-- outputs -->  ...  <!-- /outputs -->         (docs/output.md)
# the output of `crumble list --outputs --markdown` (every CSV column and summary.json key,
# declared in output/OutputReference.cpp). The tests OptionDocs.* (tests/integration/option_docs)
# and OutputReference.* (tests/integration/output_reference) fail when a block disagrees with
# the code; run this after building build/crumble to refresh them.
#
#   scripts/update-option-docs.sh [DOC...]   (default docs/scenarios.md docs/output.md; CRUMBLE=path/to/crumble)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bin=${CRUMBLE:-$root/build/crumble}
[[ -x $bin ]] || { echo "update-option-docs: $bin not found; build it first (cmake --build build --target crumble)" >&2; exit 2; }
(($#)) || set -- "$root/docs/scenarios.md" "$root/docs/output.md"

options_re='^<!-- options:([A-Za-z0-9_]+) -->$'
outputs_open='<!-- outputs -->'
out=$(mktemp)
trap 'rm -f "$out"' EXIT

# refresh DOC: every generated block replaced by what the code prints now.
refresh() {
  local doc=$1 line n=0 close=''
  : >"$out"
  while IFS= read -r line || [[ -n $line ]]; do
    n=$((n + 1))
    if [[ $line =~ $options_re || $line == "$outputs_open" ]]; then
      [[ -n $close ]] && { echo "update-option-docs: $doc:$n: a generated block inside another" >&2; exit 2; }
      printf '%s\n' "$line" >>"$out"
      if [[ $line == "$outputs_open" ]]; then
        close='<!-- /outputs -->'
        "$bin" list --outputs --markdown >>"$out"
      else
        close='<!-- /options -->'
        if ! "$bin" list --options "${BASH_REMATCH[1]}" --markdown >>"$out"; then
          echo "update-option-docs: $doc:$n: no table for '${BASH_REMATCH[1]}' (not compiled in?); $doc left unchanged" >&2
          exit 2
        fi
      fi
    elif [[ -n $close && $line == "$close" ]]; then
      printf '%s\n' "$line" >>"$out"
      close=''
    elif [[ -z $close ]]; then
      printf '%s\n' "$line" >>"$out"
    fi
  done <"$doc"
  [[ -z $close ]] || { echo "update-option-docs: $doc: a generated block has no $close" >&2; exit 2; }
  if cmp -s "$out" "$doc"; then
    echo "update-option-docs: $doc is up to date"
  else
    cp "$out" "$doc"
    echo "update-option-docs: $doc updated"
  fi
}

for doc in "$@"; do refresh "$doc"; done
