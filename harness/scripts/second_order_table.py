#!/usr/bin/python3
"""Table of the runs of second-order-runs.sh (docs/results.md, "The second-order term").

Usage: second_order_table.py OUT [--level hands] [--json FILE]

For every run directory OUT/<case>.<method>.<reading>.a<alpha>/ (trace.csv, summary.json): the
final hand errors, the ratio channels level.<L>.second_order_ratio / .curvature_ratio of the
level (median and max over its augmented ticks), its Newton timeline (augmented ticks, first
augmented time, GN <-> Newton switches), the fraction of ticks with an accepted BFGS update,
the convergence time (last time the sum of hand errors is more than 1 mm from its final value),
the peak active-set iterations, the oscillation checks and the failed checks. Markdown on stdout.
"""
import argparse
import json
import math
import os
import sys

import numpy as np

import lexdyn

HANDS = {"exp1": ["right_hand", "left_hand"], "exp2": ["right_hand"], "exp3": ["right_hand"],
         "pointmass-damping": ["position"]}
LEVEL = {"pointmass-damping": "position"}


def load_trace(path, wanted):
    """{channel: values} of the channels WANTED that the trace has."""
    tr = lexdyn.read_trace(path, channels=wanted)
    return {w: tr.col(w) for w in wanted if tr.has(w)}


def fmt(v, spec=".3g"):
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "-"
    return format(v, spec)


def analyse(d):
    base = os.path.basename(d.rstrip("/"))
    case, method, reading, alpha = base.split(".", 3)
    alpha = alpha[1:]
    r = {"case": case, "method": method, "reading": reading, "alpha": alpha}
    sp = os.path.join(d, "summary.json")
    if not os.path.exists(sp):
        r["status"] = "no summary"
        return r
    s = lexdyn.read_summary(sp)
    r["status"] = s.status
    hands = HANDS.get(case, ["right_hand"])
    te = s.get("tasks", {})
    r["final"] = {h: te.get(h, {}).get("final_error") for h in hands}
    r["mean"] = {h: te.get(h, {}).get("mean_error") for h in hands}
    r["peak_iterations"] = s.get("solver", {}).get("peak_iterations")
    r["peak_iterations_at_s"] = s.get("solver", {}).get("peak_iterations_at_s")
    checks = {c.name: c for c in s.checks}
    # Wall-clock checks (machine-dependent, reported only: decides false) are left out.
    r["failed"] = [c.name for c in s.failed_checks]
    for key, name in (("sign_changes", "joint_accel_sign_changes"), ("hf_energy", "joint_velocity_hf")):
        r[key] = checks.get(name, {}).get("value")
    lvl = LEVEL.get(case, "hands")
    ch = [f"level.{lvl}.{w}" for w in ("augmented", "hessian_updated", "second_order_ratio", "curvature_ratio")]
    t = load_trace(os.path.join(d, "trace.csv"), ["t"] + ch + [f"task.{h}.error" for h in hands])
    time = t["t"]
    aug = t.get(ch[0], np.zeros_like(time)) > 0.5
    r["augmented_ticks"] = int(aug.sum())
    r["first_augmented_s"] = float(time[aug][0]) if aug.any() else None
    r["switches"] = int(np.count_nonzero(np.diff(aug.astype(int)) != 0))
    upd = t.get(ch[1], np.zeros_like(time)) > 0.5
    r["update_fraction_augmented"] = float(upd[aug].mean()) if aug.any() else None
    for key, c in (("ratio", ch[2]), ("curvature", ch[3])):
        v = t.get(c)
        if v is not None and aug.any():
            va = v[aug]
            va = va[np.isfinite(va)]
            r[key + "_median"] = float(np.median(va)) if va.size else None
            r[key + "_max"] = float(np.max(va)) if va.size else None
    err = sum(t[f"task.{h}.error"] for h in hands if f"task.{h}.error" in t)
    if isinstance(err, np.ndarray):
        final = err[-1]
        far = np.nonzero(np.abs(err - final) > 1e-3)[0]
        r["converged_s"] = float(time[far[-1]]) if far.size else 0.0
        for ts in (45.0, 90.0):
            k = np.searchsorted(time, ts)
            if k < len(time):
                r[f"err_{int(ts)}"] = float(err[k])
        r["final_sum"] = float(final)
    return r


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--json")
    a = ap.parse_args()
    runs = sorted(os.path.join(a.out, x) for x in os.listdir(a.out) if os.path.isdir(os.path.join(a.out, x)))
    try:
        rows = [analyse(d) for d in runs]
    except lexdyn.FormatError as e:
        print(f"second_order_table: {e}", file=sys.stderr)
        return 2
    if a.json:
        json.dump(rows, open(a.json, "w"), indent=1)
    print("| case | method | reading | alpha | status | final hand errors (m) | err 45 s / 90 s | converged (s) "
          "| aug. ticks | first aug. (s) | switches | BFGS upd. | ratio median / max | curvature median / max "
          "| peak it. (s) | sign ch./s | HF | failed checks |")
    print("|" + "---|" * 18)
    for r in rows:
        if r.get("status") == "no summary":
            print(f"| {r['case']} | {r['method']} | {r['reading']} | {r['alpha']} | no summary |" + " |" * 13)
            continue
        final = " + ".join(fmt(v, ".4f") for v in r["final"].values())
        print(f"| {r['case']} | {r['method']} | {r['reading']} | {r['alpha']} | {r['status']} | {final} "
              f"| {fmt(r.get('err_45'), '.4f')} / {fmt(r.get('err_90'), '.4f')} | {fmt(r.get('converged_s'), '.1f')} "
              f"| {r['augmented_ticks']} | {fmt(r.get('first_augmented_s'), '.2f')} | {r['switches']} "
              f"| {fmt(r.get('update_fraction_augmented'), '.2f')} "
              f"| {fmt(r.get('ratio_median'))} / {fmt(r.get('ratio_max'))} "
              f"| {fmt(r.get('curvature_median'))} / {fmt(r.get('curvature_max'))} "
              f"| {r['peak_iterations']} ({fmt(r.get('peak_iterations_at_s'), '.2f')}) "
              f"| {fmt(r.get('sign_changes'), '.2f')} | {fmt(r.get('hf_energy'), '.2g')} "
              f"| {', '.join(r['failed']) if r['failed'] else 'none'} |")


if __name__ == "__main__":
    sys.exit(main())
