#!/usr/bin/env bash
# full-runs.sh -s, repeated: every override reaches every run, a value with spaces whole (its
# summary's overrides and its trace's solver options). Usage: test_full_runs_overrides.sh BUILD_DIR
set -u
source "$(dirname "${BASH_SOURCE[0]}")/test_lib.sh"
BUILD="$1"

"$ROOT/harness/scripts/full-runs.sh" -b "$BUILD" -o "$TMP/runs" -j 1 \
  -s "controller.solver={spanning_stages: false, lazy_snapshots: false}" -s controller.solver.max_iterations=77 \
  pointmass-damping.bfgs > "$TMP/out.txt" 2>&1
code=$?
cat "$TMP/out.txt"
check "exit 0" [ "$code" -eq 0 ]
SUMMARY="$TMP/runs/pointmass-damping.bfgs/summary.json"
check "first override in the summary" grep -q '"controller.solver"' "$SUMMARY"
check "second override in the summary" grep -q '"controller.solver.max_iterations"' "$SUMMARY"
check "both in the trace's solver options" \
  grep -q '^# solver_options: max_iterations 77, .*spanning_stages false, lazy_snapshots false' "$TMP/runs/pointmass-damping.bfgs/trace.csv"
# Without -s the controller's defaults.
"$ROOT/harness/scripts/full-runs.sh" -b "$BUILD" -o "$TMP/plain" -j 1 pointmass-damping.bfgs > /dev/null 2>&1
check "defaults without -s" \
  grep -q '^# solver_options: .*spanning_stages true, lazy_snapshots true' "$TMP/plain/pointmass-damping.bfgs/trace.csv"
check "the spanning stages of any rows, structured ones and swap reflectors by default" \
  grep -q '^# solver_options: .*spanning_any_rows true, spanning_structured true, swap_reflectors true$' "$TMP/plain/pointmass-damping.bfgs/trace.csv"
exit "$fail"
