#!/usr/bin/env bash
# Writes the files the Python readers' tests read (ctest fixture lexdyn_outputs, setup test
# python.outputs): every file here is written by the harness's own tools in this ctest run,
# never by hand.
#   OUT/runs/pointmass-damping.{bfgs,wls}/   two runs of the point mass cut at 2 s (summary.json,
#                                            trace.csv, case.yaml)
#   OUT/runs/pointmass-damping.gn/           a run whose wall-clock check (decides: false) fails
#                                            by an impossible limit: exit code 0 all the same
#   OUT/check.json                           `check --json` of the bfgs run's trace
#   OUT/sweep/                               a 2 x 2 grid sweep of the point mass, wls and bfgs
#   OUT/sweep-timeout/                       its first point with a timeout no run meets
#   OUT/report/, OUT/history.jsonl           report.py over those runs and the sweep, with the
#                                            night's record appended to the history
#   OUT/problems/exp1.gn/tick_NNNNNN.json    the controller's solver problems of the humanoid
#                                            (cases/exp1.yaml, GN) at 0.01 .. 0.015 s (--dump-problems;
#                                            the run itself in OUT/problems/exp1.gn.run/), for the
#                                            bindings' tests (lexdyn-solve against lexdyn.solve)
# Usage: write_outputs.sh HARNESS SOURCE_DIR OUT
set -euo pipefail
HARNESS="$1"; SRC="$2"; OUT="$3"
PY=/usr/bin/python3
rm -rf "$OUT"
mkdir -p "$OUT/runs"
CASE="$SRC/cases/pointmass-damping.yaml"

run() {  # run ID EXPECTED_EXIT_CODE ARGS...
  local id="$1" want="$2" rc=0
  shift 2
  "$HARNESS" run "$CASE" --out "$OUT/runs/$id" --quiet "$@" > "$OUT/runs/$id.log" 2>&1 || rc=$?
  if [ "$rc" != "$want" ]; then
    echo "write_outputs: $id: exit code $rc, expected $want" >&2
    cat "$OUT/runs/$id.log" >&2
    exit 1
  fi
}
run pointmass-damping.bfgs 0 --method bfgs --duration 2
run pointmass-damping.wls 0 --method wls --duration 2
# The controller's status check as the case has it, and a p99 tick time of at most 1 ns: the
# wall-clock check fails on any machine, and decides nothing (docs/cases.md, "Checks").
run pointmass-damping.gn 0 --method gn --duration 2 --set 'expected_failures=[]' \
  --set 'checks=[{name: controller_ok, type: controller_status, allowed: [ok, solver_stopped_early], limit_count: 0},
                 {name: tick_time_p99, type: tick_time, timer: tick, percentile: 99, limit_us: 0.001}]'
printf '%s %s %s\n' pointmass-damping.bfgs "$CASE" bfgs pointmass-damping.wls "$CASE" wls \
  pointmass-damping.gn "$CASE" gn > "$OUT/runs/runs.txt"

# The checks of a trace evaluated again (lexdyn.read_check_results).
rc=0
"$HARNESS" check "$OUT/runs/pointmass-damping.bfgs/trace.csv" --case "$CASE" --json > "$OUT/check.json" 2> "$OUT/check.log" || rc=$?
[ "$rc" = 0 ] || { echo "write_outputs: check --json: exit code $rc" >&2; cat "$OUT/check.log" >&2; exit 1; }

# Solver problems of a humanoid's controller: two consecutive ticks (outside OUT/runs: the
# report reads every run there).
mkdir -p "$OUT/problems"
rc=0
"$HARNESS" run "$SRC/cases/exp1.yaml" --out "$OUT/problems/exp1.gn.run" --quiet --method gn --duration 0.02 \
  --dump-problems "$OUT/problems/exp1.gn" --dump-window 0.01:0.015 > "$OUT/problems/exp1.gn.log" 2>&1 || rc=$?
if [ "$rc" != 0 ] || [ "$(ls "$OUT/problems/exp1.gn" | wc -l)" != 2 ]; then
  echo "write_outputs: exp1.gn with --dump-problems: exit code $rc, $(ls "$OUT/problems/exp1.gn" 2>/dev/null | wc -l) problems (expected 0, 2)" >&2
  cat "$OUT/problems/exp1.gn.log" >&2
  exit 1
fi

# A grid sweep: wls overshoots at damping 1 with kp 2 within 5 s (no_overshoot fails there).
cat > "$OUT/pm-grid.yaml" <<YAML
name: pm-grid
base: $CASE
methods: [wls, bfgs]
seed: 1
sampling: {grid: true}
duration_s: 5.0
parameters:
  - {name: damping, path: controller.params.damping, values: [0.1, 1.0]}
  - {name: kp, path: "controller.tasks[position].gains.kp", values: [0.5, 2.0]}
properties:
  checks: [no_overshoot, controller_ok]
YAML
rc=0
"$HARNESS" sweep run "$OUT/pm-grid.yaml" --out "$OUT/sweep" -j 1 --no-shrink --no-db --quiet > "$OUT/sweep.log" 2>&1 || rc=$?
if [ "$rc" != 0 ] && [ "$rc" != 1 ]; then
  echo "write_outputs: sweep: exit code $rc" >&2
  cat "$OUT/sweep.log" >&2
  exit 1
fi

# The same sweep's first point, runs of 1000 s with a timeout of 0.05 s that none meets: runs that
# stopped early.
sed -e 's/^name: pm-grid/name: pm-grid-timeout/' -e 's/^duration_s: 5.0/duration_s: 1000.0/' "$OUT/pm-grid.yaml" > "$OUT/pm-grid-timeout.yaml"
rc=0
"$HARNESS" sweep run "$OUT/pm-grid-timeout.yaml" --out "$OUT/sweep-timeout" -j 1 --points 1 --timeout 0.05 --no-shrink --no-db --quiet \
  > "$OUT/sweep-timeout.log" 2>&1 || rc=$?
if [ "$rc" != 1 ]; then
  echo "write_outputs: sweep with --timeout 0.05: exit code $rc, expected 1" >&2
  cat "$OUT/sweep-timeout.log" >&2
  exit 1
fi

# The report and the history it appends to.
"$PY" "$SRC/harness/scripts/report.py" --runs "$OUT/runs" --sweeps "$OUT/sweep" --history "$OUT/history.jsonl" \
  --append-history --out "$OUT/report" > "$OUT/report.log" 2>&1 || { cat "$OUT/report.log" >&2; exit 1; }
echo "write_outputs: wrote $OUT"
