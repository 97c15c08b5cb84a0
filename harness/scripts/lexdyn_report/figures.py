"""matplotlib figures of the report (docs/report.md, "Per case"): the paper's figure types across
methods, one colour per method (common.METHOD_COLOURS) in every figure.

Each function takes the case's runs with their traces and writes one PNG (temporary name, then
rename), returning {"key", "title", "file", "caption"} or None when no run has the channels.
"""
import io
import os

import numpy as np

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import Rectangle  # noqa: E402

from .common import method_colour, method_label, write_atomic  # noqa: E402

DPI = 80
plt.rcParams.update({"font.size": 8, "axes.titlesize": 9, "axes.grid": True, "grid.alpha": 0.3,
                     "legend.fontsize": 7, "lines.linewidth": 0.9})


def save(fig, out_dir, name):
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI, bbox_inches="tight", pil_kwargs={"optimize": True})
    plt.close(fig)
    write_atomic(os.path.join(out_dir, name), buf.getvalue())
    return name


def label(run):
    return method_label(run.method) if run.method or len(run.id.split(".")) == 1 else run.id


def _legend(ax, loc="best"):
    h, l = ax.get_legend_handles_labels()
    if h:
        ax.legend(loc=loc)


# --------------------------------------------------------------------------- task errors
def task_errors(case, items, out_dir, prefix, key_tasks):
    """Sum of the key tasks' error norms (the paper's Fig. 3 / 18 / 26) and every other task
    with a non-zero error, one panel each, methods overlaid."""
    tasks = []
    for run, tr in items:
        for n in tr.matching("task.", ".error"):
            t = n[len("task."):-len(".error")]
            if t not in tasks:
                tasks.append(t)
    if not tasks:
        return None
    panels = []
    if key_tasks:
        panels.append(("sum: " + " + ".join(key_tasks), key_tasks))
    for t in tasks:
        nonzero = any(tr.has(f"task.{t}.error") and np.nanmax(np.abs(np.where(np.isfinite(tr.col(f"task.{t}.error")),
                                                                            tr.col(f"task.{t}.error"), 0))) > 0
                      for _, tr in items)
        if nonzero and [t] != key_tasks:
            panels.append((t, [t]))
    panels = panels[:12]
    ncols = 3 if len(panels) > 2 else len(panels)
    nrows = (len(panels) + ncols - 1) // ncols
    fig, axes = plt.subplots(nrows, ncols, figsize=(10.5, 2.3 * nrows + 0.4), squeeze=False, sharex=True)
    for ax, (title, names) in zip(axes.flat, panels):
        for run, tr in items:
            if not all(tr.has(f"task.{n}.error") for n in names):
                continue
            s = sum(tr.col(f"task.{n}.error") for n in names)
            fin = s[np.isfinite(s)]
            ax.plot(tr.t, s, color=method_colour(run.method),
                    label=f"{label(run)} (final {fin[-1]:.4g})" if len(fin) else label(run))
        ax.set_title(title)
        _legend(ax)
    for ax in list(axes.flat)[len(panels):]:
        ax.set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("t (s)")
    axes[0, 0].set_ylabel("error norm")
    fig.suptitle(f"{case}: task error norms", fontsize=10)
    return {"key": "task_errors", "title": "Task error norms", "file": save(fig, out_dir, f"{prefix}task_errors.png"),
            "caption": "Error norm of every task with a non-zero error; the first panel sums the tasks the case compares "
                       "(the paper's convergence figure)."}


# --------------------------------------------------------------------------- joint velocities
def joint_velocities(case, items, out_dir, prefix):
    have = [(r, tr, tr.matching("cmd.qd.") or tr.matching("qd.")) for r, tr in items]
    have = [h for h in have if h[2]]
    if not have:
        return None
    fig, axes = plt.subplots(len(have), 1, figsize=(10.5, 1.9 * len(have) + 0.4), squeeze=False, sharex=True)
    for ax, (run, tr, names) in zip(axes[:, 0], have):
        v = tr.cols(names)
        c = method_colour(run.method)
        for k in range(v.shape[1]):
            ax.plot(tr.t, v[:, k], color=c, alpha=0.35, lw=0.6)
        with np.errstate(invalid="ignore"):
            peak = np.nanmax(np.abs(v), axis=0) if v.size else np.zeros(0)
        if peak.size and np.isfinite(peak).any():
            j = int(np.nanargmax(peak))
            ax.plot(tr.t, v[:, j], color=c, lw=1.0, label=f"{names[j].split('.', 2)[-1]} (peak {peak[j]:.3g} rad/s)")
        kind = "commanded" if names[0].startswith("cmd.") else "measured"
        ax.set_title(f"{label(run)}: {kind} joint velocities ({len(names)} joints)")
        ax.set_ylabel("rad/s")
        _legend(ax, "upper right")
    axes[-1, 0].set_xlabel("t (s)")
    return {"key": "joint_velocities", "title": "Joint velocities", "file": save(fig, out_dir, f"{prefix}joint_velocities.png"),
            "caption": "Every joint's velocity (commanded where the controller runs), the joint with the largest peak drawn bold."}


# --------------------------------------------------------------------------- torques
def torques(case, items, out_dir, prefix, efforts):
    have = []
    for run, tr in items:
        names = [n for n in (tr.matching("cmd.tau.") or tr.matching("tau.")) if efforts.get(n.split(".")[-1])]
        if names:
            have.append((run, tr, names))
    if not have:
        return None
    fig, (ax, bx) = plt.subplots(2, 1, figsize=(10.5, 5.6), gridspec_kw={"height_ratios": [1, 1]})
    width = 0.8 / len(have)
    joints = [n.split(".")[-1] for n in have[0][2]]
    for k, (run, tr, names) in enumerate(have):
        lim = np.array([efforts[n.split(".")[-1]] for n in names])
        ratio = np.abs(tr.cols(names)) / lim
        c = method_colour(run.method)
        ax.plot(tr.t, np.nanmax(ratio, axis=1), color=c, label=f"{label(run)} ({names[0].split('.')[0]}: peak {np.nanmax(ratio):.3f})")
        applied = [n for n in tr.matching("tau.") if efforts.get(n.split(".")[-1])]
        if names[0].startswith("cmd.") and applied:
            la = np.array([efforts[n.split(".")[-1]] for n in applied])
            ax.plot(tr.t, np.nanmax(np.abs(tr.cols(applied)) / la, axis=1), color=c, ls=":", lw=0.8,
                    label=f"{label(run)} applied")
        peaks = [np.nanmax(ratio[:, names.index(n)]) if n in names else np.nan for n in
                 [f"{names[0].rsplit('.', 1)[0]}.{j}" for j in joints]]
        bx.bar(np.arange(len(joints)) + (k - (len(have) - 1) / 2) * width, peaks, width, color=c, label=label(run))
    for a in (ax, bx):
        a.axhline(1.0, color="k", lw=0.8, ls="--")
    ax.set_ylabel("max |tau| / limit")
    ax.set_xlabel("t (s)")
    ax.set_title(f"{case}: largest joint torque relative to its URDF effort limit (dashed: the limit)")
    _legend(ax, "upper right")
    bx.set_xticks(np.arange(len(joints)))
    bx.set_xticklabels(joints, rotation=90, fontsize=6)
    bx.set_ylabel("peak |tau| / limit")
    bx.set_title("per joint, over the run")
    _legend(bx, "upper right")
    fig.tight_layout()
    return {"key": "torques", "title": "Torques against their limits", "file": save(fig, out_dir, f"{prefix}torques.png"),
            "caption": "Commanded (solid) and applied (dotted) torques as a fraction of each joint's effort limit: "
                       "the largest over the joints at every tick, and each joint's peak."}


# --------------------------------------------------------------------------- activity map
def activity(case, items, out_dir, prefix):
    have = []
    for run, tr in items:
        rows = [(n[len("task."):-len(".active")] + " active", tr.col(n) > 0, 0.35) for n in tr.matching("task.", ".active")]
        rows += [(n[len("level."):-len(".augmented")] + " Newton", tr.col(n) > 0, 1.0) for n in tr.matching("level.", ".augmented")]
        if rows:
            have.append((run, tr, rows))
    if not have:
        return None
    fig, axes = plt.subplots(len(have), 1, figsize=(10.5, sum(0.9 + 0.16 * len(h[2]) for h in have) + 0.3),
                             squeeze=False, sharex=True,
                             gridspec_kw={"height_ratios": [max(1, len(h[2])) for h in have]})
    for ax, (run, tr, rows) in zip(axes[:, 0], have):
        c = method_colour(run.method)
        for k, (name, on, alpha) in enumerate(rows):
            ax.fill_between(tr.t, k + 0.1, k + 0.9, where=on, color=c, alpha=alpha, step="post", lw=0)
        ax.set_yticks([k + 0.5 for k in range(len(rows))])
        ax.set_yticklabels([r[0] for r in rows], fontsize=6)
        ax.set_ylim(0, max(1, len(rows)))
        ax.grid(False)
        ax.set_title(f"{label(run)}: rows held by the solver (light) and Newton augmentation per level (dark)")
    axes[-1, 0].set_xlabel("t (s)")
    return {"key": "activity", "title": "Active constraints and Newton augmentation", "file": save(fig, out_dir, f"{prefix}activity.png"),
            "caption": "When each task has rows in the active set (light) and when each level is augmented with Newton rows (dark)."}


# --------------------------------------------------------------------------- solver
def solver(case, items, out_dir, prefix):
    have = [(r, tr) for r, tr in items if tr.has("solver.iterations")]
    if not have:
        return None
    timers = any(tr.has("time.tick_us") for _, tr in have)
    fig, axes = plt.subplots(2 if timers else 1, 1, figsize=(10.5, 5.2 if timers else 2.8), squeeze=False, sharex=True)
    ax = axes[0, 0]
    for run, tr in have:
        it = tr.col("solver.iterations")
        ax.step(tr.t, it, where="post", color=method_colour(run.method), alpha=0.8, label=f"{label(run)} (peak {int(np.nanmax(it))})")
    ax.set_ylabel("active-set iterations")
    ax.set_title(f"{case}: active-set iterations per tick")
    _legend(ax, "upper right")
    if timers:
        bx = axes[1, 0]
        for run, tr in have:
            if not tr.has("time.tick_us"):
                continue
            v = tr.col("time.tick_us")
            tm = (run.summary or {}).get("timing_us", {}).get("tick", {})
            bx.plot(tr.t, v / 1000.0, color=method_colour(run.method), lw=0.5, alpha=0.8,
                    label=f"{label(run)} (p50 {tm.get('median', float('nan')):.0f} us, p99 {tm.get('p99', float('nan')):.0f} us)")
        bx.set_yscale("log")
        bx.set_ylabel("tick wall time (ms)")
        bx.set_title("controller tick time (wall clock: machine-dependent, decides nothing)")
        _legend(bx, "upper right")
    axes[-1, 0].set_xlabel("t (s)")
    return {"key": "solver", "title": "Solver iterations and tick times", "file": save(fig, out_dir, f"{prefix}solver.png"),
            "caption": "Active-set iterations of every tick, and the wall time of the whole controller tick."}


# --------------------------------------------------------------------------- wrenches
def wrenches(case, items, out_dir, prefix):
    contacts = []
    for _, tr in items:
        for n in tr.matching("wrench.", ".fz") + tr.matching("wrench_sensed.", ".fz"):
            c = n.split(".")[1]
            if c not in contacts:
                contacts.append(c)
    surfaces = []
    if not contacts:
        for _, tr in items:
            for n in tr.matching("contact.", ".fz"):
                s = n.split(".")[1]
                if s not in surfaces:
                    surfaces.append(s)
        if not surfaces:
            return None
        fig, ax = plt.subplots(1, 1, figsize=(10.5, 2.8))
        styles = ["-", "--", ":", "-."]
        for run, tr in items:
            for k, s in enumerate(surfaces):
                if tr.has(f"contact.{s}.fz"):
                    ax.plot(tr.t, tr.col(f"contact.{s}.fz"), color=method_colour(run.method), ls=styles[k % 4], label=f"{label(run)} {s}")
        ax.set_ylabel("N")
        ax.set_xlabel("t (s)")
        ax.set_title(f"{case}: vertical contact force per surface (simulator)")
        _legend(ax)
        return {"key": "wrenches", "title": "Contact forces", "file": save(fig, out_dir, f"{prefix}wrenches.png"),
                "caption": "The simulator's vertical contact force of each surface (no controller contacts in this case)."}
    fig, axes = plt.subplots(len(contacts), 2, figsize=(10.5, 2.5 * len(contacts) + 0.3), squeeze=False, sharex=True)
    for row, c in zip(axes, contacts):
        for run, tr in items:
            col = method_colour(run.method)
            calc = [f"wrench.{c}.{k}" for k in ("fx", "fy", "fz")]
            sens = [f"wrench_sensed.{c}.{k}" for k in ("fx", "fy", "fz")]
            hc, hs = all(tr.has(n) for n in calc), all(tr.has(n) for n in sens)
            active = tr.col(f"ctrl_contact.{c}.active") > 0.5 if tr.has(f"ctrl_contact.{c}.active") else np.ones(tr.rows, bool)
            if hc:
                row[0].plot(tr.t, np.where(active, tr.col(calc[2]), np.nan), color=col, label=f"{label(run)} computed")
            if hs:
                row[0].plot(tr.t, np.where(active, tr.col(sens[2]), np.nan), color=col, ls="--", lw=0.7, label=f"{label(run)} sensed")
            if hc and hs:
                d = np.linalg.norm(tr.cols(calc) - tr.cols(sens), axis=1)
                d = np.where(active, d, np.nan)
                fin = d[np.isfinite(d)]
                rms = float(np.sqrt(np.mean(fin ** 2))) if len(fin) else float("nan")
                row[1].plot(tr.t, d, color=col, lw=0.6, label=f"{label(run)} (rms {rms:.3g} N)")
        row[0].set_title(f"{c}: normal force fz, computed (solid) and sensed (dashed)")
        row[0].set_ylabel("N")
        row[1].set_title(f"{c}: |computed - sensed| force")
        row[1].set_ylabel("N")
        _legend(row[0], "upper right")
        _legend(row[1], "upper right")
    for ax in axes[-1]:
        ax.set_xlabel("t (s)")
    return {"key": "wrenches", "title": "Contact wrenches, computed vs sensed", "file": save(fig, out_dir, f"{prefix}wrenches.png"),
            "caption": "The controller's planned contact force against the force/torque sensor's reading, in the contact frame, while the contact is active."}


# --------------------------------------------------------------------------- CoM in its boxes
def com_path(case, items, out_dir, prefix):
    have = [(r, tr) for r, tr in items if tr.has("com.x") and tr.has("com.y")]
    if not have:
        return None
    box_task = None
    for _, tr in have:
        b = tr.matching("target.", ".lower_x")
        if b:
            box_task = b[0][len("target."):-len(".lower_x")]
            break
    if box_task is None:
        return None
    fig = plt.figure(figsize=(10.5, 4.2))
    gs = fig.add_gridspec(2, 2, width_ratios=[1, 1.6])
    ax = fig.add_subplot(gs[:, 0])
    axx, axy = fig.add_subplot(gs[0, 1]), fig.add_subplot(gs[1, 1], sharex=None)
    ref = next(tr for _, tr in have if tr.has(f"target.{box_task}.lower_x"))
    keys = [f"target.{box_task}.{s}_{a}" for s in ("lower", "upper") for a in "xy"]
    bounds = ref.cols(keys)
    seen = []
    for i in range(ref.rows):
        b = tuple(bounds[i])
        if not seen or b != seen[-1][1]:
            seen.append((ref.t[i], b))
    shown = [s for s in seen if all(np.isfinite(s[1]))]
    step = max(1, len(shown) // 6)
    for k, (t0, (lx, ly, ux, uy)) in enumerate(shown[::step]):
        ax.add_patch(Rectangle((lx, ly), ux - lx, uy - ly, fill=False, ls="--", lw=0.9, color="#8e44ad"))
        ax.annotate(f"from {t0:.3g} s", (lx, uy), fontsize=6, color="#8e44ad")
    for run, tr in have:
        c = method_colour(run.method)
        ax.plot(tr.col("com.x"), tr.col("com.y"), color=c, label=label(run))
        ax.plot(tr.col("com.x")[:1], tr.col("com.y")[:1], "o", color=c, ms=3)
        axx.plot(tr.t, tr.col("com.x"), color=c)
        axy.plot(tr.t, tr.col("com.y"), color=c)
    for a, (lo, hi) in ((axx, (0, 2)), (axy, (1, 3))):
        a.step(ref.t, bounds[:, lo], where="post", color="#8e44ad", ls="--", lw=0.8)
        a.step(ref.t, bounds[:, hi], where="post", color="#8e44ad", ls="--", lw=0.8)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("CoM x (m)")
    ax.set_ylabel("CoM y (m)")
    ax.set_title(f"{case}: CoM path in its boxes ({box_task})")
    _legend(ax)
    axx.set_ylabel("x (m)")
    axy.set_ylabel("y (m)")
    axy.set_xlabel("t (s)")
    axx.set_title("CoM and the box bounds over time")
    fig.tight_layout()
    return {"key": "com", "title": "CoM path in its boxes", "file": save(fig, out_dir, f"{prefix}com.png"),
            "caption": "The centre of mass seen from above with the CoM box (dashed; each box labelled with when it starts), and x, y over time against the bounds."}


# --------------------------------------------------------------------------- trend
def trend_figure(metric, per_run, out_dir, name):
    """Small multiples: one panel per run with this metric's nightly values, the noise band of
    the previous nights (shaded) and a flagged last value (red ring)."""
    runs = [(rid, d[metric.key]) for rid, d in per_run.items() if len(d[metric.key]["values"]) >= 1]
    if not runs:
        return None
    ncols = 5
    nrows = (len(runs) + ncols - 1) // ncols
    fig, axes = plt.subplots(nrows, ncols, figsize=(10.5, 1.25 * nrows + 0.4), squeeze=False)
    for ax, (rid, d) in zip(axes.flat, runs):
        vals = [v for _, _, v in d["values"]]
        x = np.arange(len(vals))
        method = rid.split(".", 1)[1] if "." in rid else ""
        ax.plot(x, vals, "-o", ms=2, lw=0.8, color=method_colour(method))
        if d["band"] is not None:
            ax.axhspan(d["band"][0], d["band"][1], color="0.85", lw=0)
        if d["flag"]:
            ax.plot(x[-1:], vals[-1:], "o", ms=7, mfc="none", mec="#c0392b", mew=1.4)
        ax.set_title(rid, fontsize=7)
        ax.ticklabel_format(axis="y", useOffset=False)
        ax.tick_params(labelsize=6)
        ax.set_xticks([])
        ax.grid(False)
    for ax in list(axes.flat)[len(runs):]:
        ax.set_visible(False)
    fig.suptitle(f"{metric.label}: nightly values (last = this night; shaded: noise band of the earlier nights)", fontsize=9)
    fig.tight_layout()
    return save(fig, out_dir, name)
