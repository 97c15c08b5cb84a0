#!/usr/bin/env bash
# Integrator accuracy at a case's own tolerances (docs/simulator.md, "Integrator"): runs each
# case as written and again with a tight reference integrator (rtol 1e-8, atol_position 1e-10,
# atol_velocity 1e-8, steps of at most 0.2 ms), then prints the largest differences between the
# two traces over the run: WAIST position, joint positions, joint torques, vertical force of
# each foot, horizontal force at the foot sensors (also after t = 2 s).
#
# Usage: harness/scripts/sim-accuracy.sh [-b BUILD_DIR] [case.yaml ...]
#        (defaults: build/, cases/stand.yaml cases/squat_sway.yaml)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/common.sh"
BUILD="$ROOT/build"
lexdyn_options "[-b BUILD_DIR] [case.yaml ...]" b=BUILD -- "$@"
lexdyn_cases "${LEXDYN_OPERANDS[@]}"
lexdyn_harness sim-accuracy
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT

for c in "${CASES[@]}"; do
  name="$(basename "$c" .yaml)"
  # The reference case: the same file with the integrator settings replaced and the robot
  # paths made absolute (it is written elsewhere).
  python3 - "$c" "$OUT/$name.reference.yaml" <<'PY'
import os, re, sys
src, dst = sys.argv[1], sys.argv[2]
base = os.path.dirname(os.path.abspath(src))
ref = "  integrator: {rtol: 1.0e-8, atol_position: 1.0e-10, atol_velocity: 1.0e-8, max_step_s: 2.0e-4}\n"
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
  "$HARNESS" run "$c" --out "$OUT/$name.default" --quiet 2>/dev/null || true
  "$HARNESS" run "$OUT/$name.reference.yaml" --out "$OUT/$name.reference" --quiet 2>/dev/null || true
  python3 - "$OUT/$name.default/trace.csv" "$OUT/$name.reference/trace.csv" "$name" <<'PY'
import csv, math, sys
def load(path):
    rows = [l for l in open(path) if not l.startswith("#")]
    r = list(csv.reader(rows))
    return r[0], [list(map(float, x)) for x in r[1:]]
(h, a), (h2, b) = load(sys.argv[1]), load(sys.argv[2])
assert h == h2, "traces have different channels"
ix = {n: i for i, n in enumerate(h)}
n = min(len(a), len(b))
assert all(a[k][0] == b[k][0] for k in range(n)), "rows at different times"
def worst(cols, norm=False, after=-1.0):
    best, at = 0.0, 0.0
    for k in range(n):
        if a[k][0] < after:
            continue
        d = [a[k][ix[c]] - b[k][ix[c]] for c in cols]
        v = math.sqrt(sum(x * x for x in d)) if norm else max(abs(x) for x in d)
        if v > best:
            best, at = v, a[k][0]
    return best, at
print(f"{sys.argv[3]}: {n} rows compared (default vs reference)")
if "frame.WAIST.x" in ix:
    v, t = worst(["frame.WAIST.x", "frame.WAIST.y", "frame.WAIST.z"], norm=True)
    print(f"  WAIST position        {v:.3g} m (at t = {t:g} s)")
for prefix, unit, label in (("q.", "rad", "joint positions"), ("tau.", "N m", "joint torques")):
    v, t = worst([c for c in h if c.startswith(prefix)])
    print(f"  {label:21s} {v:.3g} {unit} (at t = {t:g} s)")
for c in [c for c in h if c.startswith("contact.") and c.endswith(".fz")]:
    v, t = worst([c])
    print(f"  {c:21s} {v:.3g} N (at t = {t:g} s; mean {sum(x[ix[c]] for x in b[:n]) / n:.1f} N)")
for s in sorted({c.split(".")[1] for c in h if c.startswith("ft.") and "Foot" in c}):
    v, t = worst([f"ft.{s}.fx", f"ft.{s}.fy"], norm=True)
    v2, _ = worst([f"ft.{s}.fx", f"ft.{s}.fy"], norm=True, after=2.0)
    print(f"  ft.{s} horizontal {v:.3g} N (at t = {t:g} s; {v2:.3g} N after t = 2 s)")
PY
done
