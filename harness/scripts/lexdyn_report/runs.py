"""The stored results a report is built from (docs/report.md, "Inputs").

RUNS/                      a nightly output (harness/scripts/nightly.sh) or full-runs.sh's
  <id>/summary.json        one directory per run (id CASE.METHOD, or CASE): summary.json,
  <id>/trace.csv           trace.csv (or trace.csv.partial) and log.txt
  <id>/log.txt
  runs.txt                 optional: ID CASE_FILE METHOD lines of the runs that were planned
  nightly.json             optional: the night (lexdyn.history.read_night): commit, date, machine
  compare/<case>.json      optional: `lexdyn-harness compare --json` of the case's comparisons
  ctest/junit.xml          optional: ctest's JUnit output (the golden checks among it)
"""
import math
import os
import re
import xml.etree.ElementTree as ET

from lexdyn import _json as lexdyn_json
from lexdyn import read_check_results, read_night, read_summary

from .common import ReportInputError, finite, json_constant, method_sort_key, non_finite_fields, read_yaml

# Paths stored relative to where a run was started (usually the repository root).
REPO_ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", ".."))

try:
    import yaml
except ImportError:  # pragma: no cover - Debian's python3-yaml is a dependency (install-deps.sh)
    yaml = None


def load_json(path):
    """The JSON document of PATH. NaN, Infinity and -Infinity (not JSON, but read by Python's json)
    are read as DamagedNumbers: shown as "not a number (damaged)", never taken as figures
    (common.non_finite_fields lists them)."""
    return lexdyn_json.load(path, "JSON", constant=json_constant)


def tail(path, lines=5):
    try:
        with open(path, errors="replace") as f:
            text = f.read().replace("\r", "\n")
    except OSError:
        return ""
    kept = [l for l in text.split("\n") if l.strip()]
    return "\n".join(kept[-lines:])


_TIME_RE = re.compile(r"\bt\s*=\s*([-+0-9.eE]+)\s*s\b")


def detail_time(detail):
    """The time a check's detail names ('... at t = 16.2 s ...'), or None."""
    m = _TIME_RE.search(detail or "")
    if not m:
        return None
    try:
        return float(m.group(1))
    except ValueError:
        return None


class Run:
    """One case x method run: its summary (None when the run wrote none), trace and log."""

    def __init__(self, run_id, directory, case=None, method=None, case_file=None):
        self.id = run_id
        self.dir = directory
        self.summary_path = os.path.join(directory, "summary.json")
        # lexdyn.RunSummary: the run's own verdict (exit code) and which checks decide.
        self.summary = read_summary(self.summary_path, constant=json_constant) if os.path.isfile(self.summary_path) else None
        # Figures stored as NaN or Infinity (a damaged file: the harness writes null): (field, text).
        self.damaged = non_finite_fields(self.summary)
        s = self.summary or {}
        self.case = s.get("case") or case or run_id.split(".")[0]
        self.method = s.get("method", method if method not in (None, "-") else "")
        self.case_file = s.get("case_file") or case_file
        self.header = s.get("trace_header", {})
        trace = os.path.join(directory, "trace.csv")
        partial = trace + ".partial"
        self.trace_path = trace if os.path.isfile(trace) else (partial if os.path.isfile(partial) else None)
        self.log_path = os.path.join(directory, "log.txt")

    @property
    def status(self):
        if self.summary is None:
            return "no_summary" if os.path.isdir(self.dir) else "not_run"
        return self.summary.get("status", "?")

    @property
    def checks(self):
        return (self.summary or {}).get("checks", [])

    @property
    def failed_checks(self):
        """The checks that decide and failed (a wall-clock check marked decides: false is
        reported only: info_checks)."""
        return self.summary.failed_checks if self.summary is not None else []

    @property
    def info_checks(self):
        """The checks reported only (decides: false: machine-dependent, wall-clock)."""
        return self.summary.info_checks if self.summary is not None else []

    @property
    def deciding_checks(self):
        return self.summary.deciding_checks if self.summary is not None else []

    @property
    def expected_failure(self):
        """The case's expected failure for this run (summary.json "expected_failure": status,
        checks, reason, met, mismatches), or None."""
        x = (self.summary or {}).get("expected_failure")
        # A run stopped before its expected failure shows (run --duration) is judged as any run.
        return x if x is None or x.get("reached", True) else None

    @property
    def failed_as_expected(self):
        x = self.expected_failure
        return bool(x and x.get("met"))

    @property
    def passed(self):
        """The run's own verdict: its exit code was 0 (completed with every check that decides
        passing, or failed exactly as its case expects)."""
        return self.summary is not None and self.summary.passed

    def log_tail(self, lines=5):
        return tail(self.log_path, lines)


def resolve(path, *bases):
    """PATH as given when it exists, else relative to each base in turn."""
    if not path:
        return None
    if os.path.isabs(path):
        return path if os.path.exists(path) else None
    for b in ("",) + bases:
        p = os.path.normpath(os.path.join(b, path)) if b else path
        if os.path.exists(p):
            return os.path.abspath(p)
    return None


class CaseInfo:
    """What the report needs from a case file: description, tasks (name -> type, frame),
    contacts (name -> frame, surface, sensor), the tasks whose errors the case compares."""

    def __init__(self, name, path):
        self.name = name
        self.path = path
        self.description = ""
        self.tasks = {}
        self.contacts = {}
        self.comparison_tasks = []
        self.robot = {}
        if not path or yaml is None:
            return
        doc = read_yaml(path, "case file")
        self.description = doc.get("description", "")
        self.robot = doc.get("robot", {}) or {}
        ctrl = doc.get("controller", {}) or {}
        for t in ctrl.get("tasks", []) or []:
            if isinstance(t, dict) and "name" in t:
                self.tasks[t["name"]] = t
        for c in ctrl.get("contacts", []) or []:
            if isinstance(c, dict) and "name" in c:
                self.contacts[c["name"]] = c
        for c in doc.get("comparisons", []) or []:
            for t in (c or {}).get("tasks", []) or []:
                if t not in self.comparison_tasks:
                    self.comparison_tasks.append(t)

    def key_tasks(self, summary_tasks, channel_names=()):
        """The tasks whose summed error is 'the error' of a run: those the case's comparisons
        name; else its position, orientation and com tasks; else (no case file) the tasks with
        a 3-D target channel."""
        present = set(summary_tasks or {})
        if self.comparison_tasks:
            return [t for t in self.comparison_tasks if t in present]
        typed = [n for n, t in self.tasks.items() if t.get("type") in ("position", "orientation", "com") and n in present]
        if typed or self.tasks:
            return typed
        return [n for n in sorted(present) if f"target.{n}.x" in channel_names]


def run_key_errors(run, case_info):
    """(tasks, final sum, mean sum) of the run's key tasks; sums None when a task's value is
    missing or infinite."""
    tasks = (run.summary or {}).get("tasks", {})
    names = case_info.key_tasks(tasks)
    if not names:
        return names, None, None
    final = [tasks[n].get("final_error") for n in names]
    mean = [tasks[n].get("mean_error") for n in names]
    fs = sum(final) if all(finite(v) for v in final) else None
    ms = sum(mean) if all(finite(v) for v in mean) else None
    return names, fs, ms


class Results:
    """Every stored result under a runs directory."""

    def __init__(self, runs_dir):
        if not os.path.isdir(runs_dir):
            raise ReportInputError(runs_dir, "expected a directory of runs (--runs), found none")
        self.dir = os.path.abspath(runs_dir)
        meta = os.path.join(self.dir, "nightly.json")
        self.meta = read_night(meta) if os.path.isfile(meta) else {}
        planned = self._planned()
        ids = list(planned)
        for name in sorted(os.listdir(self.dir)):
            d = os.path.join(self.dir, name)
            # Dot names are not runs: the folder's lock (.lexdyn.lock), a report's staging folder.
            if name.startswith("."):
                continue
            if name not in planned and os.path.isfile(os.path.join(d, "summary.json")):
                ids.append(name)
        self.runs = []
        for rid in ids:
            case_file, method = planned.get(rid, (None, None))
            self.runs.append(Run(rid, os.path.join(self.dir, rid), method=method, case_file=case_file))
        if not self.runs:
            raise ReportInputError(self.dir, "expected run directories holding summary.json (or a runs.txt), found none")
        self.runs.sort(key=lambda r: (r.case, method_sort_key(r.method), r.id))
        self.cases = {}
        for r in self.runs:
            self.cases.setdefault(r.case, []).append(r)
        self.case_info = {}
        for case, runs in self.cases.items():
            path = None
            for r in runs:
                path = resolve(r.case_file, self.dir, os.path.join(self.dir, r.id), REPO_ROOT)
                if path:
                    break
            self.case_info[case] = CaseInfo(case, path)
        self.comparisons = self._comparisons()
        self.ctest = CtestResults(os.path.join(self.dir, "ctest", "junit.xml"))

    def _planned(self):
        path = os.path.join(self.dir, "runs.txt")
        planned = {}
        if not os.path.isfile(path):
            return planned
        with open(path) as f:
            for lineno, line in enumerate(f, 1):
                parts = line.split()
                if not parts:
                    continue
                if len(parts) != 3:
                    raise ReportInputError(f"{path}:{lineno}", f"expected 'ID CASE_FILE METHOD', found '{line.strip()}'")
                planned[parts[0]] = (parts[1], parts[2])
        return planned

    def _comparisons(self):
        out = {}
        d = os.path.join(self.dir, "compare")
        if not os.path.isdir(d):
            return out
        for name in sorted(os.listdir(d)):
            if name.endswith(".json"):
                out[name[:-5]] = read_check_results(os.path.join(d, name), constant=json_constant).checks
        return out

    def run(self, run_id):
        for r in self.runs:
            if r.id == run_id:
                return r
        return None


class CtestResults:
    """ctest's JUnit file: every test's name, status and output; golden.<id> tests are the
    golden checks."""

    def __init__(self, path):
        self.path = path
        self.tests = []
        self.present = os.path.isfile(path)
        if not self.present:
            return
        try:
            root = ET.parse(path).getroot()
        except ET.ParseError as e:
            raise ReportInputError(path, f"expected ctest's JUnit XML, found a parse error ({e})")
        for tc in root.iter("testcase"):
            name = tc.get("name", "")
            status = tc.get("status", "")
            failed = tc.find("failure") is not None or status == "fail"
            skipped = tc.find("skipped") is not None or status in ("notrun", "disabled")
            out = tc.find("system-out")
            text = out.text if out is not None and out.text else ""
            try:
                seconds = float(tc.get("time", "nan"))
            except ValueError:
                seconds = math.nan
            self.tests.append({"name": name, "failed": failed, "skipped": skipped, "output": text, "time_s": seconds})

    @property
    def goldens(self):
        out = []
        for t in self.tests:
            if not t["name"].startswith("golden."):
                continue
            gid = t["name"][len("golden."):]
            msg = ""
            for line in t["output"].splitlines():
                s = line.strip()
                if s.startswith(("FAIL ", "MISSING ")) and gid in s:
                    msg = s
                    break
            if t["failed"] and not msg:
                lines = [l for l in t["output"].splitlines() if l.strip()]
                msg = lines[-1].strip() if lines else "failed (no output)"
            out.append({"id": gid, "failed": t["failed"], "message": msg})
        return out

    @property
    def failed_tests(self):
        return [t for t in self.tests if t["failed"]]
