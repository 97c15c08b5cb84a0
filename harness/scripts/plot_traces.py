#!/usr/bin/python3
"""Plots of lexdyn-harness traces, one figure per quantity the paper plots (docs/results.md).

Usage: /usr/bin/python3 harness/scripts/plot_traces.py --out DIR [--title NAME]
                                      [--errors TASK,TASK] [--contact NAME]
                                      [--figures NAME,NAME] LABEL=TRACE.csv ...
--figures: only these figures (errors, velocities, torques, timing, augmentation, wrench,
second_order); all by default.

Needs Debian's python3-numpy and python3-matplotlib (harness/scripts/install-deps.sh installs
them); run it with /usr/bin/python3. Writes PNG files into DIR:
  task_errors.png       sum of the error norms of --errors tasks per run (paper Fig. 3, 18, 26)
  joint_velocities.png  commanded joint velocities, one panel per run (Fig. 4, 7, 10)
  timing.png            per-tick wall times and active-set iterations (Fig. 6, 9, 11)
  augmentation.png      map of augmented (Newton) levels and active tasks (Fig. 5, 8)
  torques.png           commanded joint torques per run (Fig. 12)
  wrench_<contact>.png  computed (controller) and sensed contact force/torque (Fig. 13, 27)
  second_order.png      size of the Newton rows against J^T J on every augmented level
                        (level.<L>.second_order_ratio solid, .curvature_ratio dashed; log scale),
                        when a trace has those channels
Files are written to a temporary name first and renamed, so an interrupted run leaves no
half-written figure. Traces are read by the lexdyn package (python/lexdyn; PYTHONPATH=python from
the repository's root, or the installed package: docs/python.md); a trace that is not one is an
error naming the file, the line and the channel (exit code 2).
"""
import argparse
import os
import sys

import numpy as np

import lexdyn

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

FIGURES = ["errors", "velocities", "torques", "timing", "augmentation", "wrench", "second_order"]


class Trace:
    """A trace (lexdyn.read_trace) with the label of its run."""

    def __init__(self, label, path):
        self.label = label
        self.path = path
        self.trace = lexdyn.read_trace(path)
        self.header = self.trace.names
        self.t = self.trace.t

    def has(self, name):
        return self.trace.has(name)

    def col(self, name):
        return self.trace.col(name)

    def cols(self, prefix):
        names = self.trace.matching(prefix)
        return names, self.trace.cols(names)


def save(fig, out, name):
    path = os.path.join(out, name)
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=110, bbox_inches="tight")
    plt.close(fig)
    os.replace(tmp, path)
    print(f"plot_traces: wrote {path}")


def plot_errors(traces, tasks, out, title):
    fig, axes = plt.subplots(2, 1, figsize=(9, 6), sharex=True, gridspec_kw={"height_ratios": [3, 2]})
    ref = None
    for tr in traces:
        names = [f"task.{t}.error" for t in tasks if tr.has(f"task.{t}.error")]
        if not names:
            continue
        s = sum(tr.col(n) for n in names)
        axes[0].plot(tr.t, s, label=f"{tr.label} (final {s[-1]:.3f})")
        if ref is None:
            ref = (tr, s)
        else:
            n = min(len(ref[1]), len(s))
            axes[1].plot(tr.t[:n], s[:n] - ref[1][:n], label=f"{tr.label} - {ref[0].label}")
    axes[0].set_ylabel("sum of error norms")
    axes[0].set_title(f"{title}: {' + '.join(tasks)}")
    axes[0].legend()
    axes[0].grid(alpha=0.3)
    axes[1].set_ylabel("difference")
    axes[1].set_xlabel("t (s)")
    axes[1].grid(alpha=0.3)
    if axes[1].lines:
        axes[1].legend()
    save(fig, out, "task_errors.png")


def panels(traces, prefix, ylabel, out, name, title):
    fig, axes = plt.subplots(len(traces), 1, figsize=(9, 2.6 * len(traces)), sharex=True, squeeze=False)
    for ax, tr in zip(axes[:, 0], traces):
        names, v = tr.cols(prefix)
        for k in range(v.shape[1]):
            ax.plot(tr.t, v[:, k], lw=0.7)
        ax.set_ylabel(ylabel)
        ax.set_title(f"{title}, {tr.label}", fontsize=9)
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel("t (s)")
    save(fig, out, name)


def plot_timing(traces, out, title):
    fig, axes = plt.subplots(len(traces), 1, figsize=(9, 2.8 * len(traces)), sharex=True, squeeze=False)
    for ax, tr in zip(axes[:, 0], traces):
        for timer in ["model", "tasks", "hessian", "solver", "tick"]:
            ch = f"time.{timer}_us"
            if tr.has(ch):
                v = tr.col(ch)
                ax.plot(tr.t, v / 1000.0, lw=0.6, label=f"{timer} (max {v.max() / 1000.0:.2f} ms)")
        ax.set_ylabel("ms")
        ax.grid(alpha=0.3)
        ax2 = ax.twinx()
        if tr.has("solver.iterations"):
            it = tr.col("solver.iterations")
            ax2.plot(tr.t, it, "k.", ms=1.5, label=f"active-set iterations (max {int(it.max())})")
            ax2.set_ylabel("iterations")
        ax.set_title(f"{title}, {tr.label}", fontsize=9)
        h1, l1 = ax.get_legend_handles_labels()
        h2, l2 = ax2.get_legend_handles_labels()
        ax.legend(h1 + h2, l1 + l2, fontsize=7, loc="upper left")
    axes[-1, 0].set_xlabel("t (s)")
    save(fig, out, "timing.png")


def plot_augmentation(traces, out, title):
    fig, axes = plt.subplots(len(traces), 1, figsize=(9, 3.0 * len(traces)), sharex=True, squeeze=False)
    for ax, tr in zip(axes[:, 0], traces):
        rows = []
        for n in tr.header:
            if n.startswith("task.") and n.endswith(".active"):
                rows.append((n[5:-7] + " active", tr.col(n) > 0, "0.75"))
        for n in tr.header:
            if n.startswith("level.") and n.endswith(".augmented"):
                rows.append((n[6:-10] + " Newton", tr.col(n) > 0, "0.25"))
        for k, (label, on, color) in enumerate(rows):
            ax.fill_between(tr.t, k + 0.1, k + 0.9, where=on, color=color, step="post", lw=0)
        ax.set_yticks([k + 0.5 for k in range(len(rows))])
        ax.set_yticklabels([r[0] for r in rows], fontsize=6)
        ax.set_ylim(0, max(1, len(rows)))
        ax.set_title(f"{title}, {tr.label}: activity (light) and Newton augmentation (dark)", fontsize=9)
    axes[-1, 0].set_xlabel("t (s)")
    save(fig, out, "augmentation.png")


def plot_wrench(traces, contact, out, title):
    comps = ["fx", "fy", "fz", "tx", "ty", "tz"]
    fig, axes = plt.subplots(len(traces), 2, figsize=(11, 2.8 * len(traces)), sharex=True, squeeze=False)
    for row, tr in zip(axes, traces):
        for k, c in enumerate(comps):
            ax = row[0] if k < 3 else row[1]
            calc = f"wrench.{contact}.{c}"
            sens = f"wrench_sensed.{contact}.{c}"
            if tr.has(calc):
                ax.plot(tr.t, tr.col(calc), lw=0.7, label=f"{c} calc")
            if tr.has(sens):
                ax.plot(tr.t, tr.col(sens), lw=0.7, ls="--", label=f"{c} sens")
        row[0].set_ylabel("N")
        row[1].set_ylabel("N m")
        row[0].set_title(f"{title}, {tr.label}, {contact} forces", fontsize=9)
        row[1].set_title(f"{title}, {tr.label}, {contact} torques", fontsize=9)
        for ax in row:
            ax.grid(alpha=0.3)
            ax.legend(fontsize=6, ncol=3)
    for ax in axes[-1]:
        ax.set_xlabel("t (s)")
    save(fig, out, f"wrench_{contact}.png")


def plot_second_order(traces, out, title):
    """Per level, level.<L>.second_order_ratio (the rows the method added, identity terms included)
    and .curvature_ratio (the method's own curvature alone) of every run, log scale; nan (the
    level not augmented) leaves a gap."""
    levels = []
    for tr in traces:
        for n in tr.header:
            if n.startswith("level.") and n.endswith(".second_order_ratio"):
                lv = n[6:-len(".second_order_ratio")]
                if lv not in levels and np.isfinite(tr.col(n)).any():
                    levels.append(lv)
    if not levels:
        return
    fig, axes = plt.subplots(len(levels), 1, figsize=(9, 3.2 * len(levels)), sharex=True, squeeze=False)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, lv in zip(axes[:, 0], levels):
        for k, tr in enumerate(traces):
            c = colors[k % len(colors)]
            for suffix, ls, what in [("second_order_ratio", "-", "rows"), ("curvature_ratio", "--", "curvature")]:
                ch = f"level.{lv}.{suffix}"
                if not tr.has(ch):
                    continue
                v = tr.col(ch)
                ok = np.isfinite(v) & (v > 0)
                if not ok.any():
                    continue
                med = np.median(v[ok])
                ax.plot(tr.t, np.where(ok, v, np.nan), lw=0.7, ls=ls, color=c, label=f"{tr.label} {what} (median {med:.2g})")
        ax.set_yscale("log")
        ax.set_ylabel("trace ratio to J^T J")
        ax.set_title(f"{title}: level {lv}, Newton rows (solid) and curvature alone (dashed)", fontsize=9)
        ax.grid(alpha=0.3, which="both")
        if ax.lines:
            ax.legend(fontsize=7)
    axes[-1, 0].set_xlabel("t (s)")
    save(fig, out, "second_order.png")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--title", default="")
    ap.add_argument("--errors", default="right_hand,left_hand", help="tasks whose error norms are summed")
    ap.add_argument("--contact", action="append", default=[], help="contact for the wrench figure (repeatable)")
    ap.add_argument("--figures", default=",".join(FIGURES), help="comma-separated: " + ", ".join(FIGURES))
    ap.add_argument("runs", nargs="+", help="LABEL=TRACE.csv")
    a = ap.parse_args()
    figures = [f for f in a.figures.split(",") if f]
    for f in figures:
        if f not in FIGURES:
            sys.exit(f"plot_traces: --figures: unknown figure '{f}' (one of {', '.join(FIGURES)})")
    traces = []
    for r in a.runs:
        if "=" not in r:
            sys.exit(f"plot_traces: '{r}': expected LABEL=TRACE.csv")
        label, path = r.split("=", 1)
        if not os.path.isfile(path):
            sys.exit(f"plot_traces: {path}: no such file")
        try:
            traces.append(Trace(label, path))
        except lexdyn.FormatError as e:
            print(f"plot_traces: {e}", file=sys.stderr)
            sys.exit(2)
    os.makedirs(a.out, exist_ok=True)
    title = a.title or os.path.basename(os.path.dirname(os.path.abspath(traces[0].path)))
    if "errors" in figures:
        plot_errors(traces, [t for t in a.errors.split(",") if t], a.out, title)
    if "velocities" in figures:
        panels(traces, "cmd.qd.", "rad/s", a.out, "joint_velocities.png", f"{title}: commanded joint velocities")
    if "torques" in figures:
        panels(traces, "cmd.tau.", "N m", a.out, "torques.png", f"{title}: commanded joint torques")
    if "timing" in figures and any(tr.has("time.tick_us") for tr in traces):
        plot_timing(traces, a.out, title)
    if "augmentation" in figures:
        plot_augmentation(traces, a.out, title)
    if "wrench" in figures:
        for c in a.contact:
            plot_wrench(traces, c, a.out, title)
    if "second_order" in figures:
        plot_second_order(traces, a.out, title)


if __name__ == "__main__":
    main()
