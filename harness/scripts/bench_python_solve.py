#!/usr/bin/env python3
"""The Python solve call's overhead over the C++ call (docs/performance.md, "Python"): the same
problem files solved by `lexdyn-solve --bench --default-options` (C++) and by lexdyn.Solver.solve in
a Python loop, in alternating pairs (/usr/bin/python3 with PYTHONPATH=build/python), and the
call's own cost inside the Python process (the call's time minus Result.solve_us, the C++
solve's). Pin it to one core (taskset -c N): a process moved between cores runs slower.

Usage: bench_python_solve.py [--pairs N] [--repeats R] [--bin DIR] FILES...

FILES are consecutive ticks (e.g. a run's --dump-problems folder). Both sides solve each tick
cold, and warm from the previous tick's result (the first tick of each repeat cold), R times; a
side's figure is the median over the ticks of each tick's best of its R repeats (a shared
machine's scheduler slices lengthen some repeats, rarely all). Prints one line per pair and the
overheads (Python minus C++ across the processes, and in-process): medians and ranges over the
pairs. Exit code 0; 2 on bad options or files.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import time

import lexdyn


def cpp_side(binary, files, repeats):
    """(cold, warm) tick-best medians in microseconds from lexdyn-solve --bench."""
    out = subprocess.run([binary, "--bench", "--default-options", "--repeats", str(repeats), *files],
                         check=True, capture_output=True, text=True).stdout
    j = json.loads(out)
    return j["cold"]["tick_best_median_us"], j["warm"]["tick_best_median_us"]


def python_side(problems, repeats):
    """(cold, warm) tick-best medians in microseconds, as lexdyn-solve --bench times them, and
    (cold, warm) medians over every call of the call's time minus its C++ solve's (Result.solve_us).
    A timed call includes freeing the result it replaces, as a Python loop pays it."""
    cold_solver, warm_solver = lexdyn.Solver(), lexdyn.Solver()
    cold_best = [float("inf")] * len(problems)
    warm_best = [float("inf")] * len(problems)
    cold_in, warm_in = [], []
    clock = time.perf_counter_ns
    for _ in range(repeats):
        prev = r = None
        for k, p in enumerate(problems):
            a = clock()
            r = cold_solver.solve(p)
            b = clock()
            cold_best[k] = min(cold_best[k], (b - a) / 1e3)
            cold_in.append((b - a) / 1e3 - r.solve_us)
            if k == 0:
                prev = warm_solver.solve(p)  # each repeat starts cold, like the first
                continue
            c = clock()
            prev = warm_solver.solve(p, warm=prev)
            d = clock()
            warm_best[k] = min(warm_best[k], (d - c) / 1e3)
            warm_in.append((d - c) / 1e3 - prev.solve_us)
    return (statistics.median(cold_best), statistics.median(warm_best[1:]),
            statistics.median(cold_in), statistics.median(warm_in))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="+", help="problem files, consecutive ticks")
    ap.add_argument("--pairs", type=int, default=6, help="alternating C++/Python pairs (default 6)")
    ap.add_argument("--repeats", type=int, default=20, help="repeats of the sequence per side (default 20)")
    ap.add_argument("--bin", default=os.path.join("build", "bin"), help="folder of lexdyn-solve (default build/bin)")
    a = ap.parse_args()
    if a.pairs < 1 or a.repeats < 1:
        ap.error("--pairs and --repeats must be at least 1")
    if len(a.files) < 2:
        ap.error("give at least two consecutive problem files (the warm solves need a previous tick)")
    binary = os.path.join(a.bin, "lexdyn-solve")
    if not os.access(binary, os.X_OK):
        ap.error(f"{binary}: not an executable (build first, or give --bin)")
    try:
        problems = [lexdyn.load_problem(f) for f in a.files]
    except (lexdyn.InputError, OSError) as e:
        print(f"bench_python_solve: {e}", file=sys.stderr)
        return 2
    over = {"cold": [], "warm": [], "cold in-process": [], "warm in-process": []}
    print(f"{len(problems)} ticks, {a.repeats} repeats, {a.pairs} pairs; microseconds (tick-best medians;")
    print("in-process: the median over the calls of the call's time minus its C++ solve's)")
    print("pair  C++ cold  Python cold  overhead  in-process | C++ warm  Python warm  overhead  in-process")
    for i in range(a.pairs):
        cc, cw = cpp_side(binary, a.files, a.repeats)
        pc, pw, ic, iw = python_side(problems, a.repeats)
        for key, v in (("cold", pc - cc), ("warm", pw - cw), ("cold in-process", ic), ("warm in-process", iw)):
            over[key].append(v)
        print(f"{i + 1:4d}  {cc:8.1f}  {pc:11.1f}  {pc - cc:8.1f}  {ic:10.2f} | {cw:8.1f}  {pw:11.1f}  {pw - cw:8.1f}  {iw:10.2f}",
              flush=True)
    for name, o in over.items():
        print(f"{name} overhead: median {statistics.median(o):.2f} us (range {min(o):.2f} to {max(o):.2f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
