#!/usr/bin/env bash
# Integrator accuracy at a case's own tolerances (docs/simulator.md, "Integrator"): runs each
# case as written and again with a tight reference integrator (rtol 1e-8, atol_position 1e-10,
# atol_velocity 1e-8, steps of at most 0.2 ms, difference-quotient Jacobian), then prints the
# largest differences between the two traces over the run: WAIST position, joint positions, joint torques, vertical force of
# each foot, horizontal force at the foot sensors (also after t = 2 s).
#
# With -p N, each case is also run at N relative tolerances spread around its own one,
# rtol x (1 + k STEP) for k = -(N-1)/2 ... (N-1)/2 (STEP 0.01 unless -k; for an odd N the middle
# one is the case as written), against the same reference run, and the script prints per
# quantity (the feet combined) the unperturbed figure, the median and the max over the N runs,
# and the integrator's work (steps, right-hand sides; summary.json). These figures move with
# rounding; the median over the perturbations is the one to compare. --check (with -p) exits 1
# when a median exceeds its documented bound (harness/scripts/lib/sim_accuracy.py, BOUNDS).
#
# Options for the runs under test (the reference run always uses the settings above, with CVODE's
# difference-quotient Jacobian: independent of the applied forces' Jacobian, the default, under test):
#   -s SOLVER   sim.integrator.linear_solver: block_elimination | dense_lu
#   -J JACOBIAN sim.integrator.jacobian: difference_quotient | applied_forces
#   -a ATOL     sim.integrator.atol_velocity
#   -d S        stop every run (the reference too) at S seconds (run --duration)
#   -j J        runs at a time (default 1)
#   -o DIR      keep the runs in DIR (default: a temporary directory, removed at the end)
#
# Usage: harness/scripts/sim-accuracy.sh [-b BUILD_DIR] [-p N [-k STEP] [--check]] [-s SOLVER]
#          [-J JACOBIAN] [-a ATOL] [-d S] [-j J] [-o DIR] [case.yaml ...]
#        (defaults: build/, cases/stand.yaml cases/squat_sway.yaml)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
USAGE="[-b BUILD_DIR] [-p N [-k STEP] [--check]] [-s SOLVER] [-J JACOBIAN] [-a ATOL] [-d S] [-j J] [-o DIR] [case.yaml ...]"
BUILD="$ROOT/build"
NPERT=0
STEP=0.01
SOLVER=""
JACOBIAN=""
ATOLV=""
DURATION=""
JOBS=1
KEEP=""
CHECK=0
args=()
for a in "$@"; do
  if [ "$a" = "--check" ]; then CHECK=1; else args+=("$a"); fi
done
lexdyn_options "$USAGE" b=BUILD p=NPERT k=STEP s=SOLVER J=JACOBIAN a=ATOLV d=DURATION j=JOBS o=KEEP -- ${args[@]+"${args[@]}"}
usage_error() { echo "sim-accuracy: $1" >&2; echo "usage: $0 $USAGE" >&2; exit 2; }
[[ "$NPERT" =~ ^[0-9]+$ ]] || usage_error "-p expects a count, found '$NPERT'"
[[ "$STEP" =~ ^[0-9]*\.?[0-9]+([eE][-+]?[0-9]+)?$ ]] || usage_error "-k expects a relative step, found '$STEP'"
[[ "$JOBS" =~ ^[1-9][0-9]*$ ]] || usage_error "-j expects a positive count, found '$JOBS'"
case "$SOLVER" in ""|block_elimination|dense_lu) ;; *) usage_error "-s expects block_elimination or dense_lu, found '$SOLVER'" ;; esac
case "$JACOBIAN" in ""|difference_quotient|applied_forces) ;; *) usage_error "-J expects difference_quotient or applied_forces, found '$JACOBIAN'" ;; esac
[ "$CHECK" = 0 ] || [ "$NPERT" -ge 1 ] || usage_error "--check needs -p N"
lexdyn_cases ${LEXDYN_OPERANDS[@]+"${LEXDYN_OPERANDS[@]}"}
lexdyn_harness sim-accuracy
PY="$ROOT/harness/scripts/lib/sim_accuracy.py"
if [ -n "$KEEP" ]; then
  mkdir -p "$KEEP"
  OUT="$(cd "$KEEP" && pwd)"
else
  OUT="$(mktemp -d)"
  trap 'rm -rf "$OUT"' EXIT
fi

# Overrides of the runs under test, and the options of every run.
SETS=()
[ -z "$SOLVER" ] || SETS+=(--set "sim.integrator.linear_solver=$SOLVER")
[ -z "$JACOBIAN" ] || SETS+=(--set "sim.integrator.jacobian=$JACOBIAN")
[ -z "$ATOLV" ] || SETS+=(--set "sim.integrator.atol_velocity=$ATOLV")
RUNOPTS=(--quiet)
[ -z "$DURATION" ] || RUNOPTS+=(--duration "$DURATION")

# run_case CASE DIR [ARG ...]: one run; a failed run leaves no trace (the comparison says so).
run_case() {
  local c="$1" dir="$2"
  shift 2
  "$HARNESS" run "$c" --out "$dir" "${RUNOPTS[@]}" "$@" 2>/dev/null || true
}

# run_all: the runs of the lines "CASE DIR [ARG ...]" of stdin (no spaces inside a word), at
# most $JOBS at a time.
run_all() {
  local line running=0
  while read -r line; do
    # shellcheck disable=SC2086
    run_case $line &
    running=$((running + 1))
    if [ "$running" -ge "$JOBS" ]; then wait -n || true; running=$((running - 1)); fi
  done
  wait || true
}

status=0
for c in "${CASES[@]}"; do
  name="$(basename "$c" .yaml)"
  # The reference case: the same file with the integrator settings replaced and the robot
  # paths made absolute (it is written elsewhere).
  python3 - "$c" "$OUT/$name.reference.yaml" <<'PY'
import os, re, sys
src, dst = sys.argv[1], sys.argv[2]
base = os.path.dirname(os.path.abspath(src))
ref = "  integrator: {rtol: 1.0e-8, atol_position: 1.0e-10, atol_velocity: 1.0e-8, max_step_s: 2.0e-4, jacobian: difference_quotient}\n"
out, skip, placed = [], False, False
for line in open(src):
    m = re.match(r"^(\s*)(urdf|data):\s*(\S+)\s*$", line)
    if m and not os.path.isabs(m.group(3)):
        line = f"{m.group(1)}{m.group(2)}: {os.path.normpath(os.path.join(base, m.group(3)))}\n"
    m = re.match(r"^(\s*robot:\s*\{)(.*)(\}\s*)$", line)
    if m:
        parts = [p.strip() for p in m.group(2).split(",")]
        fixed = []
        for p in parts:
            k, v = [x.strip() for x in p.split(":", 1)]
            fixed.append(f"{k}: {v if os.path.isabs(v) else os.path.normpath(os.path.join(base, v))}")
        line = m.group(1) + ", ".join(fixed) + m.group(3)
    if skip:
        if re.match(r"^\s{3,}\S", line):
            continue
        skip = False
    if re.match(r"^  integrator:", line):
        out.append(ref)
        placed = True
        skip = not line.rstrip().endswith("}")
        continue
    out.append(line)
    if re.match(r"^sim:\s*$", line) and not placed and "  integrator:" not in open(src).read():
        out.append(ref)
        placed = True
open(dst, "w").write("".join(out))
PY
  ref="$OUT/$name.reference.yaml $OUT/$name.reference"
  if [ "$NPERT" = 0 ]; then
    printf '%s\n' "$c $OUT/$name.default ${SETS[*]+${SETS[*]}}" "$ref" | run_all
    /usr/bin/python3 "$PY" single "$name" "$OUT/$name.default/trace.csv" "$OUT/$name.reference/trace.csv"
    continue
  fi
  # The case as written (with -s / -a) first: its trace header gives the case's own rtol.
  run_case "$c" "$OUT/$name.0" ${SETS[@]+"${SETS[@]}"}
  rtol="$(sed -n 's/^# integrator: .*; rtol \([^,]*\),.*/\1/p' "$OUT/$name.0/trace.csv" 2>/dev/null | head -1)"
  if [ -z "$rtol" ]; then
    echo "$name: the run of the case as written failed" >&2
    status=$(lexdyn_worse "$status" 3)
    continue
  fi
  # "LABEL DIR [rtol]" of the N runs; for an odd N the middle one is the run above.
  mapfile -t values < <(python3 - "$rtol" "$NPERT" "$STEP" "$OUT/$name" <<'PY'
import sys
rtol, n, step, stem = float(sys.argv[1]), int(sys.argv[2]), float(sys.argv[3]), sys.argv[4]
for i in range(n):
    k = i - (n - 1) / 2
    if k == 0:
        print(f"{sys.argv[1]} {stem}.0")
    else:
        r = f"{rtol * (1 + k * step):.6g}"
        print(f"{r} {stem}.k{k:g} {r}")
PY
  )
  runs=()
  {
    echo "$ref"
    for v in "${values[@]}"; do
      read -r label dir r <<< "$v"
      [ -z "${r:-}" ] || echo "$c $dir ${SETS[*]+${SETS[*]}} --set sim.integrator.rtol=$r"
    done
  } | run_all
  for v in "${values[@]}"; do
    read -r label dir r <<< "$v"
    runs+=("$label=$dir")
  done
  check=()
  [ "$CHECK" = 0 ] || check=(--check)
  rc=0
  /usr/bin/python3 "$PY" perturbed "$name" "$OUT/$name.reference/trace.csv" "$OUT/$name.0" "${runs[@]}" ${check[@]+"${check[@]}"} || rc=$?
  status=$(lexdyn_worse "$status" "$rc")
done
exit "$status"
