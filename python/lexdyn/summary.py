"""A run's summary (`DIR/summary.json` of `lexdyn-harness run`; docs/simulator.md and
docs/cases.md, "summary.json").

    s = lexdyn.read_summary("out/run/summary.json")
    s.status, s.exit_code, s.passed     # the run's own verdict: exit code 0
    s.failed_checks                     # the checks that decide and failed
    s.info_checks                       # machine-dependent checks (decides: false), reported only

A check marked `"decides": false` (a wall-clock `tick_time` check without
`--wall-clock-checks`) is reported, never part of the verdict.
"""
import warnings

from . import _json
from .errors import FormatError

# The format key of summary.json (C++: kRunSummaryFormat). Files written before the key existed
# have none: they are read with a warning saying so.
SUMMARY_FORMAT = "lexdyn-run-summary/1"
SUMMARY_FORMATS = (SUMMARY_FORMAT,)
# The format key of `lexdyn-harness check --json` / `compare --json` (C++: kCheckResultsFormat).
CHECK_RESULTS_FORMAT = "lexdyn-check-results/1"


class Check(dict):
    """One check of a summary: name, type, passed, value, limit, margin, unit, detail, and for a
    wall-clock check machine_dependent and decides."""

    @property
    def name(self):
        return self.get("name")

    @property
    def passed(self):
        return bool(self.get("passed"))

    @property
    def decides(self):
        """False for a check that is reported only (machine-dependent)."""
        return self.get("decides", True) is not False


class _Checks:
    """The checks of a record holding a "checks" list of Checks: those that decide, failed or are
    reported only."""

    @property
    def checks(self):
        return self.get("checks", [])

    @property
    def deciding_checks(self):
        return [c for c in self.checks if c.decides]

    @property
    def failed_checks(self):
        """The checks that decide and failed."""
        return [c for c in self.checks if c.decides and not c.passed]

    @property
    def info_checks(self):
        """The checks that are reported only (decides: false)."""
        return [c for c in self.checks if not c.decides]


class RunSummary(_Checks, dict):
    """summary.json as read (a dict), with `path` and the run's verdict."""

    path = None

    @property
    def status(self):
        return self["status"]

    @property
    def exit_code(self):
        """The run's exit code as the harness gave it (None in a summary without one)."""
        return self.get("exit_code")

    @property
    def expected_failure(self):
        return self.get("expected_failure")

    @property
    def passed(self):
        """The run's verdict: its exit code is 0 (it completed and every check that decides
        passed, or it failed exactly as its case expects). Without an exit code: completed and
        every deciding check passed."""
        if isinstance(self.get("exit_code"), int) and not isinstance(self.get("exit_code"), bool):
            return self["exit_code"] == 0
        return self.status == "completed" and not self.failed_checks


def _check_checks(doc, path):
    checks = doc.get("checks", [])
    if not isinstance(checks, list):
        raise FormatError(path, f"expected a list of checks, found {_json.kind(checks)}", field="checks")
    for i, c in enumerate(checks):
        if not isinstance(c, dict):
            raise FormatError(path, f"expected a check (an object), found {_json.kind(c)}", field=f"checks[{i}]")
        if not isinstance(c.get("name"), str):
            raise FormatError(path, f"expected the check's name (a string), found {_json.kind(c.get('name')) if 'name' in c else 'none'}",
                              field=f"checks[{i}].name")
        for key in ("passed", "decides", "machine_dependent"):
            if (key == "passed" or key in c) and not isinstance(c.get(key), bool):
                raise FormatError(path, f"expected true or false, found {_json.kind(c.get(key)) if key in c else 'none'}",
                                  field=f"checks[{i}].{key}")


def check_summary(doc, path):
    """Raises FormatError (naming the field) unless DOC is a run summary this reader knows."""
    if not isinstance(doc, dict):
        raise FormatError(path, f"expected a run summary (a JSON object), found {_json.kind(doc)}")
    if "format" not in doc:
        warnings.warn(f"{path}: summary.json without a format key (written by a build before {SUMMARY_FORMAT}): read as that "
                      "format", stacklevel=3)
    elif doc["format"] not in SUMMARY_FORMATS:
        raise FormatError(path, f"expected format {SUMMARY_FORMAT!r}, found {doc['format']!r}", field="format")
    st = doc.get("status")
    if not isinstance(st, str) or not st:
        raise FormatError(path, f"expected the run's status (a string), found {_json.kind(st) if 'status' in doc else 'none'}",
                          field="status")
    if "exit_code" in doc and (not isinstance(doc["exit_code"], int) or isinstance(doc["exit_code"], bool)):
        raise FormatError(path, f"expected an integer, found {_json.kind(doc['exit_code'])}", field="exit_code")
    _check_checks(doc, path)
    for key in ("tasks", "solver", "controller", "timing_us", "integrator", "trace_header", "statistics"):
        if key in doc and not isinstance(doc[key], dict):
            raise FormatError(path, f"expected an object, found {_json.kind(doc[key])}", field=key)


def as_summary(doc, path):
    """DOC (a checked summary document) as a RunSummary, its checks as Checks."""
    s = RunSummary(doc)
    s.path = str(path)
    if "checks" in s:
        s["checks"] = [Check(c) for c in s["checks"]]
    return s


def read_summary(path, constant=None):
    """The run summary PATH (a summary.json, or a run directory holding one) as a RunSummary.
    A figure stored as NaN or Infinity (the harness writes null) is an error naming the field,
    unless CONSTANT (json's parse_constant) says what to make of it."""
    import os
    path = os.fspath(path)
    if os.path.isdir(path):
        path = os.path.join(path, "summary.json")
    doc = _json.load(path, "a run summary (JSON)", constant=constant)
    check_summary(doc, path)
    return as_summary(doc, path)


class CheckResults(_Checks, dict):
    """`lexdyn-harness check --json` / `compare --json` as read: `checks` (Checks) and
    `all_checks_passed`."""

    path = None

    @property
    def passed(self):
        """Every check that decides passed (`all_checks_passed`; an expected failure the case
        declares is judged by `lexdyn-harness check`'s exit code, not here)."""
        return bool(self.get("all_checks_passed"))


def read_check_results(path, constant=None):
    """The output of `lexdyn-harness check --json` or `compare --json` saved in PATH. Another
    format is refused (FormatError naming it); a file without the key (written before it existed)
    is read with a warning."""
    import os
    path = os.fspath(path)
    doc = _json.load(path, "check results (JSON)", constant=constant)
    if not isinstance(doc, dict):
        raise FormatError(path, f"expected check results (a JSON object), found {_json.kind(doc)}")
    if "format" not in doc:
        warnings.warn(f"{path}: check results without a format key (written by a build before {CHECK_RESULTS_FORMAT}): read as that "
                      "format", stacklevel=2)
    elif doc["format"] != CHECK_RESULTS_FORMAT:
        raise FormatError(path, f"expected format {CHECK_RESULTS_FORMAT!r}, found {doc['format']!r}", field="format")
    if not isinstance(doc.get("checks"), list):
        raise FormatError(path, f"expected a list of checks, found {_json.kind(doc.get('checks')) if 'checks' in doc else 'none'}",
                          field="checks")
    _check_checks(doc, path)
    if not isinstance(doc.get("all_checks_passed"), bool):
        raise FormatError(path, "expected true or false", field="all_checks_passed")
    r = CheckResults(doc)
    r.path = path
    r["checks"] = [Check(c) for c in doc["checks"]]
    return r
