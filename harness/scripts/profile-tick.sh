#!/usr/bin/env bash
# Where a closed-loop run's time goes, in instructions (docs/performance.md, "Where an exp1 tick
# goes now"): runs one case under valgrind's callgrind and prints the instructions of each part
# of the run (controller: solver, model, Newton rows, tasks; simulator: right-hand sides,
# Jacobians, Newton matrices, CVODE, observation; trace writing; the rest), in all, per tick and
# as a share of the run. Unlike wall-clock timings, instructions hardly depend on the machine's
# load: two runs of the same binary and case differ by a few hundred instructions in hundreds of
# millions (address-space layout, the clock reads). They are not time (the solver's kernels run
# more instructions per cycle than Simbody's realization). Valgrind makes the run about 50 times
# slower: exp1's first 30 s take about 4 minutes.
#
# Usage: harness/scripts/profile-tick.sh [-b BUILD_DIR] [-m METHOD] [-d DURATION] [-o OUT_DIR] case.yaml
#        METHOD: bfgs | ah | gn | wls (default: the case's); DURATION: seconds simulated (default:
#        the case's); OUT_DIR keeps callgrind.out and the run (default: a temporary directory).
# Exit codes (harness/scripts/exit-codes.sh): 0 when the run completed (its checks are not looked
# at: a cut run fails those that look at the end of the case); 3 when it did not complete or a
# part of the table is missing from the profile; 2 bad input (or valgrind missing); 130 / 143
# interrupted.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
BUILD="$ROOT/build"
METHOD=""
DURATION=""
KEEP=""
lexdyn_options "[-b BUILD_DIR] [-m METHOD] [-d DURATION] [-o OUT_DIR] case.yaml" b=BUILD m=METHOD d=DURATION o=KEEP -- "$@"
[ "${#LEXDYN_OPERANDS[@]}" -eq 1 ] || { echo "profile-tick.sh: expected one case file" >&2; exit 2; }
CASE="${LEXDYN_OPERANDS[0]}"
[ -f "$CASE" ] || { echo "profile-tick.sh: $CASE: no such case file" >&2; exit 2; }
command -v valgrind > /dev/null && command -v callgrind_annotate > /dev/null ||
  { echo "profile-tick.sh: valgrind (callgrind_annotate) is not installed: harness/scripts/install-deps.sh" >&2; exit 2; }
lexdyn_harness profile-tick
if [ -n "$KEEP" ]; then
  OUT="$KEEP"
  mkdir -p "$OUT"
else
  OUT="$(mktemp -d)"
  trap 'rm -rf "$OUT"' EXIT
fi
extra=()
[ -n "$METHOD" ] && extra+=(--method "$METHOD")
[ -n "$DURATION" ] && extra+=(--duration "$DURATION")

rm -rf "$OUT/run"
code=0
valgrind --tool=callgrind --callgrind-out-file="$OUT/callgrind.out" \
  "$HARNESS" run "$CASE" --out "$OUT/run" --quiet "${extra[@]}" 2> "$OUT/valgrind.log" || code=$?
code="$(lexdyn_code "$code")"
if [ "$code" -ge 128 ] || [ "$code" -eq 2 ]; then
  echo "profile-tick.sh: the run stopped with code $code (valgrind's log: $OUT/valgrind.log)" >&2
  exit "$code"
fi
[ -f "$OUT/run/summary.json" ] || { echo "profile-tick.sh: the run wrote no summary (code $code)" >&2; exit 3; }

# Each function's inclusive instructions (its "*" line) and, under it, those of its callees
# from it (">" lines).
callgrind_annotate --tree=calling --inclusive=yes --threshold=100 "$OUT/callgrind.out" > "$OUT/calling.txt" 2> /dev/null
/usr/bin/python3 - "$OUT/calling.txt" "$OUT/run/summary.json" "$CASE" <<'PY' || exit 3
import re, sys
import lexdyn

calling, summary, case = sys.argv[1:4]
cost, callees, current = {}, {}, None
for line in open(calling, encoding="utf-8", errors="replace"):
    m = re.match(r"\s*([\d,]+)\s+\([\s\d.]+%\)\s+(\*|>)?\s*(.*)$", line)
    if not m:
        current = None if not line.strip() else current
        continue
    value, mark, name = int(m.group(1).replace(",", "")), m.group(2), m.group(3)
    if mark == ">":
        if current is not None:
            callees.setdefault(current, []).append((name, value))
    else:  # a function's own line ("*"), or the program's total
        current = name
        cost.setdefault(name, value)

def find(table, p):
    return [v for k, v in table if p in k]

def part(*patterns, optional=False):
    total = 0
    for p in patterns:
        hits = find(cost.items(), p)
        if not hits and not optional:
            sys.exit(f"profile-tick.sh: '{p}' is not in the profile (renamed?)")
        total += max(hits) if hits else 0
    return total

def called(caller, callee, optional=False):
    """Instructions of `callee` as called from `caller` (summed over the caller's entries)."""
    total = 0
    for name, lst in callees.items():
        if caller in name:
            total += sum(find(lst, callee))
    if total == 0 and not optional:
        sys.exit(f"profile-tick.sh: '{caller}' -> '{callee}' is not in the profile (renamed?)")
    return total

s = lexdyn.read_summary(summary)
ticks = int(s.get("ticks") or s.get("controller", {}).get("ticks") or 0)
run = part("PROGRAM TOTALS")
ctrl = part("lexdyn::control::Controller::tick(", optional=True)  # none in posture-only cases
solver = part("lexdyn::solver::Solver::Impl::solve(", optional=True)
fact = part("lexdyn::solver::HlsFactorization::factorize(", optional=True)
model = part("lexdyn::model::RobotModel::update(", "lexdyn::model::RobotModel::massMatrix(",
             "lexdyn::model::RobotModel::nonlinearEffects(", optional=True)
newton = part("VelocityDomainMethod::addRows(", optional=True)
command = part("lexdyn::control::Controller::Impl::finishTick(", optional=True)
step = part("lexdyn::sim::Simulator::step(")
rhs = part("lexdyn::sim::Simulator::Impl::rhs(")
realize = called("lexdyn::sim::Simulator::Impl::rhs(", "lexdyn::sim::Multibody::setState(")
fwd = called("lexdyn::sim::Simulator::Impl::rhs(", "lexdyn::sim::Multibody::accelerations(")
jac = part("lexdyn::sim::Simulator::Impl::jacobian(", optional=True)
lin = part("lexdyn::sim::CvodeIntegrator::Impl::linearSystem(", optional=True)
obs = part("lexdyn::sim::Simulator::Impl::observe(")
trace = part("lexdyn::checks::TraceWriter::write(")
loop = part("lexdyn::cases::runCase(")

rows = [
    ("controller tick", ctrl, 0),
    ("solver: level factorisations", fact, 1),
    ("solver: the rest (A x, back-substitution, dual check, multipliers, data)", solver - fact, 1),
    ("model (kinematics, M, N)", model, 1),
    ("Newton rows (method's second-order term)", newton, 1),
    ("torques and contact wrenches of the command", command, 1),
    ("tasks, the rows' copy into the problem, the rest", ctrl - solver - model - newton - command, 1),
    ("simulator step", step, 0),
    ("right-hand sides: Simbody's state and realization", realize, 1),
    ("right-hand sides: forward dynamics", fwd, 1),
    ("right-hand sides: applied forces, the rest", rhs - realize - fwd, 1),
    ("Jacobians of the applied forces", jac, 1),
    ("Newton matrices and their factorisation", lin, 1),
    ("observation at the tick", obs, 1),
    ("CVODE's own work", step - rhs - jac - lin - obs, 1),
    ("trace writing", trace, 0),
    ("checks, the run loop, start-up", run - ctrl - step - trace, 0),
]
print(f"case {case}: {ticks} ticks, {run / 1e9:.2f} G instructions ({run / max(ticks, 1) / 1e6:.2f} M per tick)")
print(f"{'part':<76} {'instructions':>12} {'per tick':>10} {'share':>7}")
for name, v, indent in rows:
    label = ("  - " if indent else "") + name
    print(f"{label:<76} {v / 1e9:>10.2f} G {v / max(ticks, 1) / 1e3:>8.1f} k {100.0 * v / run:>6.1f} %")
PY
