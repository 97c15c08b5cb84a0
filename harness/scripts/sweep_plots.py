#!/usr/bin/python3
"""Robustness maps of a grid sweep (docs/sweeps.md, "Summaries").

Usage: /usr/bin/python3 harness/scripts/sweep_plots.py OUT_DIR

Reads OUT_DIR/maps/*.csv (written by `lexdyn-harness sweep run|merge` for a grid over two
parameters: columns X, Y, passed, margin, value) and writes a PNG beside each: one cell per grid
point, coloured by the margin (how far the value lies on the passing side of the limit; red
fails, blue passes, white on the limit), a cross on each failing cell. A property without a
margin (run_completed) is drawn pass / fail only.
"""
import csv
import glob
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.colors import TwoSlopeNorm  # noqa: E402


def read_map(path):
    with open(path) as f:
        title = f.readline().lstrip("# ").strip()
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    return title, header, body


def ordered(values):
    """Distinct values in numeric order when they are numbers, else in first-seen order."""
    seen = list(dict.fromkeys(values))
    try:
        return sorted(seen, key=float)
    except ValueError:
        return seen


def draw(path):
    title, header, body = read_map(path)
    xs = ordered([r[0] for r in body])
    ys = ordered([r[1] for r in body])
    grid = [[math.nan] * len(xs) for _ in ys]
    failed = []
    has_margin = False
    for x, y, passed, margin, _value in body:
        i, j = ys.index(y), xs.index(x)
        m = float(margin) if margin not in ("nan", "") else math.nan
        if not math.isnan(m):
            has_margin = True
        grid[i][j] = m if not math.isnan(m) else (1.0 if passed == "1" else -1.0)
        if passed != "1":
            failed.append((j, i))
    fig, ax = plt.subplots(figsize=(1.2 + 0.75 * len(xs), 1.2 + 0.6 * len(ys)))
    finite = [v for row in grid for v in row if not math.isnan(v)]
    lo, hi = (min(finite), max(finite)) if finite else (-1.0, 1.0)
    lo, hi = min(lo, -1e-12), max(hi, 1e-12)
    image = ax.imshow(grid, origin="lower", aspect="auto", cmap="RdBu", norm=TwoSlopeNorm(vmin=lo, vcenter=0.0, vmax=hi))
    for j, i in failed:
        ax.plot(j, i, marker="x", color="black", markersize=8)
    ax.set_xticks(range(len(xs)))
    ax.set_xticklabels([short(v) for v in xs], rotation=45, ha="right")
    ax.set_yticks(range(len(ys)))
    ax.set_yticklabels([short(v) for v in ys])
    ax.set_xlabel(header[0])
    ax.set_ylabel(header[1])
    ax.set_title("\n".join(title[k:k + 70] for k in range(0, len(title), 70)), fontsize=8)
    if has_margin:
        fig.colorbar(image, ax=ax, label="margin (< 0: fails)")
    fig.tight_layout()
    out = os.path.splitext(path)[0] + ".png"
    fig.savefig(out + ".partial.png", dpi=110)
    os.replace(out + ".partial.png", out)
    plt.close(fig)


def short(v):
    try:
        return "%.3g" % float(v)
    except ValueError:
        return v


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    maps = sorted(glob.glob(os.path.join(sys.argv[1], "maps", "*.csv")))
    for path in maps:
        draw(path)
    print("drew %d maps" % len(maps))
    return 0


if __name__ == "__main__":
    sys.exit(main())
