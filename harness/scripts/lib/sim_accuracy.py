"""Comparison of harness/scripts/sim-accuracy.sh: the largest differences between runs of a case
and its tight reference run, over the traces (docs/simulator.md, "Integrator").

  sim_accuracy.py single NAME TRACE REFERENCE
      one run against the reference, per foot (the script's output without -p).
  sim_accuracy.py perturbed NAME REFERENCE UNPERTURBED_DIR LABEL=RUN_DIR ... [--check]
      several runs (each RUN_DIR holds trace.csv and summary.json): per quantity the figure of
      the unperturbed run, the median and the max over the runs LABEL=RUN_DIR (the unperturbed
      one counts only if it is among them); the integrator's work. With
      --check, exits 1 when a median exceeds its bound (BOUNDS), 2 when the case has none.
"""
import math
import os
import statistics
import sys

import lexdyn

# Bounds on the median over 9 rtol perturbations (sim-accuracy.sh -p 9) at the cases' own
# tolerances, 10 s runs (docs/simulator.md, "Integrator"; keys as in QUANTITIES): the 99th
# percentile of the median of 9 runs drawn from 50 runs of each case (rtol x (1 + 0.004 k),
# k = -12 ... 12, with either linear solver: the two gave the same distributions), rounded up to
# two significant digits. Rounding alone puts a median above its bound in about 1 % of the sets.
BOUNDS = {
    "stand": {"waist": 2.7e-6, "q": 2.9e-6, "tau": 0.17, "fz": 0.23, "fh": 0.32, "fh2": 0.14},
    "squat_sway": {"waist": 2.7e-5, "q": 4.1e-5, "tau": 1.1, "fz": 1.1, "fh": 13.0, "fh2": 2.7},
}

# (key, label, unit) of the quantities of the perturbed mode, in order.
QUANTITIES = [
    ("waist", "WAIST position", "m"),
    ("q", "joint positions", "rad"),
    ("tau", "joint torques", "N m"),
    ("fz", "vertical force of a foot", "N"),
    ("fh", "horizontal force at a foot sensor", "N"),
    ("fh2", "  the same after t = 2 s", "N"),
]


WAIST = ["frame.WAIST.x", "frame.WAIST.y", "frame.WAIST.z"]

_kept = {}


def load(path, keep=False):
    """(channel names, rows) of a trace (lexdyn.read_trace); keep: remember it (the reference,
    read once)."""
    if path in _kept:
        return _kept[path]
    tr = lexdyn.read_trace(path)
    t = tr.names, tr.data.tolist()
    if keep:
        _kept[path] = t
    return t


class Pair:
    """A run's trace against the reference trace."""

    def __init__(self, trace, reference):
        (h, a), (h2, b) = load(trace), load(reference, keep=True)
        assert h == h2, "traces have different channels"
        self.h, self.a, self.b = h, a, b
        self.ix = {n: i for i, n in enumerate(h)}
        self.n = min(len(a), len(b))
        assert all(a[k][0] == b[k][0] for k in range(self.n)), "rows at different times"

    def worst(self, cols, norm=False, after=-1.0):
        a, b, ix = self.a, self.b, self.ix
        best, at = 0.0, 0.0
        for k in range(self.n):
            if a[k][0] < after:
                continue
            d = [a[k][ix[c]] - b[k][ix[c]] for c in cols]
            v = math.sqrt(sum(x * x for x in d)) if norm else max(abs(x) for x in d)
            if v > best:
                best, at = v, a[k][0]
        return best, at

    def fz_channels(self):
        return [c for c in self.h if c.startswith("contact.") and c.endswith(".fz")]

    def foot_sensors(self):
        return sorted({c.split(".")[1] for c in self.h if c.startswith("ft.") and "Foot" in c})

    def horizontal(self, sensor, after=-1.0):
        """Largest horizontal force difference at a foot sensor (and when)."""
        return self.worst([f"ft.{sensor}.fx", f"ft.{sensor}.fy"], norm=True, after=after)

    def prefixed(self, prefix):
        return [c for c in self.h if c.startswith(prefix)]

    def quantities(self):
        """{key: (value, time)} of QUANTITIES, the feet combined (the larger figure)."""
        out = {}
        if WAIST[0] in self.ix:
            out["waist"] = self.worst(WAIST, norm=True)
        out["q"] = self.worst(self.prefixed("q."))
        out["tau"] = self.worst(self.prefixed("tau."))
        fz = [self.worst([c]) for c in self.fz_channels()]
        if fz:
            out["fz"] = max(fz)
        sensors = self.foot_sensors()
        if sensors:
            out["fh"] = max(self.horizontal(s) for s in sensors)
            out["fh2"] = max(self.horizontal(s, after=2.0) for s in sensors)
        return out


def single(name, trace, reference):
    p = Pair(trace, reference)
    print(f"{name}: {p.n} rows compared (default vs reference)")
    if WAIST[0] in p.ix:
        v, t = p.worst(WAIST, norm=True)
        print(f"  WAIST position        {v:.3g} m (at t = {t:g} s)")
    for prefix, unit, label in (("q.", "rad", "joint positions"), ("tau.", "N m", "joint torques")):
        v, t = p.worst(p.prefixed(prefix))
        print(f"  {label:21s} {v:.3g} {unit} (at t = {t:g} s)")
    for c in p.fz_channels():
        v, t = p.worst([c])
        print(f"  {c:21s} {v:.3g} N (at t = {t:g} s; mean {sum(x[p.ix[c]] for x in p.b[:p.n]) / p.n:.1f} N)")
    for s in p.foot_sensors():
        v, t = p.horizontal(s)
        v2, _ = p.horizontal(s, after=2.0)
        print(f"  ft.{s} horizontal {v:.3g} N (at t = {t:g} s; {v2:.3g} N after t = 2 s)")
    return 0


def integrator_stats(run_dir):
    try:
        return lexdyn.read_summary(run_dir).get("integrator", {})
    except (OSError, lexdyn.FormatError):
        return {}


def perturbed(name, reference, unperturbed_dir, runs, check):
    figures = {}  # run directory -> quantities
    work = {}     # run directory -> (steps, rhs_evals, jac_rhs_evals)
    rows = None
    missing = [d for d in [reference, unperturbed_dir] + [d for _, d in runs] if not os.path.exists(
        d if d == reference else os.path.join(d, "trace.csv"))]
    if missing:
        print(f"{name}: no trace from the run(s) {', '.join(missing)}", file=sys.stderr)
        return 3
    for run_dir in [unperturbed_dir] + [d for _, d in runs]:
        if run_dir in figures:
            continue
        p = Pair(os.path.join(run_dir, "trace.csv"), reference)
        rows = p.n if rows is None else min(rows, p.n)
        figures[run_dir] = p.quantities()
        st = integrator_stats(run_dir)
        work[run_dir] = (st.get("steps", 0), st.get("rhs_evals", 0), st.get("jac_rhs_evals", 0))
    unperturbed = unperturbed_dir
    labels = [d for _, d in runs]
    rtol_of = dict((d, l) for l, d in runs)
    print(f"{name}: {len(runs)} runs (rtol {', '.join(l for l, _ in runs)}) against the reference, {rows} rows")
    print(f"  {'quantity':36s} {'unperturbed':>11s} {'median':>10s} {'max':>10s}  (max at rtol, t)")
    medians = {}
    for key, label, unit in QUANTITIES:
        vals = [(figures[l][key][0], rtol_of[l], figures[l][key][1]) for l in labels if key in figures[l]]
        if not vals:
            continue
        med = statistics.median(v for v, _, _ in vals)
        mx = max(vals)
        medians[key] = med
        u = figures[unperturbed][key][0] if key in figures[unperturbed] else float("nan")
        print(f"  {label + ' [' + unit + ']':36s} {u:11.3g} {med:10.3g} {mx[0]:10.3g}  ({mx[1]}, {mx[2]:g} s)")
    for i, what in enumerate(("steps", "right-hand sides (integrator)", "right-hand sides (Jacobians)")):
        vals = [work[l][i] for l in labels]
        u = work[unperturbed][i]
        print(f"  {what:36s} {u:11.0f} {statistics.median(vals):10.0f} {max(vals):10.0f}")
    if not check:
        return 0
    bounds = BOUNDS.get(name)
    if not bounds:
        print(f"  check: no documented bounds for the case '{name}' (harness/scripts/lib/sim_accuracy.py)")
        return 2
    failed = 0
    for key, label, unit in QUANTITIES:
        if key not in bounds:
            continue
        ok = medians.get(key, float("inf")) <= bounds[key]
        failed |= not ok
        print(f"  check {'ok  ' if ok else 'FAIL'} {label.strip()}: median {medians.get(key, float('nan')):.3g} {unit}"
              f" {'<=' if ok else '>'} bound {bounds[key]:.3g} {unit}")
    return 1 if failed else 0


def main(argv):
    try:
        return run(argv)
    except lexdyn.FormatError as e:
        print(f"sim_accuracy: {e}", file=sys.stderr)
        return 3


def run(argv):
    if len(argv) >= 1 and argv[0] == "single" and len(argv) == 4:
        return single(argv[1], argv[2], argv[3])
    if len(argv) >= 5 and argv[0] == "perturbed":
        rest = argv[4:]
        check = "--check" in rest
        runs = [tuple(r.split("=", 1)) for r in rest if r != "--check"]
        return perturbed(argv[1], argv[2], argv[3], runs, check)
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
