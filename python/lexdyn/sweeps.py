"""A sweep's output directory (`lexdyn-harness sweep run FILE --out DIR`; docs/sweeps.md):
DIR/summary.json (format lexdyn-sweep-summary/1) and DIR/results.jsonl, one record per point
with the run of every method under `runs`.

    sw = lexdyn.read_sweep("out/sweeps/pm")
    sw.summary["checks"]               # pass rates and worst margins per check and method
    sw.records                         # the point records of results.jsonl
    sw.status_counts()                 # {method: {status: runs}}
    df = sw.dataframe()                # one row per point x method, the parameters as columns
"""
import math
import os

from . import _json
from .errors import FormatError

SWEEP_SUMMARY_FORMAT = "lexdyn-sweep-summary/1"
# A point record's format (results.jsonl's lines, OUT/points/<i>.json) and its runs' (C++:
# records::kSweepPointFormat, kSweepRunFormat).
SWEEP_POINT_FORMAT = "lexdyn-sweep-point/1"
SWEEP_RUN_FORMAT = "lexdyn-sweep-run/1"
SUMMARY_KEYS = ["name", "base_case", "methods", "points", "completed", "checks"]


def check_sweep_summary(s, path):
    if not isinstance(s, dict):
        raise FormatError(path, f"expected a sweep summary (a JSON object), found {_json.kind(s)}")
    if s.get("format") != SWEEP_SUMMARY_FORMAT:
        found = repr(s["format"]) if "format" in s else "none"
        raise FormatError(path, f"expected '{SWEEP_SUMMARY_FORMAT}', found {found}", field="format")
    for key in SUMMARY_KEYS:
        if key not in s:
            raise FormatError(path, "expected this key, found none", field=key)
    if not isinstance(s["methods"], list) or not all(isinstance(m, str) for m in s["methods"]):
        raise FormatError(path, f"expected a list of method names, found {_json.kind(s['methods'])}", field="methods")
    for group, keys in (("checks", ("check", "method", "runs", "passed", "pass_rate")), ("maps", ("x", "y", "property")),
                        ("comparisons", ("name", "better", "worse")), ("failures", ("check", "method")),
                        ("parameters", ("name",))):
        items = s.get(group, [])
        if not isinstance(items, list):
            raise FormatError(path, f"expected a list, found {_json.kind(items)}", field=group)
        for i, c in enumerate(items):
            if not isinstance(c, dict):
                raise FormatError(path, f"expected an object, found {_json.kind(c)}", field=f"{group}[{i}]")
            for key in keys:
                if key not in c:
                    raise FormatError(path, "expected this key, found none", field=f"{group}[{i}].{key}")


def read_sweep_summary(path, constant=None):
    """DIR/summary.json of a sweep (a dict), checked: its format, the keys every summary has."""
    path = os.fspath(path)
    s = _json.load(path, "a sweep summary (JSON)", constant=constant)
    check_sweep_summary(s, path)
    return s


def check_point_record(r, path, line, methods=None):
    """Raises FormatError unless R is a point record of results.jsonl (with a run of each of
    METHODS when given)."""
    def need(cond, field, what):
        if not cond:
            raise FormatError(path, what, line=line, field=field)
    need(isinstance(r, dict), None, f"expected a point record (a JSON object), found {_json.kind(r)}")
    need(r.get("format") == SWEEP_POINT_FORMAT, "format",
         f"expected '{SWEEP_POINT_FORMAT}', found {repr(r['format']) if 'format' in r else 'none (written by an older build)'}")
    p = r.get("point")
    need(isinstance(p, int) and not isinstance(p, bool), "point",
         f"expected the point's index (an integer), found {_json.kind(p) if 'point' in r else 'none'}")
    need(isinstance(r.get("values"), dict), "values",
         f"expected the parameters' values (an object), found {_json.kind(r.get('values')) if 'values' in r else 'none'}")
    runs = r.get("runs")
    need(isinstance(runs, dict), "runs",
         f"expected the runs by method (an object), found {_json.kind(runs) if 'runs' in r else 'none'}")
    for m in methods or []:
        need(m in runs, f"runs.{m}", "expected the run of this method, found none")
    for m, run in runs.items():
        need(isinstance(run, dict), f"runs.{m}", f"expected a run (an object), found {_json.kind(run)}")
        need(run.get("format") == SWEEP_RUN_FORMAT, f"runs.{m}.format",
             f"expected '{SWEEP_RUN_FORMAT}', found {repr(run['format']) if 'format' in run else 'none'}")
        need(isinstance(run.get("status"), str), f"runs.{m}.status",
             f"expected the run's status (a string), found {_json.kind(run.get('status')) if 'status' in run else 'none'}")
        checks = run.get("checks", [])
        need(isinstance(checks, list), f"runs.{m}.checks", f"expected a list of checks, found {_json.kind(checks)}")
        for i, c in enumerate(checks):
            need(isinstance(c, dict) and isinstance(c.get("name"), str) and isinstance(c.get("passed"), bool),
                 f"runs.{m}.checks[{i}]", "expected a check with its name and passed (true / false)")
        for key in ("statistics", "final_errors"):
            need(isinstance(run.get(key, {}), dict), f"runs.{m}.{key}", f"expected an object, found {_json.kind(run.get(key))}")


def read_sweep_results(path, methods=None, constant=None):
    """The point records of a sweep's results.jsonl, each checked (with a run of each of METHODS
    when given); an error names the file, the line and the field."""
    path = os.fspath(path)
    out = []
    for lineno, r in _json.load_lines(path, "one JSON point record per line", constant=constant):
        check_point_record(r, path, lineno, methods)
        out.append(r)
    return out


def _number(text):
    """TEXT as a float when it reads as a finite or infinite number, else None."""
    if isinstance(text, bool):
        return None
    if isinstance(text, (int, float)):
        return float(text)
    try:
        return float(text)
    except (TypeError, ValueError):
        return None


class Sweep:
    """A sweep's output directory as read: `dir`, `summary`, `records` (results.jsonl; empty
    when the directory has none yet), `name`, `methods`, `parameters` (names, in the sweep's
    order)."""

    def __init__(self, directory, constant=None):
        self.dir = os.path.abspath(os.fspath(directory))
        self.summary = read_sweep_summary(os.path.join(self.dir, "summary.json"), constant=constant)
        self.name = str(self.summary["name"])
        self.methods = list(self.summary["methods"])
        results = os.path.join(self.dir, "results.jsonl")
        self.records = read_sweep_results(results, self.methods, constant=constant) if os.path.isfile(results) else []
        names = [p["name"] for p in self.summary.get("parameters", [])]
        for r in self.records:
            for k in r["values"]:
                if k not in names:
                    names.append(k)
        self.parameters = names

    def path(self, rel):
        """A file the summary names, relative to the sweep directory (None when absent)."""
        if not rel:
            return None
        p = os.path.normpath(os.path.join(self.dir, rel))
        return p if os.path.isfile(p) else None

    def status_counts(self):
        """{method: {status: number of runs}} over results.jsonl."""
        out = {}
        for r in self.records:
            for m, run in r["runs"].items():
                per = out.setdefault(m, {})
                per[run["status"]] = per.get(run["status"], 0) + 1
        return out

    def rows(self):
        """One dict per point x method: point, method, each parameter's value (a number where
        every value of the parameter reads as one), status, exit_code, wall_s, simulated_s,
        peak_iterations, message, failed (the property checks that failed), check.NAME.passed /
        .value / .margin (a run that stopped early fails each of the sweep's property checks, value
        and margin NaN, as summary.json counts it), statistic.NAME, final_error.TASK."""
        numeric = {p: all(_number(r["values"].get(p)) is not None for r in self.records if p in r["values"])
                   for p in self.parameters}
        # The sweep's property checks of each method (summary.json's, as it counts them): a run
        # that stopped early has none of them, and fails each, as the summary's pass rates say.
        properties = {}
        for c in self.summary.get("checks", []):
            if isinstance(c, dict) and c.get("check") != "run_completed":
                properties.setdefault(c.get("method"), []).append(c.get("check"))
        out = []
        for r in self.records:
            for m in self.methods + sorted(set(r["runs"]) - set(self.methods)):
                run = r["runs"].get(m)
                if run is None:
                    continue
                row = {"point": r["point"], "method": m}
                for p in self.parameters:
                    v = r["values"].get(p)
                    row[p] = _number(v) if numeric[p] and v is not None else v
                for key in ("status", "exit_code", "wall_s", "simulated_s", "peak_iterations", "message"):
                    row[key] = run.get(key)
                row["failed"] = [f.split(":", 1)[1] for f in r.get("failures", []) if f.startswith(m + ":")]
                for n in properties.get(m, []):
                    row[f"check.{n}.passed"] = False
                    row[f"check.{n}.value"] = row[f"check.{n}.margin"] = math.nan
                for c in run.get("checks", []):
                    n = c["name"]
                    row[f"check.{n}.passed"] = c["passed"]
                    for key in ("value", "margin"):
                        v = c.get(key)
                        row[f"check.{n}.{key}"] = math.nan if v is None else v
                for n, v in run.get("statistics", {}).items():
                    row[f"statistic.{n}"] = math.nan if v is None else v
                for n, v in run.get("final_errors", {}).items():
                    row[f"final_error.{n}"] = math.nan if v is None else v
                out.append(row)
        return out

    def dataframe(self):
        """rows() as a pandas DataFrame (needs pandas)."""
        import pandas as pd
        rows = self.rows()
        fixed = ["point", "method"] + self.parameters + ["status", "exit_code", "wall_s", "simulated_s", "peak_iterations",
                                                          "message", "failed"]
        extra = []
        for row in rows:
            for k in row:
                if k not in fixed and k not in extra:
                    extra.append(k)
        return pd.DataFrame(rows, columns=fixed + extra)


def read_sweep(directory, constant=None):
    """The sweep output directory DIRECTORY (summary.json, results.jsonl) as a Sweep."""
    return Sweep(directory, constant=constant)


def sweep_dataframe(directory):
    """One row per point x method of the sweep in DIRECTORY, the parameters as columns."""
    return read_sweep(directory).dataframe()
