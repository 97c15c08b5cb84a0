"""Sweep outputs (docs/report.md, "Sweeps"): SWEEP_OUT/summary.json
(format lexdyn-sweep-summary/1) and SWEEP_OUT/results.jsonl, one record per point. --sweeps
names one such directory or a directory whose subdirectories are."""
import json
import os

from .common import ReportInputError, json_constant
from .runs import load_json

FORMAT = "lexdyn-sweep-summary/1"
REQUIRED = ["name", "base_case", "methods", "points", "completed", "checks"]


class Sweep:
    def __init__(self, directory):
        self.dir = os.path.abspath(directory)
        path = os.path.join(self.dir, "summary.json")
        s = load_json(path)
        if not isinstance(s, dict) or s.get("format") != FORMAT:
            found = s.get("format") if isinstance(s, dict) else type(s).__name__
            raise ReportInputError(f"{path}: format", f"expected '{FORMAT}', found {found!r}")
        for key in REQUIRED:
            if key not in s:
                raise ReportInputError(f"{path}: {key}", "expected this key, found none")
        for i, c in enumerate(s.get("checks", [])):
            for key in ("check", "method", "runs", "passed", "pass_rate"):
                if key not in c:
                    raise ReportInputError(f"{path}: checks[{i}].{key}", "expected this key, found none")
        for i, m in enumerate(s.get("maps", [])):
            for key in ("x", "y", "property"):
                if key not in m:
                    raise ReportInputError(f"{path}: maps[{i}].{key}", "expected this key, found none")
        self.summary = s
        self.name = str(s["name"])
        self.records = []
        results = os.path.join(self.dir, "results.jsonl")
        if os.path.isfile(results):
            with open(results) as f:
                for lineno, line in enumerate(f, 1):
                    if not line.strip():
                        continue
                    try:
                        self.records.append(json.loads(line, parse_constant=json_constant))
                    except json.JSONDecodeError as e:
                        raise ReportInputError(f"{results}:{lineno}", f"expected one JSON record per line ({e.msg})")

    def path(self, rel):
        """A file the summary names, relative to the sweep directory (None when absent)."""
        if not rel:
            return None
        p = os.path.normpath(os.path.join(self.dir, rel))
        return p if os.path.isfile(p) else None

    def method_status_counts(self):
        """{method: {status: count}} over results.jsonl (records with a 'methods' mapping)."""
        out = {}
        for r in self.records:
            methods = r.get("methods") if isinstance(r, dict) else None
            if not isinstance(methods, dict):
                continue
            for m, v in methods.items():
                st = v.get("status", "?") if isinstance(v, dict) else "?"
                out.setdefault(m, {}).setdefault(st, 0)
                out[m][st] += 1
        return out


def load_sweeps(path):
    if not path:
        return []
    if not os.path.isdir(path):
        raise ReportInputError(path, "expected a sweep output directory (--sweeps), found none")
    if os.path.isfile(os.path.join(path, "summary.json")):
        return [Sweep(path)]
    out = []
    for name in sorted(os.listdir(path)):
        d = os.path.join(path, name)
        if not name.startswith(".") and os.path.isfile(os.path.join(d, "summary.json")):
            out.append(Sweep(d))
    return out
