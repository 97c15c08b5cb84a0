#!/usr/bin/env bash
# Solver benchmark (docs/performance.md, "Solver"): paper-shaped problems in three regimes, each a
# drifting sequence of ticks solved cold and warm-started by `lexdyn-solve --bench`, the sequence
# run REPEATS times. Printed per regime: the pooled median, p99 and max, and the minimum over the
# repeats of each repeat's median (a shared machine's scheduler adds false tails to single runs).
# Usage: harness/scripts/bench-solver.sh [-r REPEATS] [ticks]   (defaults: 3 repeats, 1000 ticks).
# Results: build/bench/solver-<regime>-<ticks>.json
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
cd "$ROOT"
REPEATS=3
lexdyn_options "[-r REPEATS] [ticks]" r=REPEATS -- "$@"
TICKS="${LEXDYN_OPERANDS[0]:-1000}"
lexdyn_positive_count "bench-solver.sh: -r" repeats "$REPEATS"
lexdyn_positive_count "bench-solver.sh" ticks "$TICKS"
[ -x build/bin/lexdyn-solve ] && [ -x build/bin/lexdyn-bench-solver-problems ] || harness/scripts/build.sh
OUT=build/bench
mkdir -p "$OUT"
echo "machine: $(lscpu | sed -n 's/^Model name: *//p' | head -1), $(nproc) cores; load: $(cut -d' ' -f1-3 /proc/loadavg); $TICKS ticks, $REPEATS repeats"
for regime in nominal stress near-singular; do
  dir="$OUT/problems-$regime-$TICKS"
  if [ ! -f "$dir/tick_$(printf %04d $((TICKS - 1))).json" ]; then
    build/bin/lexdyn-bench-solver-problems --regime "$regime" --ticks "$TICKS" --out "$dir"
  fi
  build/bin/lexdyn-solve --bench --repeats "$REPEATS" "$dir"/tick_*.json > "$OUT/solver-$regime-$TICKS.json"
  /usr/bin/python3 - "$regime" "$OUT/solver-$regime-$TICKS.json" <<'PY'
import json, sys
regime, path = sys.argv[1], sys.argv[2]
d = json.load(open(path))
print(f"{regime:14s} qr_unit {d['qr_unit_us']:.1f} us   max|x| {d['max_abs_x']:.3g}")
for k in ("cold", "warm"):
    s = d[k]
    if s["count"] == 0:
        print(f"  {k:5s} nothing timed")
        continue
    print(f"  {k:5s} min of medians {s['min_repeat_median_us']:8.1f} us ({s['min_repeat_median_qr_units']:.2f} u)"
          f"  median {s['median_us']:8.1f} us ({s['median_qr_units']:.2f} u)  p99 {s['p99_us']:8.1f} us  max {s['max_us']:8.1f} us"
          f"  iterations mean {s['mean_iterations']:.2f} max {s['max_iterations']}  cap hits {s['iteration_limit_hits']}")
PY
done
