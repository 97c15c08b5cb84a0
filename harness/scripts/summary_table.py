#!/usr/bin/env python3
"""Comparison table of lexdyn-harness runs, from their summary.json files (read by the lexdyn
package: /usr/bin/python3 with PYTHONPATH=python, as the scripts set it).

Usage: summary_table.py [--errors TASK,TASK] LABEL=RUN_DIR ...

One row per run: run status, simulated and wall time, the sum of the --errors tasks' final and
time-averaged error norms ("-" for runs without those tasks), the peak active-set iterations,
per-tick wall time (median, p99, max of the whole tick), Newton-augmented ticks and the failed
checks. Prints to stdout; a run without summary.json gets a row saying so and the exit code is 1.
"""
import argparse
import os
import sys

import lexdyn


def _expectation(s):
    """ " (expected)" when the run failed as its case expects (summary.json "expected_failure"),
    " (NOT expected)" when the case expects another failure."""
    x = s.get("expected_failure")
    if not x:
        return ""
    return " (expected)" if x.get("met") else " (NOT expected)"


def load(path):
    try:
        return lexdyn.read_summary(path)
    except lexdyn.FormatError as e:
        sys.exit(f"summary_table: {e}")


def fmt(v, spec):
    return "-" if v is None else format(v, spec)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--errors", default="right_hand,left_hand")
    ap.add_argument("runs", nargs="+", help="LABEL=RUN_DIR (holding summary.json)")
    a = ap.parse_args()
    tasks = [t for t in a.errors.split(",") if t]
    rows, missing = [], []
    for r in a.runs:
        if "=" not in r:
            sys.exit(f"summary_table: '{r}': expected LABEL=RUN_DIR")
        label, d = r.split("=", 1)
        path = os.path.join(d, "summary.json")
        if not os.path.exists(path):
            missing.append(f"{label}  (no summary: see {os.path.join(d, 'log.txt')})")
            continue
        s = load(path)
        te = s.get("tasks", {})
        final = mean = None
        if all(t in te and te[t].get("final_error") is not None for t in tasks):
            final = sum(te[t]["final_error"] for t in tasks)
            mean = sum(te[t]["mean_error"] for t in tasks)
        tick = s.get("timing_us", {}).get("tick", {})
        aug = s.get("controller", {}).get("augmented_ticks", {})
        failed = [c.name for c in s.failed_checks]  # those that decide (not the wall-clock ones reported only)
        rows.append([
            label,
            s.get("status", "?") + _expectation(s),
            fmt(s.get("simulated_s"), ".1f"),
            fmt(s.get("wall_s"), ".1f"),
            fmt(final, ".4f"),
            fmt(mean, ".4f"),
            str(s.get("solver", {}).get("peak_iterations", "-")),
            fmt(tick.get("median"), ".0f") + " / " + fmt(tick.get("p99"), ".0f") + " / " + fmt(tick.get("max"), ".0f"),
            str(sum(aug.values())) if aug else "-",
            (str(len(failed)) + (": " + ", ".join(failed) if failed else "")),
        ])
    head = ["run", "status", "sim s", "wall s", "final " + "+".join(tasks) + " (m)", "mean (m)", "peak it",
            "tick us med/p99/max", "Newton ticks", "failed checks"]
    widths = [max(len(str(x[i])) for x in rows + [head]) for i in range(len(head) - 1)]
    line = lambda x: "  ".join(str(v).ljust(w) for v, w in zip(x[:-1], widths)) + "  " + str(x[-1])
    print(line(head))
    for x in rows:
        print(line(x))
    for m in missing:
        print(m)
    sys.exit(1 if missing else 0)


if __name__ == "__main__":
    main()
