"""Case runs from Python through the compiled module lexdyn._core (docs/python.md, "Bindings"):
`run_case` does what `lexdyn-harness run` does, in this process, and reads back what the run wrote.

    run = lexdyn.run_case("cases/pointmass-damping.yaml", method="gn", duration=2,
                          overrides={"controller.params.damping": 0.1})
    run.summary.status, run.summary.passed, run.trace["q.x"]
"""
import math
import numbers
import os
import shutil
import tempfile
import weakref

from .summary import RunSummary, read_summary
from .trace import read_trace


class CaseRun:
    """What run_case returns: `summary` (summary.json as a RunSummary: status, exit_code, checks,
    passed ...), `trace` (trace.csv as a Trace, read on first access: a run costs what the
    command line's does until its trace is wanted) and `out_dir` (the run's directory; None for a
    temporary one, which is deleted once the trace has been read, or when the CaseRun goes away).
    Unpacks as (summary, trace, out_dir)."""

    def __init__(self, summary, trace_path, out_dir=None, temporary_dir=None):
        self.summary = summary
        self.out_dir = out_dir
        self._trace_path = trace_path
        self._trace = None
        self._cleanup = weakref.finalize(self, shutil.rmtree, temporary_dir, True) if temporary_dir else None

    @property
    def trace(self):
        if self._trace is None:
            self._trace = read_trace(self._trace_path)
            if self._cleanup is not None:
                self._cleanup()   # the temporary directory, once the trace is in memory
        return self._trace

    @property
    def exit_code(self):
        """The exit code `lexdyn-harness run` gives this run (docs/architecture.md)."""
        return self.summary["exit_code"]

    def __iter__(self):
        return iter((self.summary, self.trace, self.out_dir))

    def __repr__(self):
        return f"CaseRun(status={self.summary.status!r}, exit_code={self.exit_code}, out_dir={self.out_dir!r})"


def _yaml_value(value):
    """An override's value as YAML text: a str as it is (YAML, as `--set PATH=VALUE` takes it),
    a number in its shortest round-trip form (2.0 as 2), True/False as true/false, None as null,
    a list or dict as a YAML flow collection of the same."""
    if isinstance(value, str):
        return value
    if value is None:
        return "null"
    if isinstance(value, bool) or type(value).__name__ == "bool_":  # numpy's too
        return "true" if value else "false"
    if isinstance(value, numbers.Integral):  # numpy's integers too
        return str(int(value))
    if isinstance(value, numbers.Real):  # numpy's floats too
        value = float(value)
        if math.isnan(value):
            return ".nan"
        if math.isinf(value):
            return ".inf" if value > 0 else "-.inf"
        text = repr(value)
        return text[:-2] if text.endswith(".0") else text
    if hasattr(value, "tolist") and not isinstance(value, (list, tuple, dict)):  # a numpy array
        return _yaml_value(value.tolist())
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_yaml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k}: {_yaml_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(f"override value: expected a str, number, bool, None, list or dict, found {type(value).__name__}")


def run_case(case_path, method=None, overrides=None, duration=None, out_dir=None, *, wall_clock_checks=False,
             progress=False, dump_problems=None, dump_window=None):
    """Runs a case file as `lexdyn-harness run CASE_PATH --out OUT_DIR` does, in this process (the
    GIL released while it runs), and returns a CaseRun (summary, trace, out_dir).

    method: a lexdyn method (bfgs | ah | gn | wls) overriding the case's (`--method`).
    overrides: {key path: value} applied in order, as `--set PATH=VALUE` (docs/cases.md,
        "Overrides"); a str value is YAML text as given, other values are written as YAML.
    duration: simulate at most this long, in s (`--duration`: the override stop_at_s, first).
    out_dir: where trace.csv, summary.json and case.yaml are written. When None the run writes
        into a temporary directory that is deleted once the trace has been read (on the first
        access to `.trace`) or the returned CaseRun goes away (the Trace's and RunSummary's `path`
        then name files that no longer exist).
    wall_clock_checks: tick_time checks decide pass/fail (`--wall-clock-checks`).
    progress: progress lines on stderr (off by default, as `--quiet`).
    dump_problems, dump_window: `--dump-problems DIR` and `--dump-window FROM:TO` as (from, to)
        in s: each controller tick's solver problem as DIR/tick_NNNNNN.json (for load_problem).

    Bad input (the case file, an override, the method) raises lexdyn.InputError (a ValueError)
    and runs nothing; a run that fails or whose checks fail returns normally: see
    summary.status, summary.passed and exit_code. Ctrl-C stops the run after its current tick
    (the trace and the summary are written, status interrupted) and then raises
    KeyboardInterrupt.
    """
    from . import _core

    ov = []
    if duration is not None:
        text = _yaml_value(duration)
        ov.append(("stop_at_s", text, "duration=" + text))
    for path, value in (overrides or {}).items():
        text = _yaml_value(value)
        ov.append((str(path), text, f"overrides[{path!r}]={text}"))
    dump_from, dump_to = 0.0, 1e300
    if dump_window is not None:
        if dump_problems is None:
            raise ValueError("dump_window: needs dump_problems (a directory)")
        dump_from, dump_to = (float(v) for v in dump_window)
    temporary = out_dir is None
    run_dir = tempfile.mkdtemp(prefix="lexdyn-run-") if temporary else os.fspath(out_dir)
    try:
        written = _core._run_case(os.fspath(case_path), method or "", ov, run_dir, bool(progress), bool(wall_clock_checks),
                                  os.fspath(dump_problems) if dump_problems is not None else "", dump_from, dump_to)
        summary = read_summary(written["summary_path"])
    except BaseException:
        if temporary:
            shutil.rmtree(run_dir, ignore_errors=True)
        raise
    return CaseRun(summary, written["trace_path"], None if temporary else run_dir, run_dir if temporary else None)
