#!/usr/bin/python3
"""The nightly report of lexdyn runs: one folder (index.html, figures, 3D replay data, three.js)
that opens from disk with no server and no network (docs/report.md).

Usage: /usr/bin/python3 harness/scripts/report.py --runs DIR [--sweeps DIR] [--history FILE]
                                                  --out DIR [--append-history] [--title TEXT]

  --runs DIR        run directories (<id>/summary.json, trace.csv, log.txt), as
                    harness/scripts/nightly.sh or full-runs.sh write them; optional
                    nightly.json, runs.txt, compare/<case>.json, ctest/junit.xml
  --sweeps DIR      one sweep output directory (summary.json, results.jsonl) or a directory of them
  --history FILE    JSON Lines, one record per night: the trend and "since last night"
  --append-history  also write this night's record into FILE (replacing a record of the same
                    night), as the nightly job does
  --out DIR         the report folder (created; files are replaced one by one, atomically)

Built from stored results alone, so a report can be rebuilt at any time. Needs Debian's
python3-numpy, python3-matplotlib, python3-yaml and libjs-three (install-deps.sh).
Exit codes: 0 the report was written; 2 bad input (the message names the file and the key);
3 internal error.
"""
import argparse
import os
import sys
import traceback

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from lexdyn_report.common import ReportInputError  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", required=True)
    ap.add_argument("--sweeps")
    ap.add_argument("--history")
    ap.add_argument("--out", required=True)
    ap.add_argument("--append-history", action="store_true")
    ap.add_argument("--title")
    try:
        a = ap.parse_args(argv)
    except SystemExit as e:
        return 2 if e.code else 0
    if a.append_history and not a.history:
        print("report: error: --append-history: expected --history FILE as well, found none", file=sys.stderr)
        return 2
    try:
        from lexdyn_report import page, runs, sweeps
        results = runs.Results(a.runs)
        sw = sweeps.load_sweeps(a.sweeps)
        b = page.ReportBuilder(results, sw, a.history, a.out, append_history=a.append_history, title=a.title)
        index = b.build()
    except ReportInputError as e:
        print(f"report: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("report: interrupted", file=sys.stderr)
        return 130
    except Exception:  # noqa: BLE001 - an internal error is exit code 3 with its traceback
        traceback.print_exc()
        print("report: internal error", file=sys.stderr)
        return 3
    size, files = page.folder_size(a.out)
    for w in b.warnings:
        print(f"report: warning: {w}", file=sys.stderr)
    print(f"report: wrote {index} ({files} files, {size / 1e6:.2f} MB in {a.out}); "
          f"{len(results.runs)} runs, {len(b.replays)} replays, {len(sw)} sweeps"
          + (f", history {a.history}" + (" (appended)" if a.append_history else "") if a.history else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
