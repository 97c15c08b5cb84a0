#!/usr/bin/env python3
"""Draws a robot in a posture, for `lexdyn-harness robot check` (docs/model.md): three views (front,
side, top) of its geometry outlines, its kinematic skeleton, the contact points, the support
polygon, the centre of mass and the data file's frames (soles, grasp points: x and z axes). Input: the JSON robot check writes; output: a PNG.

Usage: /usr/bin/python3 harness/scripts/robot_view.py VIEW.json OUT.png
"""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import Polygon  # noqa: E402


def main(argv):
    if len(argv) != 3 or argv[1] in ("-h", "--help"):
        print(__doc__.strip())
        return 0 if len(argv) == 2 else 2
    with open(argv[1]) as f:
        v = json.load(f)
    fig, axs = plt.subplots(1, 3, figsize=(13, 5.2))
    names = [("front (y, z)", 1, 2), ("side (x, z)", 0, 2), ("top (x, y)", 0, 1)]
    for k, (title, a, b) in enumerate(names):
        ax = axs[k]
        for poly in v["outlines"][k]:
            if len(poly) >= 3:
                ax.add_patch(Polygon(poly, closed=True, facecolor="#c8d0da", edgecolor="#8a96a3", linewidth=0.5, alpha=0.7))
        for p, q in v["bones"]:
            ax.plot([p[a], q[a]], [p[b], q[b]], color="#2b4a6f", linewidth=1.2)
        if k == 2 and len(v["support"]) >= 3:
            ax.add_patch(Polygon(v["support"], closed=True, facecolor="#9bd49b", edgecolor="#2e7d32", alpha=0.5, label="support polygon"))
        if v["contacts"]:
            ax.scatter([c[a] for c in v["contacts"]], [c[b] for c in v["contacts"]], s=14, color="#2e7d32", zorder=5, label="contact points")
        for fr in v.get("frames", []):
            p, x, z = fr["p"], fr["x"], fr["z"]
            ax.plot([p[a], x[a]], [p[b], x[b]], color="#d84315", linewidth=1.0, zorder=7)
            ax.plot([p[a], z[a]], [p[b], z[b]], color="#1565c0", linewidth=1.0, zorder=7)
            ax.annotate(fr["name"], (p[a], p[b]), fontsize=6, color="#37474f", xytext=(3, 3), textcoords="offset points", zorder=8)
        c = v["com"]
        ax.scatter([c[a]], [c[b]], s=60, marker="x", color="#c62828", zorder=6, label="centre of mass")
        if b == 2:
            ax.axhline(0.0, color="#555555", linewidth=0.8)
        ax.set_title(title)
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(True, linewidth=0.3)
        ax.set_xlabel("xyz"[a] + " (m)")
        ax.set_ylabel("xyz"[b] + " (m)")
        ax.autoscale_view()
    if v.get("frames"):
        axs[2].plot([], [], color="#d84315", label="frame x")
        axs[2].plot([], [], color="#1565c0", label="frame z")
    axs[2].legend(loc="upper right", fontsize=8)
    facing = "faces +x" if v.get("forward", 1) > 0 else "faces -x"
    fig.suptitle(v["title"] + " (" + facing + ")")
    fig.tight_layout()
    fig.savefig(argv[2], dpi=90)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
