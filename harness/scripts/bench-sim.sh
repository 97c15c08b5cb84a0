#!/usr/bin/env bash
# Closed-loop speed (docs/performance.md, "Simulator" and "Controller tick in the closed loop"):
# runs each case N times with lexdyn-harness and prints, from the runs' summary.json:
#   - the wall time: minimum, median and maximum over the runs, and the real-time factor
#     (simulated seconds per wall second of each run): maximum, median, minimum;
#   - for a lexdyn or WLS controller, each timed part of the tick (tick, solver, model, tasks,
#     Hessians): the minimum over the runs of the per-run median, the median of those medians,
#     and the largest per-run p99; the slowest tick of each run (minimum and median over the
#     runs) and, next to it, the solver's deterministic work peak (active-set iterations and
#     factorised stages in one tick, with the time of the tick).
# A single run on a shared machine can show false tails of one scheduler slice (about 4 ms): the
# minimum over runs is the figure to compare. Figures compare on one machine only.
# With -B OTHER_BUILD, two builds are compared: each run of BUILD_DIR's lexdyn-harness is followed
# by one of OTHER_BUILD's (alternating pairs, so that a change of the machine's load falls on both),
# and each build's figures are printed, then the differences of the minima (B - A). The runs' traces
# are compared too: "traces: identical" (apart from the wall-clock columns) or "traces: differ".
# Exit codes (harness/scripts/exit-codes.sh): 0 when every run completed (failing checks are
# reported in the line, not in the code: a benchmark measures time); 3 when a run did not
# complete or wrote no summary; 2 bad input; 130 / 143 interrupted.
#
# Usage: harness/scripts/bench-sim.sh [-n RUNS] [-b BUILD_DIR] [-B OTHER_BUILD] [-m METHOD] [-d DURATION] [case.yaml ...]
#        METHOD: bfgs | ah | gn | wls (LexDynBFGS, LexDynAH, pure Gauss-Newton, the weighted QP)
#        (defaults: 5 runs, build/, each case's own method and duration,
#         cases/stand.yaml cases/squat_sway.yaml). A run cut by -d cannot pass the checks that
#        look at the end of the case (e.g. hands_settled); they are listed as failing.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
RUNS=5
BUILD="$ROOT/build"
OTHER=""
METHOD=""
DURATION=""
lexdyn_options "[-n RUNS] [-b BUILD_DIR] [-B OTHER_BUILD] [-m METHOD] [-d DURATION] [case.yaml ...]" n=RUNS b=BUILD B=OTHER m=METHOD d=DURATION -- "$@"
lexdyn_positive_count "bench-sim.sh: -n" runs "$RUNS"
lexdyn_cases "${LEXDYN_OPERANDS[@]}"
lexdyn_harness bench-sim
HARNESSES=("$HARNESS")
LABELS=(A)
if [ -n "$OTHER" ]; then
  [ -x "$OTHER/bin/lexdyn-harness" ] || { echo "bench-sim.sh: -B: $OTHER/bin/lexdyn-harness not built" >&2; exit 2; }
  HARNESSES+=("$OTHER/bin/lexdyn-harness")
  LABELS+=(B)
  echo "A: $HARNESS"
  echo "B: $OTHER/bin/lexdyn-harness"
fi
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
extra=()
[ -n "$METHOD" ] && extra+=(--method "$METHOD")
[ -n "$DURATION" ] && extra+=(--duration "$DURATION")

echo "machine: $(lscpu | sed -n 's/^Model name: *//p' | head -1), $(nproc) cores; load: $(cut -d' ' -f1-3 /proc/loadavg)"
for c in "${CASES[@]}"; do
  name="$(basename "$c" .yaml)"
  for i in $(seq 1 "$RUNS"); do
    for k in "${!HARNESSES[@]}"; do
      run="$OUT/$name.${LABELS[$k]}.$i"
      code=0
      "${HARNESSES[$k]}" run "$c" --out "$run" --quiet "${extra[@]}" 2>"$run.err" || code=$?
      code="$(lexdyn_code "$code")"
      # Interrupted (130 / 143) or bad input (2): stop. A run without a summary is a run failure.
      if [ "$code" -ge 128 ] || [ "$code" -eq 2 ] || [ ! -f "$run/summary.json" ]; then
        echo "bench-sim.sh: $c: run $i of ${HARNESSES[$k]} stopped (exit $code):" >&2
        tail -3 "$run.err" >&2
        exit "$(lexdyn_worse "$code" 3)"
      fi
    done
  done
  /usr/bin/python3 - "$OUT" "$name" "$RUNS" "${LABELS[@]}" <<'PY'
import csv, statistics, sys
import lexdyn
out, name, runs, labels = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4:]
PARTS = ("tick", "solver", "model", "tasks", "hessian")


def report(label):
    """Prints one build's figures; returns (minimum wall, {part: minimum per-run median}, completed)."""
    s = [lexdyn.read_summary(f"{out}/{name}.{label}.{i}/summary.json") for i in range(1, runs + 1)]
    prefix = f"[{label}] " if len(labels) > 1 else ""
    wall = [x["wall_s"] for x in s]
    sim = s[0]["simulated_s"]
    rtf = [x["simulated_s"] / x["wall_s"] for x in s]
    st = {x["status"] for x in s}
    failing = sorted({c["name"] for x in s for c in x.get("checks", []) if not c.get("passed", True)})
    checks = "passed" if not failing else "failing: " + ", ".join(failing)
    method = s[0].get("method") or "posture servo"
    integ = s[0]["integrator"]
    print(f"{prefix}{name} ({method}), {runs} runs of {sim:.1f} s: wall min {min(wall):.3f} s, median {statistics.median(wall):.3f} s, "
          f"max {max(wall):.3f} s; real-time factor max {max(rtf):.1f}x, median {statistics.median(rtf):.1f}x, min {min(rtf):.1f}x; "
          f"steps {integ['steps']}, rhs {integ['rhs_evals']} + {integ['jac_rhs_evals']} (Jacobians); "
          f"status {','.join(sorted(st))}; checks {checks}")
    timing = [x.get("timing_us") or {} for x in s]
    minima = {}
    for part in PARTS:
        if not all(part in t for t in timing):
            continue
        med = [t[part]["median"] for t in timing]
        p99 = [t[part]["p99"] for t in timing]
        minima[part] = min(med)
        print(f"  {part:8s} median: min {min(med):8.1f} us, median {statistics.median(med):8.1f} us; p99: max {max(p99):8.1f} us")
    if all("tick" in t for t in timing):
        peak = [t["tick"]["max"] for t in timing]
        print(f"  tick     max:    min {min(peak):8.1f} us, median {statistics.median(peak):8.1f} us (each run's slowest tick)")
    # The deterministic measure of the worst tick's work, next to its wall time: the same in every run.
    work = {(x["solver"]["peak_iterations"], x["solver"]["peak_iterations_at_s"], x["solver"]["peak_factorizations"],
             x["solver"]["peak_factorizations_at_s"]) for x in s if x.get("solver")}
    for it, it_at, fa, fa_at in sorted(work):
        print(f"  solver work peak: {it} active-set iterations at {it_at:g} s, {fa} factorised stages at {fa_at:g} s")
    if st != {"completed"}:
        print(f"  a run did not complete: {', '.join(sorted(st))}; its figures cover less simulated time")
    return min(wall), minima, st == {"completed"}


def trace_rows(label):
    """The first run's trace without the wall-clock columns (time.*) and the header lines."""
    with open(f"{out}/{name}.{label}.1/trace.csv", newline="") as f:
        rows = [r for r in csv.reader(line for line in f if not line.startswith("#"))]
    keep = [i for i, h in enumerate(rows[0]) if not h.startswith("time.")]
    return [[r[i] for i in keep] for r in rows]


results = [report(label) for label in labels]
if len(labels) == 2:
    (wa, ma, _), (wb, mb, _) = results
    diffs = [f"wall {wb - wa:+.3f} s ({100.0 * (wb - wa) / wa:+.1f} %)"]
    for part in PARTS:
        if part in ma and part in mb:
            diffs.append(f"{part} {mb[part] - ma[part]:+.1f} us")
    print(f"  B - A (minima): {', '.join(diffs)}")
    print("  traces: " + ("identical" if trace_rows("A") == trace_rows("B") else "differ") + " (wall-clock columns left out)")
if not all(r[2] for r in results):
    sys.exit(3)
PY
done
