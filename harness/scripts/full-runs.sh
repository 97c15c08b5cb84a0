#!/usr/bin/env bash
# Every case x method of the golden manifest over the case's full duration (ctest only runs the
# short golden horizons): writes OUT_DIR/<id>/{trace.csv,summary.json,log.txt}, evaluates the
# cases' method comparisons (OUT_DIR/<case>.compare.txt) and prints a table (OUT_DIR/table.txt).
# docs/cases.md, "Commands". Takes minutes (the experiments are 40-120 s of simulated time each).
#
# Usage: harness/scripts/full-runs.sh [-b BUILD_DIR] [-o OUT_DIR] [-j JOBS] [-m MANIFEST] [-s PATH=VALUE]... [ID ...]
#   ID: CASE.METHOD or CASE (see `lexdyn-harness golden list`); none: all of the manifest.
#   -s: an override of every run (`run --set`, docs/cases.md "Overrides"), e.g.
#       sim.integrator.jacobian=difference_quotient; repeat -s for several.
#   defaults: build/, out/full-runs, 2 jobs, golden/manifest.yaml.
# Exit codes (harness/scripts/exit-codes.sh): the worst of the runs and comparisons (130/143
# interrupted, 2 bad input, 3 a run stopped early or wrote no summary, 1 a check or comparison
# failed, 0 everything passed); the table is printed in every case. Some runs are expected to fail
# (exp1-gn, exp1-wls-weak; docs/results.md), so a full set of runs exits 1 or 3.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
BUILD="$ROOT/build"
OUT="$ROOT/out/full-runs"
JOBS=2
MANIFEST="$ROOT/golden/manifest.yaml"
SET=""
lexdyn_options "[-b BUILD_DIR] [-o OUT_DIR] [-j JOBS] [-m MANIFEST] [-s PATH=VALUE]... [ID ...]" b=BUILD o=OUT j=JOBS m=MANIFEST s=SET+ -- "$@"
lexdyn_harness full-runs " (cmake --build $BUILD)"
mkdir -p "$OUT"
lexdyn_golden_list "$MANIFEST" "${LEXDYN_OPERANDS[@]}" > "$OUT/runs.txt"   # ID CASE_FILE METHOD

run_one() {
  local id="$1" case_file="$2" method="$3" dir="$OUT/$1"
  local args=(run "$case_file" --out "$dir" --quiet)
  [ "$method" != "-" ] && args+=(--method "$method")
  local kv
  while IFS= read -r kv; do
    [ -z "$kv" ] || args+=(--set "$kv")
  done <<< "$SET"
  mkdir -p "$dir"
  echo "[full-runs] start $id" >&2
  local code=0
  "$HARNESS" "${args[@]}" > "$dir/log.txt" 2>&1 || code=$?
  echo "$code" > "$dir/exit_code"
  echo "[full-runs] done  $id (exit $code): $(head -1 "$dir/log.txt")" >&2
}
export -f run_one
export HARNESS OUT SET
xargs -P "$JOBS" -L 1 bash -c 'run_one "$0" "$1" "$2"' < "$OUT/runs.txt"

# The method comparisons of the cases that have some, on the traces just written.
compare_case() {  # NAME CASE_FILE TRACE ...
  local name="$1" case_file="$2" code=0
  shift 2
  "$HARNESS" compare --case "$case_file" "$@" > "$OUT/$name.compare.txt" 2>&1 || code=$?
  echo "$code" > "$OUT/$name.compare.exit_code"
}
lexdyn_each_comparison "$OUT/runs.txt" "$OUT" compare_case

# The table (harness/scripts/summary_table.py), then the comparisons.
set +e
/usr/bin/python3 "$ROOT/harness/scripts/summary_table.py" --errors right_hand,left_hand \
  $(cut -d' ' -f1 "$OUT/runs.txt" | sed "s#.*#&=$OUT/&#") > "$OUT/table.txt"
table=$?
set -e
for f in "$OUT"/*.compare.txt; do
  [ -f "$f" ] && printf '\n%s:\n%s\n' "$(basename "$f")" "$(cat "$f")" >> "$OUT/table.txt"
done
cat "$OUT/table.txt"
# The worst exit code of the runs (a run without a summary is a run failure) and comparisons.
status=0
[ "$table" -eq 0 ] || status=3
while read -r id cf m; do
  code=3
  [ -f "$OUT/$id/summary.json" ] && [ -f "$OUT/$id/exit_code" ] && code=$(cat "$OUT/$id/exit_code")
  status=$(lexdyn_worse "$status" "$code")
done < "$OUT/runs.txt"
for f in "$OUT"/*.compare.exit_code; do
  [ -f "$f" ] && status=$(lexdyn_worse "$status" "$(cat "$f")")
done
echo "full-runs: exit code $status (docs/architecture.md, \"Errors and exit codes\")" >&2
exit "$status"
