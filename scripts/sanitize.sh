#!/usr/bin/env bash
# AddressSanitizer + UndefinedBehaviorSanitizer (+ LeakSanitizer) run of the unit tests and
# the quick integration tests (issue 10 §5). Configures ./build-asan (RelWithDebInfo at -O1,
# -DCRUMBLE_SANITIZE=address,undefined; a separate tree, so ./build stays a Release build),
# builds only crumble and the test programs it runs, and runs them with every report fatal:
# an ASan or LSan report, or any UBSan finding, fails the test that triggered it. Tests that
# run the CLI run build-asan/crumble, the sanitized binary.
#
#   bash scripts/sanitize.sh              # configure, build, run
#   bash scripts/sanitize.sh -R Lsdem     # extra arguments go to ctest
#
# Environment: JOBS (default: nproc), CRUMBLE_ASAN_DIR (default build-asan).
# Leaks inside the third-party libraries are suppressed by name in scripts/lsan.supp; crumble's
# own code has no suppression.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
dir=${CRUMBLE_ASAN_DIR:-build-asan}
jobs=${JOBS:-$(nproc 2>/dev/null || echo 2)}

# The test programs this script runs (tests/<kind>/<folder> → test_<folder>) and their labels.
mapfile -t unit < <(cd tests/unit && ls -d */ | tr -d /)
integration=(cli guards_cli stress_cli jaw_cli option_docs lsdem_simulation resume extremes)
conformance=(engines models builders)
labels="^(unit/.*|conformance/.*|fuzz|integration/($(IFS='|'; echo "${integration[*]}")))\$"
targets=(crumble test_fuzz)
for t in "${unit[@]}" "${integration[@]}" "${conformance[@]}"; do targets+=("test_$t"); done

# Every report is fatal, and so is the first: a sanitizer finding is a test failure.
export ASAN_OPTIONS="detect_leaks=1:halt_on_error=1:check_initialization_order=1:strict_init_order=1:detect_stack_use_after_return=0:abort_on_error=0"
export LSAN_OPTIONS="suppressions=$root/scripts/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:report_error_type=1"

launcher=()
command -v ccache >/dev/null 2>&1 && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
t0=$(date +%s)
cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g -DNDEBUG" \
      -DCRUMBLE_SANITIZE=address,undefined "${launcher[@]}" >/dev/null
# Test discovery runs each program once at build time, under the same options.
nice -n 10 cmake --build "$dir" --target "${targets[@]}" -j"$jobs"
t1=$(date +%s)
status=0
ctest --test-dir "$dir" -L "$labels" -j"$jobs" --output-on-failure "$@" || status=$?
t2=$(date +%s)
echo "sanitize: build $((t1 - t0)) s, tests $((t2 - t1)) s (labels $labels); ctest exit $status"
exit $status
