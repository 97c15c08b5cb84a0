"""The nightly job's records (docs/report.md, docs/file-formats.md "Nightly records"), defined
here once for the job (nightly.sh), the report and the user.

The night (OUT/nightly.json, written by nightly.sh through write_night, read by the report
through read_night):

  {"format": "lexdyn-night/1", "night": "DATE COMMIT12", "commit": SHA, "date": ISO-8601 UTC,
   "machine": {"host", "cpu", "cores", "os"}, "jobs": N, "duration_s": S or null}

The history of nights (a JSON Lines file; "History and trend"), one record per night:

  {"format": "lexdyn-nightly-history/1", "night": ID, "commit": SHA, "date": ISO-8601 UTC,
   "machine": {...}, "runs": {RUN_ID: {"case", "method", "status", "error_tasks",
   "final_error", "mean_error", "peak_iterations", "tick_p50_us", "tick_p99_us",
   "realtime_factor", "failed_checks": [names], "checks"}},
   "goldens": {"total", "failed": [ids]}, "tests": {"total", "failed": [names]},
   "sweeps": {NAME: {"CHECK/METHOD": pass_rate}}}

    h = lexdyn.read_history("out/nightly/history.jsonl")            # strict: the first problem raises
    h = lexdyn.read_history(path, strict=False)                      # skips bad lines, h.warnings

The records are in the order of their nights' dates (`date`, ties by `night`). strict=False: a
line that is not such a record (cut, garbage, another format version, a key of the wrong type)
is skipped with a warning (`skipped` keeps its bytes), a figure that is not a finite number is
kept with a warning; strict=True refuses both (FormatError naming the file, the line and the
field).
"""
import datetime
import json
import math
import os
import platform
import socket

from . import _json
from .errors import FormatError

HISTORY_FORMAT = "lexdyn-nightly-history/1"
NIGHT_FORMAT = "lexdyn-night/1"
# nightly.json's format before it had a name of its own (the same keys).
_NIGHT_FORMAT_BEFORE = "lexdyn-nightly/1"
# The figures of a run's record: null or a finite number.
RUN_FIGURES = ["final_error", "mean_error", "peak_iterations", "tick_p50_us", "tick_p99_us", "realtime_factor", "checks"]
DATE_EXAMPLE = "2026-11-24T20:24:35Z"


def parse_date(text):
    """An ISO-8601 time (a string) as an aware UTC datetime (no zone: UTC), or None."""
    if not isinstance(text, str):
        return None
    try:
        d = datetime.datetime.fromisoformat(text.strip())
    except ValueError:
        return None
    if d.tzinfo is None:
        d = d.replace(tzinfo=datetime.timezone.utc)
    return d.astimezone(datetime.timezone.utc)


_EARLIEST = datetime.datetime.min.replace(tzinfo=datetime.timezone.utc)


def night_key(rec):
    """The order of the nights: the night's date, then its id."""
    return (parse_date(rec.get("date")) or _EARLIEST, str(rec.get("night")))


class Record(dict):
    """A record of the history file: `where` (FILE:LINE) and `line`, its bytes as read."""
    where = None
    line = None


def _finite(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _damaged_text(v):
    if isinstance(v, float) and hasattr(v, "text"):
        return v.text
    text = json.dumps(v)
    return text if len(text) <= 40 else text[:37] + "..."


def _figure_problem(v):
    """None when V is a figure (null or a finite number), else how it looks."""
    if v is None or _finite(v):
        return None
    return _damaged_text(v)


def check_record(rec):
    """((field, what) of the first problem that makes REC no record of this format, or None;
    [(field, text)] of its figures that are not finite numbers)."""
    kind = _json.kind
    if not isinstance(rec, dict):
        return ("", f"expected a record (a JSON object), found {kind(rec)}"), []
    fmt = rec.get("format")
    if fmt != HISTORY_FORMAT:
        return ("format", f"expected '{HISTORY_FORMAT}', found " + (repr(fmt) if fmt is not None else "none")), []
    night = rec.get("night")
    if not isinstance(night, str) or not night:
        return ("night", f"expected the night's id (a string), found {kind(night) if 'night' in rec else 'none'}"), []
    if parse_date(rec.get("date")) is None:
        d = rec.get("date")
        return ("date", f"expected an ISO-8601 time ({DATE_EXAMPLE}), found "
                + (repr(d) if isinstance(d, str) else kind(d) if "date" in rec else "none")), []
    if "commit" in rec and not isinstance(rec["commit"], str):
        return ("commit", f"expected a string, found {kind(rec['commit'])}"), []
    if "machine" in rec and not isinstance(rec["machine"], dict):
        return ("machine", f"expected an object, found {kind(rec['machine'])}"), []
    runs = rec.get("runs")
    if not isinstance(runs, dict):
        return ("runs", f"expected an object of runs by id, found {kind(runs) if 'runs' in rec else 'none'}"), []
    damaged = []
    for rid, rr in runs.items():
        where = f"runs.{rid}"
        if not isinstance(rr, dict):
            return (where, f"expected an object of the run's figures, found {kind(rr)}"), []
        for key in ("case", "method", "status"):
            if rr.get(key) is not None and not isinstance(rr[key], str):
                return (f"{where}.{key}", f"expected a string, found {kind(rr[key])}"), []
        for key in ("failed_checks", "error_tasks"):
            v = rr.get(key)
            if v is not None and not (isinstance(v, list) and all(isinstance(x, str) for x in v)):
                return (f"{where}.{key}", f"expected a list of names, found {kind(v)}"
                        + (" holding something else" if isinstance(v, list) else "")), []
        for key in RUN_FIGURES:
            bad = _figure_problem(rr.get(key))
            if bad is not None:
                damaged.append((f"{where}.{key}", bad))
    for group in ("goldens", "tests"):
        if group not in rec:
            continue
        g = rec[group]
        if not isinstance(g, dict):
            return (group, f"expected an object (total, failed), found {kind(g)}"), []
        f = g.get("failed")
        if not (isinstance(f, list) and all(isinstance(x, str) for x in f)):
            return (f"{group}.failed", f"expected a list of names, found {kind(f) if 'failed' in g else 'none'}"), []
        bad = _figure_problem(g.get("total"))
        if bad is not None:
            damaged.append((f"{group}.total", bad))
    if "sweeps" in rec:
        sw = rec["sweeps"]
        if not isinstance(sw, dict) or not all(isinstance(v, dict) for v in sw.values()):
            return ("sweeps", f"expected an object of pass rates by sweep, found {kind(sw)}"), []
        for name, rates in sw.items():
            for k, v in rates.items():
                bad = _figure_problem(v)
                if bad is not None:
                    damaged.append((f"sweeps.{name}.{k}", bad))
    return None, damaged


class History:
    """The history file PATH as read: `records` in date order (ties by night id), `skipped` (the
    lines that are no record, as read) and `warnings` (one per problem: FILE:LINE: FIELD: what).
    strict=True: FormatError at the first problem instead. No file: no record. CONSTANT: json's
    parse_constant for NaN and Infinity (default: a float remembering its text)."""

    def __init__(self, path, strict=False, constant=None):
        self.path = path
        self.records = []
        self.skipped = []
        self.warnings = []
        self.constant = constant or _json.NonFiniteNumber
        if not path or not os.path.lexists(path):
            return
        if os.path.isdir(path):
            raise FormatError(path, "expected a history file (JSON Lines), found a folder")
        with open(path, "rb") as f:
            data = f.read()
        lines = data.split(b"\n")
        cut = lines[-1] != b""          # the last line has no end
        if not cut:
            lines.pop()
        for lineno, raw in enumerate(lines, 1):
            if not raw.strip():
                continue
            rec, damaged = self._parse(raw, lineno == len(lines) and cut)
            if not isinstance(rec, Record):
                field, what = rec
                if strict:
                    raise FormatError(path, what, line=lineno, field=field or None)
                self.skipped.append(raw)
                self.warnings.append(f"{path}:{lineno}: {field + ': ' if field else ''}{what}: the line is skipped")
                continue
            for field, text in damaged:
                if strict:
                    raise FormatError(path, f"expected a finite number, found {text}", line=lineno, field=field)
                self.warnings.append(f"{path}:{lineno}: {field}: expected a finite number, found {text}: left out of the trend")
            rec.where = f"{path}:{lineno}"
            rec.line = raw
            self.records.append(rec)
        self.records.sort(key=night_key)

    def _parse(self, raw, last_and_cut):
        """(Record, damaged) or ((field, what), [])."""
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError as e:
            return ("", f"expected one JSON record per line (UTF-8 text), found binary data (byte {e.start + 1})"), []
        try:
            doc = json.loads(text, parse_constant=self.constant)
        except json.JSONDecodeError as e:
            what = f"expected one JSON record per line, found a syntax error ({_json.syntax_error(e)})"
            if last_and_cut:
                what += "; the file's last line has no end: cut"
            return ("", what), []
        problem, damaged = check_record(doc)
        if problem is not None:
            return problem, []
        return Record(doc), damaged


def read_history(path, strict=True, constant=None):
    """The History of PATH (see History); strict by default, and then a missing file is an error
    (History itself reads a missing file as no night yet: the nightly job's first)."""
    path = os.fspath(path) if path else path
    if strict and path and not os.path.lexists(path):
        raise FormatError(path, "expected a history file (JSON Lines), found no such file")
    return History(path, strict=strict, constant=constant)


# ------------------------------------------------------------------ the night (nightly.json)
def _cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return ""


def night_info(commit, jobs=None, duration_s=None, now=None):
    """A night's record (nightly.json) for COMMIT on this machine, dated NOW (default: now, UTC)."""
    now = now or datetime.datetime.now(datetime.timezone.utc)
    date = now.astimezone(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    return {"format": NIGHT_FORMAT, "night": date + " " + str(commit)[:12], "commit": str(commit), "date": date,
            "machine": {"host": socket.gethostname(), "cpu": _cpu_model(), "cores": os.cpu_count(), "os": platform.platform()},
            "jobs": None if jobs is None else int(jobs), "duration_s": None if duration_s in (None, "") else float(duration_s)}


def write_night(path, info):
    """Writes the night's record INFO (night_info) into PATH whole or not at all."""
    problem = _night_problem(info)
    if problem:
        raise ValueError(f"{path}: not a night's record: {problem[0]}: {problem[1]}")
    tmp = str(path) + ".partial"
    with open(tmp, "w") as f:
        json.dump(info, f, indent=1)
        f.write("\n")
    os.replace(tmp, path)


def _night_problem(doc):
    """(field, what) of the first thing that makes DOC no night's record, or None."""
    kind = _json.kind
    if not isinstance(doc, dict):
        return "", f"expected a night's record (a JSON object), found {kind(doc)}"
    fmt = doc.get("format")
    if fmt not in (NIGHT_FORMAT, _NIGHT_FORMAT_BEFORE):
        return "format", f"expected '{NIGHT_FORMAT}', found " + (repr(fmt) if fmt is not None else "none")
    for key in ("night", "commit"):
        if not isinstance(doc.get(key), str) or not doc[key]:
            return key, f"expected a string, found {kind(doc[key]) if key in doc else 'none'}"
    if "date" in doc and parse_date(doc["date"]) is None:
        return "date", f"expected an ISO-8601 time ({DATE_EXAMPLE}), found {doc['date']!r}"
    if "machine" in doc and not isinstance(doc["machine"], dict):
        return "machine", f"expected an object, found {kind(doc['machine'])}"
    for key in ("jobs", "duration_s"):
        v = doc.get(key)
        if v is not None and not _finite(v):
            return key, f"expected a number or null, found {_damaged_text(v)}"
    return None


def read_night(path):
    """The night's record of PATH (nightly.json); FormatError naming the file and the field when
    it is not one (another format, a missing commit, a date that is no ISO-8601 time)."""
    doc = _json.load(path, "a night's record (nightly.json)")
    problem = _night_problem(doc)
    if problem:
        raise FormatError(path, problem[1], field=problem[0] or None)
    return doc
