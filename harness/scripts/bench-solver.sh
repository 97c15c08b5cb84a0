#!/usr/bin/env bash
# Solver benchmark (docs/performance.md, "Solver"): paper-shaped problems in three regimes, each a
# drifting sequence of ticks solved cold and warm-started by `lexdyn-solve --bench`.
# Usage: harness/scripts/bench-solver.sh [ticks]   (default 1000). Results: build/bench/solver-*.json
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$ROOT"
TICKS="${1:-1000}"
[ -x build/bin/lexdyn-solve ] && [ -x build/bin/lexdyn-bench-solver-problems ] || harness/scripts/build.sh
OUT=build/bench
mkdir -p "$OUT"
echo "machine: $(lscpu | sed -n 's/^Model name: *//p' | head -1), $(nproc) cores; load: $(cut -d' ' -f1-3 /proc/loadavg)"
for regime in nominal stress near-singular; do
  dir="$OUT/problems-$regime-$TICKS"
  if [ ! -f "$dir/tick_$(printf %04d $((TICKS - 1))).json" ]; then
    build/bin/lexdyn-bench-solver-problems --regime "$regime" --ticks "$TICKS" --out "$dir"
  fi
  build/bin/lexdyn-solve --bench "$dir"/tick_*.json > "$OUT/solver-$regime.json"
  /usr/bin/python3 - "$regime" "$OUT/solver-$regime.json" <<'PY'
import json, sys
regime, path = sys.argv[1], sys.argv[2]
d = json.load(open(path))
print(f"{regime:14s} qr_unit {d['qr_unit_us']:.1f} us   max|x| {d['max_abs_x']:.3g}")
for k in ("cold", "warm"):
    s = d[k]
    print(f"  {k:5s} median {s['median_us']:8.1f} us ({s['median_qr_units']:.2f} u)  p99 {s['p99_us']:8.1f}  max {s['max_us']:8.1f} us"
          f"  iterations mean {s['mean_iterations']:.2f} max {s['max_iterations']}  cap hits {s['iteration_limit_hits']}")
PY
done
