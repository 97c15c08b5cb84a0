#!/usr/bin/env bash
# The exit-code convention of the wrapper scripts (harness/scripts/exit-codes.sh) and the usage
# errors of the scripts: every code in its order of precedence.
set -u
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
source "$ROOT/harness/scripts/exit-codes.sh"
fail=0
expect() {  # expect WHAT EXPECTED ACTUAL
  if [ "$2" != "$3" ]; then echo "FAIL: $1: expected $2, found $3"; fail=1; else echo "ok: $1 = $3"; fi
}
expect "pass and pass" 0 "$(lexdyn_worse 0 0)"
expect "a failed check" 1 "$(lexdyn_worse 0 1)"
expect "a run failure over a failed check" 3 "$(lexdyn_worse 1 3)"
expect "bad input over a run failure" 2 "$(lexdyn_worse 3 2)"
expect "SIGINT over bad input" 130 "$(lexdyn_worse 2 130)"
expect "SIGTERM over a failed check" 143 "$(lexdyn_worse 143 1)"
expect "a crash (128 + SIGSEGV) is a run failure" 3 "$(lexdyn_worse 0 139)"
expect "an abort (134) is a run failure" 3 "$(lexdyn_code 134)"
# Usage errors of the scripts are 2.
"$ROOT/harness/scripts/fuzz.sh" -m abc > /dev/null 2>&1
expect "fuzz.sh -m abc" 2 "$?"
"$ROOT/harness/scripts/fuzz.sh" -e nosuchengine > /dev/null 2>&1
expect "fuzz.sh -e nosuchengine" 2 "$?"
"$ROOT/harness/scripts/full-runs.sh" -x > /dev/null 2>&1
expect "full-runs.sh -x" 2 "$?"
"$ROOT/harness/scripts/golden-update.sh" -x > /dev/null 2>&1
expect "golden-update.sh -x" 2 "$?"
"$ROOT/harness/scripts/sim-accuracy.sh" --check > /dev/null 2>&1
expect "sim-accuracy.sh --check (without -p)" 2 "$?"
"$ROOT/harness/scripts/sim-accuracy.sh" -p 3 -s sparse_lu > /dev/null 2>&1
expect "sim-accuracy.sh -s sparse_lu" 2 "$?"
"$ROOT/harness/scripts/bench-sim.sh" -n x > /dev/null 2>&1
expect "bench-sim.sh -n x" 2 "$?"
"$ROOT/harness/scripts/bench-solver.sh" -r 0 > /dev/null 2>&1
expect "bench-solver.sh -r 0" 2 "$?"
"$ROOT/harness/scripts/bench-solver.sh" abc > /dev/null 2>&1
expect "bench-solver.sh abc" 2 "$?"
"$ROOT/harness/scripts/second-order-runs.sh" -x > /dev/null 2>&1
expect "second-order-runs.sh -x" 2 "$?"
# --help and -h: the usage line and the script's header comment (its first line checked), exit 0.
# (timeout: without the option, build.sh, test.sh and main.sh would start building.)
for script in bench-sim bench-solver bench-sweep sim-accuracy full-runs golden-update fuzz second-order-runs \
  exp1 build test main install-deps; do
  for flag in --help -h; do
    out="$(timeout 30 "$ROOT/harness/scripts/$script.sh" $flag 2>&1)"
    expect "$script.sh $flag" 0 "$?"
    first="$(sed -n '2s/^# //p' "$ROOT/harness/scripts/$script.sh")"
    case "$out" in
      "usage: "*"$script.sh"*"$first"*) ;;
      *) echo "FAIL: $script.sh $flag: expected the usage line and the header ('$first'), found: ${out:0:200}"; fail=1 ;;
    esac
  done
done
exit $fail
