#!/usr/bin/env bash
# Closed-loop simulator speed (docs/performance.md, "Simulator"): runs each case N times with
# lexdyn-harness and prints the median and maximum real-time factor (simulated seconds per wall
# second, from summary.json). Figures compare on one machine only.
#
# Usage: harness/scripts/bench-sim.sh [-n RUNS] [-b BUILD_DIR] [case.yaml ...]
#        (defaults: 5 runs, build/, cases/stand.yaml cases/squat_sway.yaml)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
RUNS=5
BUILD="$ROOT/build"
lexdyn_options "[-n RUNS] [-b BUILD_DIR] [case.yaml ...]" n=RUNS b=BUILD -- "$@"
lexdyn_cases "${LEXDYN_OPERANDS[@]}"
lexdyn_harness bench-sim
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT

echo "machine: $(lscpu | sed -n 's/^Model name: *//p' | head -1), $(nproc) cores"
for c in "${CASES[@]}"; do
  name="$(basename "$c" .yaml)"
  for i in $(seq 1 "$RUNS"); do
    "$HARNESS" run "$c" --out "$OUT/$name.$i" --quiet 2>/dev/null || true
  done
  python3 - "$OUT" "$name" "$RUNS" <<'PY'
import json, statistics, sys
out, name, runs = sys.argv[1], sys.argv[2], int(sys.argv[3])
s = [json.load(open(f"{out}/{name}.{i}/summary.json")) for i in range(1, runs + 1)]
rtf = [x["realtime_factor"] for x in s]
st = {x["status"] for x in s}
ok = all(x["all_checks_passed"] for x in s)
print(f"{name}: realtime factor median {statistics.median(rtf):.1f}x, max {max(rtf):.1f}x, min {min(rtf):.1f}x "
      f"over {runs} runs of {s[0]['simulated_s']:.1f} s; wall median {statistics.median(x['wall_s'] for x in s):.3f} s; "
      f"steps {s[0]['integrator']['steps']}, rhs {s[0]['integrator']['rhs_evals']} + {s[0]['integrator']['jac_rhs_evals']} (Jacobians); "
      f"status {','.join(sorted(st))}; checks {'passed' if ok else 'FAILED'}")
PY
done
