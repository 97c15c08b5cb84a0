#!/usr/bin/env python3
"""Writes handover.csv: a recorded-like right-hand target for cases/exp3.yaml (the paper's exp. 3
follows a motion-capture wand; we make our own path). Deterministic (no random numbers): a
piecewise path through way-points, smoothed by a cosine blend, plus a small hand tremor made of
incommensurate sines. Times are seconds since the target_trajectory event; world frame, m.

    python3 cases/trajectories/make_handover.py > cases/trajectories/handover.csv

The path starts in front of the right hand's initial position, leaves the workspace to the front
and holds there (out of reach), sweeps out of reach to the right, re-enters the workspace for
hand-over-like moves in front of the chest, and ends near the start.
"""
import math

# (time s, x, y, z): way-points, held between successive times with a cosine blend.
WAYPOINTS = [
    (0.0, 0.10, -0.37, 0.70),   # near the hand's half-sitting position
    (4.0, 0.10, -0.37, 0.70),
    (9.0, 0.95, -0.55, 1.30),   # forward and up: out of reach
    (24.0, 1.00, -0.50, 1.35),  # held out there
    (30.0, 0.35, -1.20, 1.20),  # sweep to the right: out of reach
    (40.0, 0.30, -1.25, 1.10),
    (46.0, 0.45, -0.30, 1.05),  # back into the workspace: hand-over in front of the chest
    (52.0, 0.40, -0.20, 1.15),
    (58.0, 0.50, -0.35, 0.95),
    (64.0, 0.40, -0.30, 1.05),
    (72.0, 0.10, -0.37, 0.70),  # back near the start
    (76.0, 0.10, -0.37, 0.70),
]
SAMPLE_S = 0.05


def blended(t):
    for (t0, *p0), (t1, *p1) in zip(WAYPOINTS, WAYPOINTS[1:]):
        if t0 <= t <= t1:
            s = 0.5 - 0.5 * math.cos(math.pi * (t - t0) / (t1 - t0))
            return [a + s * (b - a) for a, b in zip(p0, p1)]
    return list(WAYPOINTS[-1][1:])


def tremor(t):
    # A few millimetres, like a hand holding a wand.
    return [0.004 * math.sin(2 * math.pi * 0.83 * t) + 0.002 * math.sin(2 * math.pi * 2.71 * t + 1.0),
            0.004 * math.sin(2 * math.pi * 0.61 * t + 2.0) + 0.002 * math.sin(2 * math.pi * 3.13 * t),
            0.003 * math.sin(2 * math.pi * 0.97 * t + 0.5) + 0.002 * math.sin(2 * math.pi * 2.29 * t + 2.5)]


def main():
    print("# Right-hand target for cases/exp3.yaml, written by make_handover.py (do not edit by hand).")
    print("t,x,y,z")
    n = int(round(WAYPOINTS[-1][0] / SAMPLE_S))
    for k in range(n + 1):
        t = k * SAMPLE_S
        p = [a + b for a, b in zip(blended(t), tremor(t))]
        print("%.2f,%.6f,%.6f,%.6f" % (t, *p))


if __name__ == "__main__":
    main()
