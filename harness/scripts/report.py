#!/usr/bin/python3
"""The nightly report of lexdyn runs: one folder (index.html, figures, 3D replay data, three.js)
that opens from disk with no server and no network (docs/report.md).

Usage: /usr/bin/python3 harness/scripts/report.py --runs DIR [--sweeps DIR] [--history FILE]
                                                  --out DIR [--append-history] [--strict-history]
                                                  [--title TEXT]

  --runs DIR        run directories (<id>/summary.json, trace.csv, log.txt), as
                    harness/scripts/nightly.sh or full-runs.sh write them; optional
                    nightly.json, runs.txt, compare/<case>.json, ctest/junit.xml
  --sweeps DIR      one sweep output directory (summary.json, results.jsonl) or a directory of them
  --history FILE    JSON Lines, one record per night: the trend and "since last night"; a line
                    that is no record is skipped with a warning
  --append-history  also write this night's record into FILE (replacing a record of the same
                    night; the records in date order), as the nightly job does
  --strict-history  refuse a history with a line that is no record or a figure that is not a
                    number (exit code 2) instead of skipping it
  --out DIR         the report folder (created), locked while the report is built (DIR/.lexdyn.lock:
                    a second job on DIR exits 2); the report is built in DIR/.staging-PID and
                    swapped in whole, so a failed build leaves the previous report as it was

Built from stored results alone, so a report can be rebuilt at any time. Reads them with the
lexdyn Python package (python/lexdyn; PYTHONPATH=python from the repository's root, as the
scripts of harness/scripts set it, or the installed package: docs/python.md). Needs Debian's
python3-numpy, python3-matplotlib, python3-yaml and libjs-three (install-deps.sh).
Exit codes: 0 the report was written; 2 bad input or options (the message names the file, the
line and the key), --out in use by another job or not a folder; 3 a file that cannot be written
or read (a full disk: "DIR: No space left on device"), an internal error (with its traceback);
130 / 143 interrupted by SIGINT / SIGTERM.
"""
import argparse
import signal
import sys
import traceback

from lexdyn import FormatError
from lexdyn_report.common import ReportOutputError, os_reason


class BadOptions(Exception):
    pass


class Terminated(BaseException):
    """SIGTERM, raised where the program is, so that the staging folder is removed."""


class Parser(argparse.ArgumentParser):
    def error(self, message):
        # One line, as every lexdyn tool: "report: error: ...", exit code 2 (no usage block).
        raise BadOptions(message)


def _on_sigterm(signum, frame):
    raise Terminated()


def main(argv=None):
    ap = Parser(prog="report", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", required=True)
    ap.add_argument("--sweeps")
    ap.add_argument("--history")
    ap.add_argument("--out", required=True)
    ap.add_argument("--append-history", action="store_true")
    ap.add_argument("--strict-history", action="store_true")
    ap.add_argument("--title")
    try:
        a = ap.parse_args(argv)
    except BadOptions as e:
        print(f"report: error: {e} (--help for the options)", file=sys.stderr)
        return 2
    except SystemExit as e:  # --help
        return 2 if e.code else 0
    for opt, given in (("--append-history", a.append_history), ("--strict-history", a.strict_history)):
        if given and not a.history:
            print(f"report: error: {opt}: expected --history FILE as well, found none", file=sys.stderr)
            return 2
    signal.signal(signal.SIGTERM, _on_sigterm)
    lock = None
    try:
        from lexdyn_report import locks, page, runs, sweeps
        # First the folder's lock: a second job on the same --out stops at once.
        lock = locks.FolderLock(a.out, "report.py")
        results = runs.Results(a.runs)
        sw = sweeps.load_sweeps(a.sweeps)
        b = page.ReportBuilder(results, sw, a.history, a.out, append_history=a.append_history, title=a.title,
                               strict_history=a.strict_history)
        index = b.build()
        size, files = page.folder_size(a.out)
    except FormatError as e:   # bad input (lexdyn's readers and the report's own checks)
        print(f"report: error: {e}", file=sys.stderr)
        return 2
    except ReportOutputError as e:
        print(f"report: error: {e}", file=sys.stderr)
        return 3
    except OSError as e:
        # A file that cannot be read or written (permissions, a full or read-only file system):
        # a run failure with the operating system's reason, not a traceback.
        where = e.filename if e.filename is not None else a.out
        print(f"report: error: {where}: {os_reason(e)}", file=sys.stderr)
        return 3
    except KeyboardInterrupt:
        print("report: interrupted by SIGINT", file=sys.stderr)
        return 130
    except Terminated:
        print("report: interrupted by SIGTERM", file=sys.stderr)
        return 143
    except Exception:  # noqa: BLE001 - an internal error is exit code 3 with its traceback
        traceback.print_exc()
        print("report: internal error", file=sys.stderr)
        return 3
    finally:
        if lock is not None:
            lock.release()
    for w in b.warnings:
        print(f"report: warning: {w}", file=sys.stderr)
    print(f"report: wrote {index} ({files} files, {size / 1e6:.2f} MB in {a.out}); "
          f"{len(results.runs)} runs, {len(b.replays)} replays, {len(sw)} sweeps"
          + (f", history {a.history}" + (" (appended)" if a.append_history else "") if a.history else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
