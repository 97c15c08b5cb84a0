"""The readers of the lexdyn package (python/lexdyn; docs/python.md) on files the harness wrote in
this ctest run, and on copies of them damaged the way files get damaged (cut, edited, another
version): one FormatError naming the file, the line and the field."""
import json
import math
import os

import numpy as np
import pandas as pd
import pytest

import lexdyn
from lexdyn import FormatError

RUNS = "runs"
BFGS = "runs/pointmass-damping.bfgs"
GN = "runs/pointmass-damping.gn"
WLS = "runs/pointmass-damping.wls"


def lines_of(path):
    with open(path) as f:
        return f.read().split("\n")


def write_lines(path, lines):
    with open(path, "w") as f:
        f.write("\n".join(lines))


def first_row(lines):
    """Index of the first row of a trace's lines (after the header and the channel names)."""
    return next(i for i, l in enumerate(lines) if l and not l.startswith("#")) + 1


# ------------------------------------------------------------------ traces
def test_a_trace_as_numpy_and_pandas(outputs):
    tr = lexdyn.read_trace(os.path.join(outputs, BFGS, "trace.csv"))
    s = lexdyn.read_summary(os.path.join(outputs, BFGS))
    assert tr.completed and tr.end_status == "completed" and tr.end_message is None
    assert tr.metadata["case"] == "pointmass-damping" and tr.metadata["method"] == "bfgs"
    assert tr.names[0] == "t" and len(set(tr.names)) == len(tr.names)
    period = float(tr.metadata["control_period_s"])
    assert tr.rows == round(s["simulated_s"] / period) + 1
    assert np.allclose(np.diff(tr.t), period)
    # The structured array is the same numbers, one field per channel.
    a = tr.array
    assert a.dtype.names == tuple(tr.names) and a.shape == (tr.rows,)
    for n in ("t", "q.x", "task.position.error"):
        assert np.array_equal(a[n], tr[n])
    df = tr.dataframe()
    assert list(df.columns) == tr.names and df.shape == (tr.rows, len(tr.names))
    assert np.array_equal(df["task.position.error"].to_numpy(), tr["task.position.error"])
    # Bit for bit: the last row's error is the summary's final error (every tick is recorded).
    assert tr["task.position.error"][-1] == s["tasks"]["position"]["final_error"]
    assert np.array_equal(lexdyn.trace_array(os.path.join(outputs, BFGS, "trace.csv"))["q.x"], tr["q.x"])


def test_channels_and_header(outputs):
    path = os.path.join(outputs, BFGS, "trace.csv")
    tr = lexdyn.read_trace(path, channels=["q.x"])
    assert tr.names == ["t", "q.x"]
    tr = lexdyn.read_trace(path, channels=lambda n: n.startswith("task."))
    assert tr.names[0] == "t" and all(n.startswith("task.") for n in tr.names[1:])
    metadata, names = lexdyn.read_trace_header(path)
    assert names == lexdyn.read_trace(path).names and metadata["method"] == "bfgs"
    with pytest.raises(FormatError) as e:
        tr.col("no.such")
    assert e.value.field == "no.such" and e.value.path == path


def test_a_killed_runs_partial_trace(copy_of):
    # What a killed run leaves: no end mark, the last row cut.
    path = copy_of(os.path.join(BFGS, "trace.csv"), "trace.csv.partial")
    lines = lines_of(path)
    assert lines[-1] == "" and lines[-2].startswith("# end: ")
    rows = len(lines) - 2 - first_row(lines)
    cut = lines[:-3] + [lines[-3][:len(lines[-3]) // 2]]
    write_lines(path, cut)
    tr = lexdyn.read_trace(path)
    assert tr.rows == rows - 1 and tr.end_status is None and not tr.ended and tr.partial
    # The same bytes as a finished trace: an error naming the cut line.
    finished = path[:-len(".partial")]
    write_lines(finished, cut)
    with pytest.raises(FormatError) as e:
        lexdyn.read_trace(finished)
    assert e.value.line == len(cut) and "cut short" in str(e.value)
    assert str(e.value).startswith(f"{finished}:{len(cut)}: ")


@pytest.mark.parametrize("damage, line, field, what", [
    ("value", 3, "q.x", "expected a number, found 'fast'"),
    ("columns", 2, None, "expected"),
    ("time", 4, "t", "strictly increasing"),
    ("version", None, "lexdyn_trace", "expected trace format version 1, found '2'"),
    ("after_end", -1, None, "a line after the end mark"),
    ("crlf", 1, None, "carriage return"),
    ("nul", 2, None, "NUL byte"),
])
def test_damaged_traces(copy_of, damage, line, field, what):
    path = copy_of(os.path.join(BFGS, "trace.csv"))
    lines = lines_of(path)
    r = first_row(lines)           # index of the first row; file line r + 1
    names = lines[r - 1].split(",")
    at = None
    if damage == "value":
        k = r + line - 1
        fields = lines[k].split(",")
        fields[names.index("q.x")] = "fast"
        lines[k] = ",".join(fields)
        at = k + 1
    elif damage == "columns":
        lines[r + line - 1] += ",0"
        at = r + line
    elif damage == "time":
        k = r + line - 1
        fields = lines[k].split(",")
        fields[0] = lines[k - 1].split(",")[0]
        lines[k] = ",".join(fields)
        at = k + 1
    elif damage == "version":
        lines = [("# lexdyn_trace: 2" if l == "# lexdyn_trace: 1" else l) for l in lines]
    elif damage == "after_end":
        lines.insert(len(lines) - 1, lines[-3])
        at = len(lines) - 1
    elif damage == "crlf":
        lines[0] += "\r"
        at = 1
    elif damage == "nul":
        lines[1] = lines[1][:5] + "\0" + lines[1][5:]
        at = 2
    write_lines(path, lines)
    with pytest.raises(FormatError) as e:
        lexdyn.read_trace(path)
    assert isinstance(e.value, ValueError)
    assert e.value.path == path and e.value.line == at and e.value.field == field
    assert what in str(e.value)
    assert str(e.value).startswith(path + (f":{at}" if at else "") + ": " + (f"{field}: " if field else ""))


# ------------------------------------------------------------------ summaries
def test_run_summaries_and_their_verdicts(outputs):
    bfgs = lexdyn.read_summary(os.path.join(outputs, BFGS, "summary.json"))
    assert (bfgs.status, bfgs.exit_code, bfgs.passed) == ("completed", 0, True)
    assert bfgs.failed_checks == [] and bfgs.info_checks == []
    # A wall-clock check above an impossible limit decides nothing: the run passes.
    gn = lexdyn.read_summary(os.path.join(outputs, GN))
    assert [(c.name, c.passed, c.decides) for c in gn.info_checks] == [("tick_time_p99", False, False)]
    assert gn.failed_checks == [] and gn.exit_code == 0 and gn.passed
    assert gn.info_checks[0]["machine_dependent"] is True
    # WLS fails closed_form_eq49 as its case expects: exit code 0, the failed check listed.
    wls = lexdyn.read_summary(os.path.join(outputs, WLS))
    assert wls.exit_code == 0 and wls.passed and wls.expected_failure["met"]
    assert "closed_form_eq49" in [c.name for c in wls.failed_checks]


def test_the_summary_format_key(outputs, copy_of):
    # The harness writes the format key; a summary written before it existed is read with a
    # warning saying so; another version is refused (test_damaged_summaries).
    with open(os.path.join(outputs, BFGS, "summary.json")) as f:
        assert json.load(f)["format"] == lexdyn.SUMMARY_FORMAT == "lexdyn-run-summary/1"
    path = copy_of(os.path.join(BFGS, "summary.json"))
    with open(path) as f:
        s = json.load(f)
    del s["format"]
    with open(path, "w") as f:
        json.dump(s, f)
    with pytest.warns(UserWarning, match="without a format key"):
        old = lexdyn.read_summary(path)
    assert old.status == "completed"


@pytest.mark.parametrize("edit, field, what", [
    (lambda s: s.update(realtime_factor=float("nan")), "realtime_factor", "expected a finite number or null, found NaN"),
    (lambda s: s["checks"][0].update(value=float("inf")), "checks[0].value", "found Infinity"),
    (lambda s: s.update(format="lexdyn-run-summary/9"), "format", "found 'lexdyn-run-summary/9'"),
    (lambda s: s.pop("status"), "status", "expected the run's status (a string), found none"),
    (lambda s: s["checks"][1].update(decides="no"), "checks[1].decides", "expected true or false, found a string"),
    (lambda s: s.update(exit_code="0"), "exit_code", "expected an integer, found a string"),
])
def test_damaged_summaries(copy_of, edit, field, what):
    path = copy_of(os.path.join(GN, "summary.json"))
    with open(path) as f:
        s = json.load(f)
    edit(s)
    with open(path, "w") as f:
        json.dump(s, f, indent=2)       # Python's json writes NaN and Infinity as such
    with pytest.raises(FormatError) as e:
        lexdyn.read_summary(path)
    assert (e.value.path, e.value.field) == (path, field)
    assert what in str(e.value)


def test_a_cut_summary_names_the_line(copy_of):
    path = copy_of(os.path.join(GN, "summary.json"))
    lines = lines_of(path)
    write_lines(path, lines[:len(lines) // 2])
    with pytest.raises(FormatError) as e:
        lexdyn.read_summary(path)
    assert e.value.line is not None and "syntax error" in str(e.value)


# ------------------------------------------------------------------ sweeps
def test_a_sweep_as_a_dataframe(outputs):
    sw = lexdyn.read_sweep(os.path.join(outputs, "sweep"))
    s = sw.summary
    assert s["format"] == lexdyn.SWEEP_SUMMARY_FORMAT and sw.methods == ["wls", "bfgs"]
    assert sw.parameters == ["damping", "kp"] and len(sw.records) == s["points"] == 4
    df = sw.dataframe()
    assert isinstance(df, pd.DataFrame)
    assert len(df) == s["points"] * len(sw.methods)
    assert list(df.columns[:4]) == ["point", "method", "damping", "kp"]
    assert df["damping"].dtype == float and df["kp"].dtype == float
    assert sorted(set(zip(df["damping"], df["kp"]))) == [(0.1, 0.5), (0.1, 2.0), (1.0, 0.5), (1.0, 2.0)]
    # The DataFrame's pass rates are the sweep's own (summary.json, computed by the driver).
    for c in s["checks"]:
        rows = df[df["method"] == c["method"]]
        if c["check"] == "run_completed":
            got = (rows["status"] == "completed").mean()
        else:
            got = rows[f"check.{c['check']}.passed"].mean()
        assert got == pytest.approx(c["pass_rate"]), (c["check"], c["method"])
    # The status counts are those of each record's runs.
    assert sw.status_counts() == {m: dict(df[df["method"] == m]["status"].value_counts()) for m in sw.methods}
    failing = df[df["check.no_overshoot.passed"] == False]  # noqa: E712
    assert list(failing["method"]) == ["wls"] and (failing["damping"].iloc[0], failing["kp"].iloc[0]) == (1.0, 2.0)
    assert failing["failed"].iloc[0] == ["no_overshoot"]
    assert lexdyn.sweep_dataframe(os.path.join(outputs, "sweep")).equals(df)


def test_sweep_results_with_the_runs_under_another_key_are_refused(copy_of):
    """The drift between the sweep driver (`runs`) and a reader of `methods` fails here."""
    d = copy_of("sweep")
    path = os.path.join(d, "results.jsonl")
    lines = lines_of(path)
    rec = json.loads(lines[2])
    assert sorted(rec["runs"]) == ["bfgs", "wls"] and "methods" not in rec
    rec["methods"] = rec.pop("runs")
    lines[2] = json.dumps(rec)
    write_lines(path, lines)
    with pytest.raises(FormatError) as e:
        lexdyn.read_sweep(d)
    assert (e.value.path, e.value.line, e.value.field) == (path, 3, "runs")
    assert "expected the runs by method (an object), found none" in str(e.value)


def test_damaged_sweep_files(copy_of):
    d = copy_of("sweep")
    results = os.path.join(d, "results.jsonl")
    lines = lines_of(results)
    rec = json.loads(lines[1])
    del rec["runs"]["bfgs"]
    write_lines(results, [lines[0], json.dumps(rec)] + lines[2:])
    with pytest.raises(FormatError) as e:
        lexdyn.read_sweep(d)
    assert (e.value.line, e.value.field) == (2, "runs.bfgs")
    write_lines(results, lines[:1] + [lines[1][:40]] + lines[2:])
    with pytest.raises(FormatError) as e:
        lexdyn.read_sweep_results(results)
    assert e.value.line == 2 and "syntax error" in str(e.value)
    summary = os.path.join(d, "summary.json")
    with open(summary) as f:
        s = json.load(f)
    s["format"] = "lexdyn-sweep-summary/2"
    with open(summary, "w") as f:
        json.dump(s, f)
    with pytest.raises(FormatError) as e:
        lexdyn.read_sweep_summary(summary)
    assert e.value.field == "format" and "found 'lexdyn-sweep-summary/2'" in str(e.value)


# ------------------------------------------------------------------ the nightly history
def test_the_history_the_report_wrote(outputs):
    h = lexdyn.read_history(os.path.join(outputs, "history.jsonl"))
    assert len(h.records) == 1 and h.warnings == []
    rec = h.records[0]
    assert rec["format"] == lexdyn.HISTORY_FORMAT
    assert sorted(rec["runs"]) == ["pointmass-damping.bfgs", "pointmass-damping.gn", "pointmass-damping.wls"]
    # The wall-clock check that decides nothing is no failed check of the night.
    assert rec["runs"]["pointmass-damping.gn"]["failed_checks"] == []
    assert rec["sweeps"]["pm-grid"]
    s = lexdyn.read_summary(os.path.join(outputs, BFGS))
    assert rec["runs"]["pointmass-damping.bfgs"]["final_error"] == s["tasks"]["position"]["final_error"]


def test_a_damaged_history(copy_of):
    path = copy_of("history.jsonl")
    lines = lines_of(path)
    rec = json.loads(lines[0])
    rec["night"] = "later"
    rec["date"] = "2999-01-01T00:00:00Z"
    rec["runs"]["pointmass-damping.bfgs"]["final_error"] = float("nan")
    write_lines(path, [lines[0], json.dumps(rec), "{not json", ""])
    with pytest.raises(FormatError) as e:
        lexdyn.read_history(path)
    assert (e.value.line, e.value.field) == (2, "runs.pointmass-damping.bfgs.final_error")
    h = lexdyn.read_history(path, strict=False)
    assert [r["night"] for r in h.records] == [json.loads(lines[0])["night"], "later"]
    assert math.isnan(h.records[1]["runs"]["pointmass-damping.bfgs"]["final_error"])
    assert len(h.warnings) == 2 and f"{path}:3: expected one JSON record per line" in h.warnings[1]
    assert h.skipped == [b"{not json"]


# ------------------------------------------------------------------ the night (nightly.json)
def test_a_night_reads_back_and_a_damaged_one_is_refused_by_name(tmp_path):
    path = str(tmp_path / "nightly.json")
    info = lexdyn.night_info("a" * 40, jobs=2, duration_s="")
    lexdyn.write_night(path, info)
    back = lexdyn.read_night(path)
    assert back == info and back["format"] == lexdyn.NIGHT_FORMAT and back["duration_s"] is None
    assert back["night"].endswith(" " + "a" * 12) and back["machine"]["cores"] >= 1
    for field, value, what in (("format", "lexdyn-night/2", "expected 'lexdyn-night/1', found 'lexdyn-night/2'"),
                               ("commit", None, "expected a string, found null"),
                               ("date", "yesterday", "expected an ISO-8601 time"),
                               ("jobs", float("nan"), "expected a finite number or null, found NaN")):
        bad = dict(info, **{field: value})
        with open(path, "w") as f:
            json.dump(bad, f)
        with pytest.raises(FormatError) as e:
            lexdyn.read_night(path)
        assert e.value.field == field and what in e.value.what, str(e.value)


# ------------------------------------------------------------------ check --json
def test_check_results_the_harness_printed(outputs, tmp_path):
    r = lexdyn.read_check_results(os.path.join(outputs, "check.json"))
    assert r["format"] == lexdyn.CHECK_RESULTS_FORMAT and r["all_checks_passed"] is True
    s = lexdyn.read_summary(os.path.join(outputs, BFGS))
    assert [(c.name, c.passed) for c in r.checks] == [(c.name, c.passed) for c in s.checks]
    doc = json.loads(open(os.path.join(outputs, "check.json")).read())
    path = str(tmp_path / "check.json")
    for change, field, what in ((dict(format="lexdyn-check-results/2"), "format", "found 'lexdyn-check-results/2'"),
                                (dict(checks={}), "checks", "expected a list of checks"),
                                (dict(all_checks_passed="yes"), "all_checks_passed", "expected true or false")):
        with open(path, "w") as f:
            json.dump(dict(doc, **change), f)
        with pytest.raises(FormatError) as e:
            lexdyn.read_check_results(path)
        assert e.value.field == field and what in str(e.value)


@pytest.mark.parametrize("value, what", [
    ("+1", "expected a number, found '+1'"),
    ("1e999", "expected a number in the double range, found '1e999'"),
    ("1e-400", "expected a number in the double range, found '1e-400'"),
    ("1e-310", None),  # a subnormal: in range, as the C++ reader takes it
])
def test_a_value_the_cpp_reader_refuses_is_refused(copy_of, value, what):
    path = copy_of(os.path.join(BFGS, "trace.csv"))
    lines = lines_of(path)
    r = first_row(lines)
    names = lines[r - 1].split(",")
    fields = lines[r + 2].split(",")
    fields[names.index("q.x")] = value
    lines[r + 2] = ",".join(fields)
    write_lines(path, lines)
    if what is None:
        assert lexdyn.read_trace(path)["q.x"][2] == float(value)
        return
    with pytest.raises(FormatError) as e:
        lexdyn.read_trace(path)
    assert (e.value.line, e.value.field) == (r + 3, "q.x") and what in str(e.value)


def test_runs_that_stopped_early_fail_the_sweeps_checks_as_the_summary_counts_them(outputs):
    sw = lexdyn.read_sweep(os.path.join(outputs, "sweep-timeout"))
    df = sw.dataframe()
    assert set(df["status"]) == {"timeout"}
    assert df["check.no_overshoot.passed"].dtype == bool and not df["check.no_overshoot.passed"].any()
    assert df["check.no_overshoot.value"].isna().all()
    rates = df.groupby("method")["check.no_overshoot.passed"].mean()
    for c in sw.summary["checks"]:
        if c["check"] == "no_overshoot":
            assert rates[c["method"]] == c["pass_rate"]


def test_missing_files_and_cut_json_lines(tmp_path, copy_of):
    with pytest.raises(FormatError, match="expected a history file \\(JSON Lines\\), found no such file"):
        lexdyn.read_history(str(tmp_path / "typo.jsonl"))
    assert lexdyn.read_history(str(tmp_path / "typo.jsonl"), strict=False).records == []
    with pytest.raises(FormatError, match="expected a trace file, found no such file"):
        lexdyn.read_trace_header(str(tmp_path / "none.csv"))
    with pytest.raises(FormatError, match="expected a trace file, found a folder"):
        lexdyn.read_trace_header(str(tmp_path))
    path = copy_of(os.path.join("sweep", "results.jsonl"))
    text = open(path).read()
    with open(path, "w") as f:
        f.write(text[:len(text) - 40])
    with pytest.raises(FormatError) as e:
        lexdyn.read_sweep_results(path)
    assert "it was cut short" in str(e.value) and " at at " not in str(e.value), str(e.value)
