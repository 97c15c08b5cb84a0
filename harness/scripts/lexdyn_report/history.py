"""The history of nights (docs/report.md, "History and trend"): this night's record, writing it
into the history file, the trend and "since last night". The file's format and its reader are
lexdyn.history's (a JSON Lines file, one record per night).

The records are taken in the order of their nights' dates (`date`, ties by `night`), not in the
order of the file. A line that is not such a record (cut, garbage, another format version, a
key of the wrong type) is skipped with a warning, and kept as it was at the end of the file when
the file is rewritten; a figure that is not a finite number (NaN, Infinity, a string) is left
out of the trend with a warning. strict=True refuses both instead (lexdyn.FormatError naming the
file, the line and the field).

A figure "moves beyond its noise band" when it leaves the band of the same run's figure over
the previous nights (at most WINDOW of them): median +- max(K * 1.4826 * MAD, floor), on a log
scale for wall-clock figures (noise_band).
"""
import datetime
import json
import math
import os

from lexdyn import history as lexdyn_history
from lexdyn.history import DATE_EXAMPLE, Record, night_key, parse_date

from .common import ReportInputError, finite, json_constant, write_atomic
from .locks import FileLock
from .runs import run_key_errors

FORMAT = lexdyn_history.HISTORY_FORMAT
WINDOW = 14
K = 3.0


class Metric:
    """A figure of the history. Deterministic figures are compared linearly with floors of
    rounding size; wall-clock figures (log=True) on a log scale, with a floor factor."""

    def __init__(self, key, label, rel_floor=0.0, abs_floor=0.0, higher_is_worse=True, fmt=".4g", log=False, factor=1.0):
        self.key, self.label = key, label
        self.rel_floor, self.abs_floor = rel_floor, abs_floor
        self.higher_is_worse = higher_is_worse
        self.fmt = fmt
        self.log, self.factor = log, factor


# Deterministic figures (same binary + same input = same value) get a floor of rounding size:
# any real change is flagged. Wall-clock figures get a factor measured on the shared 2-core
# machine (docs/report.md, "Noise bands": the same runs repeated two at a time gave tick p50
# within 1.35x, p99 within 4.8x, real-time factor within 2.4x of each other).
METRICS = [
    Metric("final_error", "final error (m)", 1e-9, 1e-12),
    Metric("mean_error", "mean error (m)", 1e-9, 1e-12),
    Metric("peak_iterations", "peak active-set iterations", 0.0, 0.5, fmt=".0f"),
    Metric("failed_check_count", "failed checks", 0.0, 0.5, fmt=".0f"),
    Metric("tick_p50_us", "tick time p50 (us)", fmt=".0f", log=True, factor=1.5),
    Metric("tick_p99_us", "tick time p99 (us)", fmt=".0f", log=True, factor=5.0),
    Metric("realtime_factor", "real-time factor", higher_is_worse=False, fmt=".2f", log=True, factor=3.0),
]


# The figures of a run's record (the metrics' own keys, and its number of checks): a value that
# is not a finite number is "damaged", never a point of the trend.
FIGURES = [m.key for m in METRICS if m.key != "failed_check_count"] + ["checks"]
assert FIGURES == lexdyn_history.RUN_FIGURES, "the history's figures are those lexdyn.history reads"


def metric_value(run_record, key):
    if key == "failed_check_count":
        fc = run_record.get("failed_checks")
        return len(fc) if isinstance(fc, list) else None
    v = run_record.get(key)
    return v if finite(v) else None


def night_record(results):
    """This night's record from the stored results ("failed_checks": the checks that decide). Figures are taken as stored (a damaged one
    stays what it is, for the page to say so); storable() makes the record that is written."""
    meta = results.meta
    date = meta.get("date")
    if date is not None and parse_date(date) is None:
        raise ReportInputError(f"{os.path.join(results.dir, 'nightly.json')}: date",
                               f"expected an ISO-8601 time ({DATE_EXAMPLE}), found {date!r}")
    if not date:
        stamps = [os.path.getmtime(r.summary_path) for r in results.runs if r.summary is not None]
        when = max(stamps) if stamps else 0.0
        date = datetime.datetime.fromtimestamp(when, datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    rec = {
        "format": FORMAT,
        "night": str(meta.get("night") or os.path.basename(results.dir.rstrip("/"))),
        "commit": meta.get("commit", "unknown"),
        "date": date,
        "machine": meta.get("machine", {}),
        "runs": {},
    }
    for r in results.runs:
        info = results.case_info[r.case]
        s = r.summary or {}
        tasks, final, mean = run_key_errors(r, info)
        tick = _mapping(_mapping(s.get("timing_us")).get("tick"))
        rec["runs"][r.id] = {
            "case": r.case,
            "method": r.method,
            "status": r.status,
            "error_tasks": tasks,
            "final_error": final,
            "mean_error": mean,
            "peak_iterations": _mapping(s.get("solver")).get("peak_iterations"),
            "tick_p50_us": tick.get("median"),
            "tick_p99_us": tick.get("p99"),
            "realtime_factor": s.get("realtime_factor"),
            "failed_checks": [c.get("name") for c in r.failed_checks] if r.summary is not None else None,
            "checks": len(r.checks) if r.summary is not None else None,
        }
    if results.ctest.present:
        goldens = results.ctest.goldens
        rec["goldens"] = {"total": len(goldens), "failed": [g["id"] for g in goldens if g["failed"]]}
        others = [t for t in results.ctest.tests if not t["name"].startswith("golden.")]
        rec["tests"] = {"total": len(others), "failed": [t["name"] for t in others if t["failed"]]}
    return rec


def _mapping(x):
    return x if isinstance(x, dict) else {}


def add_sweeps(rec, sweeps):
    if not sweeps:
        return
    rec["sweeps"] = {}
    for sw in sweeps:
        rates = {}
        for c in sw.summary.get("checks", []):
            if finite(c.get("pass_rate")):
                rates[f"{c.get('check')}/{c.get('method')}"] = c["pass_rate"]
        rec["sweeps"][sw.name] = rates


def storable(rec):
    """REC as it is written into the history: a figure that is not a finite number is null (the
    file holds JSON only: never NaN or Infinity)."""
    def clean(x):
        if isinstance(x, float) and not math.isfinite(x):
            return None
        if isinstance(x, dict):
            return {k: clean(v) for k, v in x.items()}
        if isinstance(x, list):
            return [clean(v) for v in x]
        return x
    out = clean(rec)
    for rr in out.get("runs", {}).values():
        for key in FIGURES:
            if key in rr and rr[key] is not None and not finite(rr[key]):
                rr[key] = None
    return out


# ------------------------------------------------------------------ reading the history file
def load_history(path, strict=False):
    """The history file PATH as lexdyn.history reads it: `records` in date order, `skipped` lines
    and `warnings`; strict=True refuses the first problem (lexdyn.FormatError naming the file,
    the line and the field). Figures stored as NaN or Infinity are DamagedNumbers."""
    return lexdyn_history.History(path, strict=strict, constant=json_constant)


def append_record(path, rec, strict=False, command="report.py"):
    """Writes REC into the history PATH, under the lock PATH.lock (other jobs writing the same
    history wait): read again, a record of the same night replaced (a report rebuilt after a
    resumed night does not count the night twice), every record in date order, the skipped lines
    kept at the end as they were; written to a temporary name, synced, renamed. Returns the
    History as read under the lock and the records as written."""
    with FileLock(path, command):
        h = load_history(path, strict)
        new = Record(storable(rec))
        new.line = json.dumps(new, sort_keys=True, allow_nan=False).encode()
        kept = sorted([r for r in h.records if r.get("night") != rec["night"]] + [new], key=night_key)
        data = b"".join(r.line + b"\n" for r in kept) + b"".join(line + b"\n" for line in h.skipped)
        write_atomic(path, data, durable=True)
    return h, kept


def earlier_records(records, current):
    """The records of the nights dated before CURRENT (ties by night id), in that order; never
    CURRENT's own night."""
    k = night_key(current)
    return sorted((r for r in records if r.get("night") != current["night"] and night_key(r) < k), key=night_key)


def median(xs):
    s = sorted(xs)
    n = len(s)
    return s[n // 2] if n % 2 else 0.5 * (s[n // 2 - 1] + s[n // 2])


def noise_band(prior, metric):
    """(low, high) of the band from earlier values, or None without any. Linear: median +-
    max(K * 1.4826 * MAD, rel_floor * |median|, abs_floor). Log (wall-clock figures): the same
    on log values with the floor log(factor), i.e. median / f .. median * f at least."""
    if metric.log:
        prior = [math.log(x) for x in prior if x > 0]
    if not prior:
        return None
    c = median(prior)
    spread = K * 1.4826 * median([abs(x - c) for x in prior])
    if metric.log:
        h = max(spread, math.log(metric.factor))
        return math.exp(c - h), math.exp(c + h)
    h = max(spread, metric.rel_floor * abs(c), metric.abs_floor)
    return c - h, c + h


def trend(records, current):
    """Per run and metric: the series (the nights dated before this one, then this one), the band
    and the flag. Returns {run_id: {metric_key: {"values": [(night, date, value)], "band": (c, h) |
    None, "flag": None | "worse" | "better", "value", "damaged"}}}; band = (low, high); damaged:
    this night's figure is stored but is not a finite number."""
    earlier = earlier_records(records, current)
    out = {}
    for rid, rr in current["runs"].items():
        per = {}
        for m in METRICS:
            series = []
            for rec in earlier:
                v = metric_value(rec.get("runs", {}).get(rid, {}), m.key)
                if v is not None:
                    series.append((rec["night"], rec.get("date", ""), v))
            v = metric_value(rr, m.key)
            prior = [x[2] for x in series[-WINDOW:]]
            band = noise_band(prior, m)
            flag = None
            if v is not None and band is not None and not band[0] <= v <= band[1]:
                up = v > band[1]
                flag = "worse" if up == m.higher_is_worse else "better"
            if v is not None:
                series.append((current["night"], current.get("date", ""), v))
            damaged = m.key != "failed_check_count" and rr.get(m.key) is not None and v is None
            per[m.key] = {"values": series, "band": band, "flag": flag, "value": v, "damaged": damaged}
        out[rid] = per
    return out


def changes(records, current):
    """What changed since the latest night dated before this one: new failures, fixed ones,
    golden drift, status changes, runs added or missing."""
    earlier = earlier_records(records, current)
    prev = earlier[-1] if earlier else None
    ch = {"previous": prev, "new_failures": [], "fixed": [], "still_failing": [], "status": [],
          "added": [], "missing": [], "goldens_new": [], "goldens_still": [], "goldens_fixed": [],
          "tests_new": [], "tests_fixed": []}
    if prev is None:
        return ch
    pr = prev.get("runs", {})
    for rid, rr in current["runs"].items():
        if rid not in pr:
            ch["added"].append(rid)
            continue
        p = pr[rid]
        if rr.get("status") != p.get("status"):
            ch["status"].append((rid, p.get("status"), rr.get("status")))
        now = set(rr.get("failed_checks") or [])
        before = set(p.get("failed_checks") or [])
        for c in sorted(now - before):
            ch["new_failures"].append((rid, c))
        for c in sorted(now & before):
            ch["still_failing"].append((rid, c))
        if rr.get("failed_checks") is not None:
            for c in sorted(before - now):
                ch["fixed"].append((rid, c))
    ch["missing"] = sorted(set(pr) - set(current["runs"]))
    if "goldens" in current and "goldens" in prev:
        now, before = set(current["goldens"]["failed"]), set(prev["goldens"]["failed"])
        ch["goldens_new"] = sorted(now - before)
        ch["goldens_still"] = sorted(now & before)
        ch["goldens_fixed"] = sorted(before - now)
    elif "goldens" in current:
        ch["goldens_new"] = sorted(current["goldens"]["failed"])
    if "tests" in current and "tests" in prev:
        now, before = set(current["tests"]["failed"]), set(prev["tests"]["failed"])
        ch["tests_new"] = sorted(now - before)
        ch["tests_fixed"] = sorted(before - now)
    return ch

