#!/usr/bin/env bash
# Every case x method of the golden manifest over the case's full duration (ctest only runs the
# short golden horizons): writes OUT_DIR/<id>/{trace.csv,summary.json,log.txt}, evaluates the
# cases' method comparisons (OUT_DIR/<case>.compare.txt) and prints a table (OUT_DIR/table.txt).
# docs/cases.md, "Commands". Takes minutes (the experiments are 40-120 s of simulated time each).
#
# Usage: harness/scripts/full-runs.sh [-b BUILD_DIR] [-o OUT_DIR] [-j JOBS] [-m MANIFEST] [ID ...]
#   ID: CASE.METHOD or CASE (see `lexdyn-harness golden list`); none: all of the manifest.
#   defaults: build/, out/full-runs, 2 jobs, golden/manifest.yaml.
# Exit code 0 when every run wrote its summary; failed checks and early stops are in the table.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD="$ROOT/build"
OUT="$ROOT/out/full-runs"
JOBS=2
MANIFEST="$ROOT/golden/manifest.yaml"
while getopts "b:o:j:m:" opt; do
  case "$opt" in
    b) BUILD="$OPTARG" ;;
    o) OUT="$OPTARG" ;;
    j) JOBS="$OPTARG" ;;
    m) MANIFEST="$OPTARG" ;;
    *) echo "usage: $0 [-b BUILD_DIR] [-o OUT_DIR] [-j JOBS] [-m MANIFEST] [ID ...]" >&2; exit 2 ;;
  esac
done
shift $((OPTIND - 1))
HARNESS="$BUILD/bin/lexdyn-harness"
[ -x "$HARNESS" ] || { echo "full-runs: $HARNESS not built (cmake --build $BUILD)" >&2; exit 2; }
mkdir -p "$OUT"
ONLY=()
if [ $# -gt 0 ]; then ONLY=(--only "$(IFS=,; echo "$*")"); fi
"$HARNESS" golden list --manifest "$MANIFEST" "${ONLY[@]}" > "$OUT/runs.txt"   # ID CASE_FILE METHOD

run_one() {
  local id="$1" case_file="$2" method="$3" dir="$OUT/$1"
  local args=(run "$case_file" --out "$dir" --quiet)
  [ "$method" != "-" ] && args+=(--method "$method")
  mkdir -p "$dir"
  echo "[full-runs] start $id" >&2
  "$HARNESS" "${args[@]}" > "$dir/log.txt" 2>&1 || true
  echo "[full-runs] done  $id: $(head -1 "$dir/log.txt")" >&2
}
export -f run_one
export HARNESS OUT
xargs -P "$JOBS" -L 1 bash -c 'run_one "$0" "$1" "$2"' < "$OUT/runs.txt"

# The method comparisons of the cases that have some, on the traces just written.
cut -d' ' -f2 "$OUT/runs.txt" | sort -u | while read -r case_file; do
  grep -q '^comparisons:' "$case_file" || continue
  traces=()
  while read -r id cf m; do
    [ "$cf" = "$case_file" ] && [ -f "$OUT/$id/trace.csv" ] && traces+=("$OUT/$id/trace.csv")
  done < "$OUT/runs.txt"
  [ ${#traces[@]} -ge 2 ] || continue
  name="$(basename "$case_file" .yaml)"
  "$HARNESS" compare --case "$case_file" "${traces[@]}" > "$OUT/$name.compare.txt" 2>&1 || true
done

# The table (harness/scripts/summary_table.py), then the comparisons.
set +e
python3 "$ROOT/harness/scripts/summary_table.py" --errors right_hand,left_hand \
  $(cut -d' ' -f1 "$OUT/runs.txt" | sed "s#.*#&=$OUT/&#") > "$OUT/table.txt"
status=$?
set -e
for f in "$OUT"/*.compare.txt; do
  [ -f "$f" ] && printf '\n%s:\n%s\n' "$(basename "$f")" "$(cat "$f")" >> "$OUT/table.txt"
done
cat "$OUT/table.txt"
exit $status
