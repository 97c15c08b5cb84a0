#!/usr/bin/env bash
# Benchmark of the sweep driver (docs/performance.md, "Sweeps"): points per minute, parallel
# efficiency at -j 1 and -j 2, the driver's overhead per run, on the point-mass sweep (short runs,
# so that overheads show) and on a few exp1 points (runs of about 10 s, the goal's scale).
# Timings compare on one machine only; each figure is the minimum and the median over REPEATS.
#
# Usage: harness/scripts/bench-sweep.sh [-b BUILD_DIR] [-r REPEATS] [-n EXP1_POINTS]
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
BUILD="$ROOT/build"
REPEATS=3
EXP1_POINTS=4
lexdyn_options "[-b BUILD_DIR] [-r REPEATS] [-n EXP1_POINTS]" b=BUILD r=REPEATS n=EXP1_POINTS -- "$@"
lexdyn_harness bench-sweep
W="$(mktemp -d /tmp/lexdyn-bench-sweep.XXXXXX)"
trap 'rm -rf "$W"' EXIT
now() { date +%s.%N; }

# One sweep run into a fresh folder; prints its wall time and the sum of its runs' own wall times.
sweep_once() {  # FILE JOBS POINTS
  local out="$W/out-$RANDOM$RANDOM"
  local t0 t1
  t0=$(now)
  "$HARNESS" sweep run "$1" --out "$out" -j "$2" --points "$3" --no-db --no-shrink --quiet > /dev/null 2>&1 || true
  t1=$(now)
  /usr/bin/python3 - "$out" "$t0" "$t1" << 'EOF'
import sys
import lexdyn
out, t0, t1 = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
runs = 0
inner = 0.0
for point in lexdyn.read_sweep_results(out + "/results.jsonl"):
    for r in point["runs"].values():
        runs += 1
        inner += r["wall_s"]
print(t1 - t0, inner, runs)
EOF
  rm -rf "$out"
}

stats() {  # values on stdin -> "min median"
  python3 -c '
import sys, statistics
v = sorted(float(x) for x in sys.stdin.read().split())
print("%.3f %.3f" % (v[0], statistics.median(v)))'
}

bench() {  # LABEL FILE POINTS
  local label="$1" file="$2" points="$3"
  local j1="" j2="" over="" start=""
  for _ in $(seq "$REPEATS"); do
    # The driver's one-time start: reading and validating the sweep file (a case load per
    # parameter value probed).
    local c0 c1
    c0=$(now); "$HARNESS" sweep check "$file" > /dev/null; c1=$(now)
    start+="$(python3 -c "print($c1 - $c0)") "
    read -r wall inner runs < <(sweep_once "$file" 1 "$points")
    j1+="$wall "
    over+="$(python3 -c "print(($wall - $inner - ($c1 - $c0)) / $runs)") "
    read -r wall2 _ _ < <(sweep_once "$file" 2 "$points")
    j2+="$wall2 "
  done
  read -r j1min j1med < <(echo "$j1" | stats)
  read -r j2min j2med < <(echo "$j2" | stats)
  read -r omin omed < <(echo "$over" | stats)
  read -r smin smed < <(echo "$start" | stats)
  python3 - "$label" "$points" "$runs" "$j1min" "$j1med" "$j2min" "$j2med" "$omin" "$omed" "$inner" "$smin" "$smed" << 'EOF'
import sys
label, points, runs = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
j1min, j1med, j2min, j2med, omin, omed, inner, smin, smed = map(float, sys.argv[4:13])
per_run = inner / runs
print(f"{label}: {points} points x {runs // points} methods ({runs} runs, {per_run:.2f} s each)")
print(f"  -j 1: {j1min:.2f} s min, {j1med:.2f} s median: {60 * points / j1min:.1f} points/min")
print(f"  -j 2: {j2min:.2f} s min, {j2med:.2f} s median: {60 * points / j2min:.1f} points/min; "
      f"parallel efficiency {j1min / (2 * j2min):.0%} (min), {j1med / (2 * j2med):.0%} (median)")
print(f"  driver start (validating the sweep file): {smin:.2f} s min, {smed:.2f} s median, once per sweep")
print(f"  driver overhead per run (sweep wall at -j 1 - the runs' own wall times - the start): {omin * 1000:.0f} ms min, "
      f"{omed * 1000:.0f} ms median = {omin / per_run:.1%} of a run")
EOF
}

echo "machine: $(nproc) cores, $(uname -r), load $(cut -d' ' -f1-3 /proc/loadavg)"
bench "point mass (12 s runs)" "$ROOT/cases/sweeps/pointmass-damping.yaml" 12
# exp1 at full length: a sweep file that runs its first EXP1_POINTS points, bfgs only.
sed -e 's/^methods: .*/methods: [bfgs]/' -e 's#^base: \.\./#base: '"$ROOT"'/cases/#' \
  "$ROOT/cases/sweeps/exp1-gains.yaml" > "$W/exp1-bench.yaml"
bench "exp1 bfgs (120 s runs)" "$W/exp1-bench.yaml" "$EXP1_POINTS"
# The worker's own cost (loading the sweep file and the case) against a plain run of the same
# configuration: exp1 cut at 1 s, so that the fixed costs show.
pw="" pr=""
for _ in $(seq "$REPEATS"); do
  t0=$(now); "$HARNESS" sweep point "$W/exp1-bench.yaml" --value kp=0.3 --method bfgs --duration 1 --out "$W/p" --quiet > /dev/null 2>&1 || true; t1=$(now)
  "$HARNESS" run "$ROOT/cases/exp1.yaml" --method bfgs --set 'controller.tasks[right_hand].gains.kp=0.3' \
    --set 'controller.tasks[left_hand].gains.kp=0.3' --set trace.every_n_ticks=50 --duration 1 --out "$W/q" --quiet > /dev/null 2>&1 || true; t2=$(now)
  pw+="$(python3 -c "print($t1 - $t0)") "
  pr+="$(python3 -c "print($t2 - $t1)") "
done
read -r pwmin pwmed < <(echo "$pw" | stats)
read -r prmin prmed < <(echo "$pr" | stats)
echo "exp1 cut at 1 s: sweep point $pwmin s min ($pwmed median), plain run $prmin s min ($prmed median)"
