#!/usr/bin/env bash
# Closed-loop speed (docs/performance.md, "Simulator" and "Controller tick in the closed loop"):
# runs each case N times with lexdyn-harness and prints, from the runs' summary.json:
#   - the wall time: minimum, median and maximum over the runs, and the real-time factor
#     (simulated seconds per wall second of each run): maximum, median, minimum;
#   - for a lexdyn or WLS controller, each timed part of the tick (tick, solver, model, tasks,
#     Hessians): the minimum over the runs of the per-run median, the median of those medians,
#     and the largest per-run p99.
# A single run on a shared machine can show false tails of one scheduler slice (about 4 ms): the
# minimum over runs is the figure to compare. Figures compare on one machine only.
# Exit codes (harness/scripts/exit-codes.sh): 0 when every run completed (failing checks are
# reported in the line, not in the code: a benchmark measures time); 3 when a run did not
# complete or wrote no summary; 2 bad input; 130 / 143 interrupted.
#
# Usage: harness/scripts/bench-sim.sh [-n RUNS] [-b BUILD_DIR] [-m METHOD] [-d DURATION] [case.yaml ...]
#        METHOD: bfgs | ah | gn | wls (LexDynBFGS, LexDynAH, pure Gauss-Newton, the weighted QP)
#        (defaults: 5 runs, build/, each case's own method and duration,
#         cases/stand.yaml cases/squat_sway.yaml). A run cut by -d cannot pass the checks that
#        look at the end of the case (e.g. hands_settled); they are listed as failing.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
RUNS=5
BUILD="$ROOT/build"
METHOD=""
DURATION=""
lexdyn_options "[-n RUNS] [-b BUILD_DIR] [-m METHOD] [-d DURATION] [case.yaml ...]" n=RUNS b=BUILD m=METHOD d=DURATION -- "$@"
lexdyn_positive_count "bench-sim.sh: -n" runs "$RUNS"
lexdyn_cases "${LEXDYN_OPERANDS[@]}"
lexdyn_harness bench-sim
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
extra=()
[ -n "$METHOD" ] && extra+=(--method "$METHOD")
[ -n "$DURATION" ] && extra+=(--duration "$DURATION")

echo "machine: $(lscpu | sed -n 's/^Model name: *//p' | head -1), $(nproc) cores; load: $(cut -d' ' -f1-3 /proc/loadavg)"
for c in "${CASES[@]}"; do
  name="$(basename "$c" .yaml)"
  for i in $(seq 1 "$RUNS"); do
    code=0
    "$HARNESS" run "$c" --out "$OUT/$name.$i" --quiet "${extra[@]}" 2>"$OUT/$name.$i.err" || code=$?
    code="$(lexdyn_code "$code")"
    # Interrupted (130 / 143) or bad input (2): stop. A run without a summary is a run failure.
    if [ "$code" -ge 128 ] || [ "$code" -eq 2 ] || [ ! -f "$OUT/$name.$i/summary.json" ]; then
      echo "bench-sim.sh: $c: run $i stopped (exit $code):" >&2
      tail -3 "$OUT/$name.$i.err" >&2
      exit "$(lexdyn_worse "$code" 3)"
    fi
  done
  python3 - "$OUT" "$name" "$RUNS" <<'PY'
import json, statistics, sys
out, name, runs = sys.argv[1], sys.argv[2], int(sys.argv[3])
s = [json.load(open(f"{out}/{name}.{i}/summary.json")) for i in range(1, runs + 1)]
wall = [x["wall_s"] for x in s]
sim = s[0]["simulated_s"]
rtf = [x["simulated_s"] / x["wall_s"] for x in s]
st = {x["status"] for x in s}
failing = sorted({c["name"] for x in s for c in x.get("checks", []) if not c.get("passed", True)})
checks = "passed" if not failing else "failing: " + ", ".join(failing)
method = s[0].get("method") or "posture servo"
print(f"{name} ({method}), {runs} runs of {sim:.1f} s: wall min {min(wall):.3f} s, median {statistics.median(wall):.3f} s, "
      f"max {max(wall):.3f} s; real-time factor max {max(rtf):.1f}x, median {statistics.median(rtf):.1f}x, min {min(rtf):.1f}x; steps {s[0]['integrator']['steps']}, rhs {s[0]['integrator']['rhs_evals']} + "
      f"{s[0]['integrator']['jac_rhs_evals']} (Jacobians); status {','.join(sorted(st))}; checks {checks}")
timing = [x.get("timing_us") or {} for x in s]
for part in ("tick", "solver", "model", "tasks", "hessian"):
    if not all(part in t for t in timing):
        continue
    med = [t[part]["median"] for t in timing]
    p99 = [t[part]["p99"] for t in timing]
    print(f"  {part:8s} median: min {min(med):8.1f} us, median {statistics.median(med):8.1f} us; p99: max {max(p99):8.1f} us")
if st != {"completed"}:
    print(f"  a run did not complete: {', '.join(sorted(st))}; its figures cover less simulated time")
    sys.exit(3)
PY
done
