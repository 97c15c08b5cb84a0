#!/usr/bin/env bash
# bench-sim.sh -B: two builds' runs alternate, each build's figures are printed with the
# differences of the minima, and the traces are compared. Usage: test_bench_sim_compare.sh BUILD_DIR
set -u
source "$(dirname "${BASH_SOURCE[0]}")/test_lib.sh"
BUILD="$1"
CASE="$ROOT/cases/pointmass-damping.yaml"

# The same build twice: identical traces.
"$ROOT/harness/scripts/bench-sim.sh" -n 2 -b "$BUILD" -B "$BUILD" -d 1 "$CASE" > "$TMP/same.txt" 2>&1
code=$?
cat "$TMP/same.txt"
check "same build: exit 0" [ "$code" -eq 0 ]
check "same build: A's figures" grep -q '^\[A\] pointmass-damping' "$TMP/same.txt"
check "same build: B's figures" grep -q '^\[B\] pointmass-damping' "$TMP/same.txt"
check "same build: differences of the minima" grep -q 'B - A (minima): wall' "$TMP/same.txt"
check "same build: traces identical" grep -q 'traces: identical' "$TMP/same.txt"
check "same build: each run's slowest tick" grep -q '^  tick     max:    min .* us, median .* us' "$TMP/same.txt"
# The solver's work peak is deterministic: one line per build, the same for both.
check "same build: the solver's work peak" [ "$(grep -c '^  solver work peak: [0-9]* active-set iterations at .* s, [0-9]* factorised stages at' "$TMP/same.txt")" -eq 2 ]
check "same build: one work peak" [ "$(grep '^  solver work peak' "$TMP/same.txt" | sort -u | wc -l)" -eq 1 ]

# A "build" whose harness integrates with another tolerance: the traces differ.
mkdir -p "$TMP/other/bin"
cat > "$TMP/other/bin/lexdyn-harness" <<SH
#!/usr/bin/env bash
exec "$BUILD/bin/lexdyn-harness" "\$@" --set sim.integrator.rtol=1e-5
SH
chmod +x "$TMP/other/bin/lexdyn-harness"
"$ROOT/harness/scripts/bench-sim.sh" -n 1 -b "$BUILD" -B "$TMP/other" -d 1 "$CASE" > "$TMP/other.txt" 2>&1
code=$?
cat "$TMP/other.txt"
check "other build: exit 0" [ "$code" -eq 0 ]
check "other build: traces differ" grep -q 'traces: differ' "$TMP/other.txt"

# A missing other build is bad input.
"$ROOT/harness/scripts/bench-sim.sh" -n 1 -b "$BUILD" -B "$TMP/nosuchbuild" "$CASE" > /dev/null 2>&1
code=$?
check "missing -B build: exit 2" [ "$code" -eq 2 ]
exit "$fail"
