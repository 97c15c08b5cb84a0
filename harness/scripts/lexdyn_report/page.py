"""Builds the report folder (docs/report.md): OUT/index.html with figures/, replay/, three.js
beside it. Everything is read from stored results (runs, sweeps, history). The report is built
in a staging folder inside OUT and swapped in whole (ReportBuilder.build)."""
import json
import os
import shutil
import signal

from lexdyn import FormatError, read_trace

from . import figures, history as hist, replay
from .common import (DAMAGED, ReportInputError, ReportOutputError, copy_atomic, esc, finite, fnum, fpercent,
                     method_colour, method_label, method_sort_key, non_finite_fields, os_reason, write_atomic)
from .locks import LOCK_NAME
from .runs import detail_time, resolve, run_key_errors

THREE_DIR = "/usr/share/javascript/three"
ASSETS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "assets")
# Paths stored relative to where a run was started (usually the repository root).
REPO_ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", ".."))
# Inside the report folder: the report being built (OUT/.staging-PID) and the entries of the
# previous report while they are swapped out (OUT/.old-PID). A job holding the folder's lock
# removes those of a job that died.
STAGING_PREFIX = ".staging-"
ASIDE_PREFIX = ".old-"

CSS = """
body{font-family:sans-serif;font-size:14px;margin:0 auto;max-width:1180px;padding:0 16px;color:#222}
h1{font-size:22px}h2{font-size:18px;border-bottom:1px solid #ccd;padding-bottom:3px;margin-top:32px}
h3{font-size:15px;margin-top:22px}table{border-collapse:collapse;margin:8px 0;font-size:12.5px}
th,td{border:1px solid #d0d4da;padding:3px 6px;text-align:left;vertical-align:top}th{background:#eef1f5}
td.num{text-align:right;font-variant-numeric:tabular-nums}.pass{background:#e3f4e1}.fail{background:#fbe0dc}
.stop{background:#fff0c2}.xfail{background:#e8e8f4}.info{background:#eef4fb;color:#555}.miss{background:#eee;color:#666}.flag-worse{background:#fbe0dc}.flag-better{background:#e3f4e1}
figure{margin:10px 0 18px}figure img{max-width:100%;border:1px solid #e0e3e8}figcaption{font-size:12px;color:#555}
nav a{margin-right:12px}.swatch{display:inline-block;width:12px;height:12px;border-radius:2px;vertical-align:middle;margin:0 4px 0 10px}
pre,code{font-size:12px;background:#f4f6f8}pre{padding:6px;overflow-x:auto;white-space:pre-wrap}
.note{color:#555;font-style:italic}#replay-view canvas{width:100%;border:1px solid #ccd}
.controls{display:flex;gap:10px;align-items:center;margin:6px 0}#replay-slider{flex:1}
.bar{display:inline-block;height:9px;background:#2ca02c;vertical-align:middle}.bar-bg{display:inline-block;width:80px;height:9px;background:#fbe0dc;vertical-align:middle}
"""


def _cls(run):
    if run.summary is None:
        return "miss"
    if run.failed_as_expected:
        return "xfail"
    if run.status != "completed":
        return "stop"
    return "pass" if run.passed else "fail"


def _verdict_text(run):
    """The run's own verdict (its exit code: summary.json exit_code) with the checks that decide
    passed / total; the checks reported only (decides: false, wall-clock) are counted apart as
    "info" and never make a run fail."""
    if run.summary is None:
        return "no summary" if run.status == "no_summary" else "not run"
    n, f = len(run.deciding_checks), len(run.failed_checks)
    if run.status != "completed":
        head = run.status
    else:
        head = "pass" if run.passed else "FAIL"
    x = run.expected_failure
    if x:
        # The case expects this failure (expected_failures): as expected, or a different outcome.
        head = ("expected failure" if x.get("met") else "NOT the expected failure") + \
            ("" if run.status == "completed" else f": {run.status}")
    k = len(run.info_checks)
    info = f", {k} info" if k else ""
    return f"{head} ({n - f}/{n} checks{info}){_cut_text(run)}"


def _cut_text(run):
    """', run to T of the scenario's D s, K checks skipped' for a run stopped before its
    scenario's end (run --duration, stop_at_s), else ''."""
    s = run.summary or {}
    scenario, stop = s.get("scenario_duration_s"), s.get("duration_s")
    if not finite(scenario) or not finite(stop) or stop >= scenario:
        return ""
    k = len(s.get("skipped_checks", []) or [])
    return f", run to {stop:g} of the scenario's {scenario:g} s, {k} check{'s' if k != 1 else ''} skipped"


def _failing_rows(run):
    """The rows of the failing-checks table for one run: a stopped or summary-less run, the
    expected-failure verdict, then each failing check; a check the case expects to fail
    (expected_failures) in the xfail colour, any other in the failure colour; a check reported
    only (decides: false) above its limit in the info colour."""
    out = []
    if run.summary is None:
        return [f"<tr class='miss'><td>{esc(run.id)}</td><td colspan='7'>{esc(_verdict_text(run))}"
                f"<pre>{esc(run.log_tail())}</pre></td></tr>"]
    x = run.expected_failure
    if x:
        what = "expected failure" if x.get("met") else "NOT the expected failure: " + "; ".join(x.get("mismatches", []))
        out.append(f"<tr class='{'xfail' if x.get('met') else 'fail'}'><td>{esc(run.id)}</td><td colspan='7'>"
                   f"{esc(what)} (the case says: {esc(x.get('reason', ''))})</td></tr>")
    if run.status != "completed":
        out.append(f"<tr class='stop'><td>{esc(run.id)}</td><td colspan='7'>run stopped: {esc(run.status)}: "
                   f"{esc(run.summary.get('message', ''))} (at t = {fnum(run.summary.get('simulated_s'), '.4g')} s)</td></tr>")
    expected = set(x.get("checks", [])) if x else set()
    # The checks that decide and failed, then those reported only (decides: false) that are
    # above their limit here: "info", never a failure of the run.
    info = [c for c in run.info_checks if not c.get("passed", False)]
    for c in run.failed_checks + info:
        t = detail_time(c.get("detail"))
        cls = "info" if not c.decides else ("xfail" if c.get("name") in expected else "fail")
        name = c.get("name") + (" (info: machine-dependent, reported only)" if cls == "info" else "")
        out.append(f"<tr class='{cls}'><td>{esc(run.id)}</td><td>{esc(name)}</td><td>{esc(c.get('type'))}</td>"
                   f"<td class='num'>{fnum(c.get('value'), '.6g')}</td><td class='num'>{fnum(c.get('limit'), '.6g')}</td>"
                   f"<td>{esc(c.get('unit', ''))}</td><td class='num'>{fnum(t, '.4g')}</td><td>{esc(c.get('detail', ''))}</td></tr>")
    return out


class ReportBuilder:
    def __init__(self, results, sweeps, history_path, out_dir, append_history=False, title=None, strict_history=False):
        self.results = results
        self.sweeps = sweeps
        self.history_path = history_path
        self.out = os.path.abspath(out_dir)   # where files are written: the staging folder while building
        self.append_history = append_history
        self.strict_history = strict_history
        self.title = title or "lexdyn nightly report"
        self.models = {}          # (urdf, data file) -> (model dict, script file, model name)
        self.replays = {}         # run id -> {run, model, model_name}
        self.case_figures = {}    # case -> [figure dicts]
        self.warnings = []
        self.history_warnings = []

    # ------------------------------------------------------------------ building
    def build(self):
        """Builds the whole report into OUT/.staging-PID, writes the night into the history when
        asked (append_history), then swaps the report in: each entry replaces the previous
        report's of the same name, index.html last. A failure (a full disk, an interruption)
        removes the staging folder and leaves the previous report as it was. OUT exists and is
        locked by the caller (locks.FolderLock)."""
        final = self.out
        remove_leftovers(final)
        staging = os.path.join(final, f"{STAGING_PREFIX}{os.getpid()}")
        aside = os.path.join(final, f"{ASIDE_PREFIX}{os.getpid()}")
        try:
            # Both folders made now: on a full disk the swap would not get one.
            os.mkdir(staging)
            os.mkdir(aside)
            self.out = staging
            self._build_into()
            if self.append_history and self.history_path:
                h, _ = hist.append_record(self.history_path, self.record, strict=self.strict_history)
                self.warnings.extend(w for w in h.warnings if w not in self.warnings)
            swap_in(staging, final, aside)
        except OSError as e:
            _remove_staging(staging, aside)
            raise ReportOutputError(e.filename or final, os_reason(e)) from e
        except BaseException:
            _remove_staging(staging, aside)
            raise
        finally:
            self.out = final
        return os.path.join(final, "index.html")

    def _build_into(self):
        for sub in ("figures", "replay", "sweeps"):
            os.makedirs(os.path.join(self.out, sub))
        for f in ("three.min.js", "examples/js/controls/OrbitControls.js"):
            src = os.path.join(THREE_DIR, f)
            if not os.path.isfile(src):
                raise ReportInputError(src, "expected Debian's libjs-three (harness/scripts/install-deps.sh installs it), found no file")
            copy_atomic(src, os.path.join(self.out, os.path.basename(f)))
        copy_atomic(os.path.join(ASSETS, "replay.js"), os.path.join(self.out, "replay.js"))

        for run in self.results.runs:
            for field, text in run.damaged:
                self.warnings.append(f"{run.summary_path}: {field}: expected a finite number, found {text} "
                                     f"(a damaged file): shown as \"{DAMAGED}\"")
        for sw in self.sweeps:
            for field, text in non_finite_fields(sw.summary):
                self.warnings.append(f"{os.path.join(sw.dir, 'summary.json')}: {field}: expected a finite number, found {text} "
                                     f"(a damaged file): shown as \"{DAMAGED}\"")
        self.record = hist.night_record(self.results)
        hist.add_sweeps(self.record, self.sweeps)
        history = hist.load_history(self.history_path, strict=self.strict_history)
        self.records = history.records
        self.history_warnings = history.warnings
        self.warnings.extend(history.warnings)
        self.earlier = hist.earlier_records(self.records, self.record)
        self.changes = hist.changes(self.records, self.record)
        self.trend = hist.trend(self.records, self.record)

        for case, runs in self.results.cases.items():
            self._case(case, runs)
        self.trend_figs = self._trend_figures()
        self.sweep_assets = self._sweep_assets()
        page = self._page()
        write_atomic(os.path.join(self.out, "index.html"), page)

    def _model_for(self, run):
        h = run.header.get("model", "")
        urdf = data = None
        if "(urdf " in h and ", data " in h:
            inner = h[h.index("(urdf ") + len("(urdf "):].rstrip(")")
            urdf, _, data = inner.partition(", data ")
        info = self.results.case_info[run.case]
        case_dir = os.path.dirname(info.path) if info.path else None
        bases = [self.results.dir] + ([case_dir] if case_dir else []) + [REPO_ROOT]
        urdf_p = resolve(urdf, *bases) or (resolve(info.robot.get("urdf"), case_dir) if case_dir else None)
        data_p = resolve(data, *bases) or (resolve(info.robot.get("data"), case_dir) if case_dir else None)
        if not urdf_p:
            self.warnings.append(f"{run.id}: the robot's URDF ({urdf or 'not named'}) is not readable: no replay")
            return None
        package_paths = []
        for pp in (info.robot.get("package_path") or []) if isinstance(info.robot, dict) else []:
            p = str(pp) if os.path.isabs(str(pp)) or not case_dir else os.path.join(case_dir, str(pp))
            if os.path.isdir(p):
                package_paths.append(os.path.abspath(p))
        key = (urdf_p, data_p)
        if key not in self.models:
            m = replay.load_model(urdf_p, data_p, package_paths)
            name = m["name"] or os.path.splitext(os.path.basename(urdf_p))[0]
            taken = {v[2] for v in self.models.values()}
            base, k = name, 2
            while name in taken:  # two robots of the same name (other files): keep both
                name, k = f"{base}-{k}", k + 1
            m["name"] = name
            fname = f"replay/model_{name}.js"
            for w in m["warnings"]:
                self.warnings.append(w)
            write_atomic(os.path.join(self.out, fname), f"LexdynReplay.registerModel({json.dumps(name)}, {json.dumps(m)});\n")
            self.models[key] = (m, fname, name)
        return self.models[key]

    def _case(self, case, runs):
        info = self.results.case_info[case]
        items = []
        prefix = f"figures/{case}."
        for run in runs:
            if not run.trace_path:
                continue
            try:
                tr = read_trace(run.trace_path, channels=_plot_or_replay_channel)
            except FormatError as e:
                # One unreadable trace leaves its run without figures and replay, not the night
                # without a report; the warning says where.
                self.warnings.append(f"{run.id}: {e}")
                continue
            items.append((run, tr))
            m = self._model_for(run)
            if m is not None:
                model, mfile, mname = m
                data = replay.motion(run, tr, model, info)
                rfile = f"replay/run_{run.id}.js"
                write_atomic(os.path.join(self.out, rfile),
                             f"LexdynReplay.registerRun({json.dumps(run.id)}, {json.dumps(data, separators=(',', ':'))});\n")
                self.replays[run.id] = {"run": rfile, "model": mfile, "model_name": mname}
        figs = []
        if items:
            key_tasks = info.key_tasks((items[0][0].summary or {}).get("tasks", {}), items[0][1].names)
            efforts = {}
            for run, _ in items:
                m = self._model_for(run)
                if m:
                    for j in m[0]["joints"]:
                        if j.get("effort"):
                            efforts[j["name"]] = j["effort"]
            out = self.out
            for f in (figures.task_errors(case, items, out, prefix, key_tasks),
                      figures.joint_velocities(case, items, out, prefix),
                      figures.torques(case, items, out, prefix, efforts),
                      figures.activity(case, items, out, prefix),
                      figures.solver(case, items, out, prefix),
                      figures.wrenches(case, items, out, prefix),
                      figures.com_path(case, items, out, prefix)):
                if f:
                    figs.append(f)
        self.case_figures[case] = figs

    def _trend_figures(self):
        if not self.earlier:
            return []
        out = []
        for m in hist.METRICS:
            f = figures.trend_figure(m, self.trend, self.out, f"figures/trend.{m.key}.png")
            if f:
                out.append((m, f))
        return out

    def _sweep_assets(self):
        assets, warnings = sweep_assets(self.sweeps, self.out)
        self.warnings.extend(warnings)
        return assets

    # ------------------------------------------------------------------ HTML
    def _page(self):
        r = self.results
        rec = self.record
        methods_present = sorted({run.method for run in r.runs}, key=method_sort_key)
        swatches = "".join(f'<span class="swatch" style="background:{method_colour(m)}"></span>{esc(method_label(m))}'
                           for m in methods_present)
        machine = rec.get("machine") or {}
        mtext = ", ".join(f"{k} {v}" for k, v in machine.items()) if isinstance(machine, dict) else str(machine)
        n_runs = len(r.runs)
        n_ok = sum(1 for x in r.runs if x.passed)
        parts = [
            "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>",
            f"<title>{esc(self.title)}: {esc(rec['night'])}</title><style>{CSS}</style></head><body>",
            f"<h1>{esc(self.title)}</h1>",
            f"<p id='meta'>night <b>{esc(rec['night'])}</b>, commit <code>{esc(rec.get('commit'))}</code>, "
            f"{esc(rec.get('date'))}{', ' + esc(mtext) if mtext else ''}. "
            f"{n_ok} of {n_runs} runs passed (exit code 0: every check that decides passed, or the failure the case expects)."
            + (f" <a href='#warnings'>{len(self.warnings)} warning(s)</a>." if self.warnings else "") + "</p>",
            f"<p id='legend'>Method colours (every figure):{swatches}</p>",
            "<nav><a href='#changes'>Since last night</a><a href='#verdicts'>Verdicts</a><a href='#goldens'>Goldens and tests</a>"
            "<a href='#cases'>Cases</a><a href='#sweeps'>Sweeps</a><a href='#trend'>Trend</a><a href='#replay'>3D replay</a></nav>",
            self._changes_html(),
            self._verdicts_html(methods_present),
            self._goldens_html(),
            self._cases_html(),
            self._sweeps_html(),
            self._trend_html(),
            self._replay_html(),
            self._footer_html(),
            "<script src='three.min.js'></script><script src='OrbitControls.js'></script><script src='replay.js'></script>",
            f"<script>LexdynReplay.init({json.dumps(self.replays)});</script>",
            "</body></html>\n",
        ]
        return "\n".join(parts)

    def _changes_html(self):
        ch = self.changes
        out = ["<section id='changes'><h2>Since last night</h2>"]
        if ch["previous"] is None:
            out.append("<p class='note' id='no-previous'>No earlier night in the history"
                       + ("" if self.history_path else " (no --history file given)") + ": nothing to compare with.</p>")
        else:
            p = ch["previous"]
            out.append(f"<p>Compared with night <b>{esc(p['night'])}</b> (commit <code>{esc(p.get('commit'))}</code>, {esc(p.get('date'))}): "
                       "the latest night of the history dated before this one.</p>")
        out.append(self._history_warnings_html())
        rows = []
        for rid, c in ch["new_failures"]:
            rows.append(("new failure", rid, c, "fail"))
        for rid, before, now in ch["status"]:
            rows.append(("status changed", rid, f"{before} -> {now}", "fail" if now != "completed" else "pass"))
        for rid, c in ch["fixed"]:
            rows.append(("fixed", rid, c, "pass"))
        for g in ch["goldens_new"]:
            rows.append(("golden drift (new)", g, self._golden_message(g), "fail"))
        for g in ch["goldens_still"]:
            rows.append(("golden drift (still)", g, self._golden_message(g), "fail"))
        for g in ch["goldens_fixed"]:
            rows.append(("golden matches again", g, "", "pass"))
        for t in ch["tests_new"]:
            rows.append(("test failing (new)", t, "", "fail"))
        for t in ch["tests_fixed"]:
            rows.append(("test fixed", t, "", "pass"))
        for rid in ch["added"]:
            rows.append(("run added", rid, "", ""))
        for rid in ch["missing"]:
            rows.append(("run missing", rid, "in the previous night, not in this one", "fail"))
        for rid, per in self.trend.items():
            for m in hist.METRICS:
                d = per[m.key]
                if d["flag"]:
                    lo, hi = d["band"]
                    rows.append((f"trend: {d['flag']}", rid, f"{m.label} {fnum(d['value'], m.fmt)} outside "
                                 f"{fnum(lo, '.4g')} .. {fnum(hi, '.4g')}", "fail" if d["flag"] == "worse" else "pass"))
        if rows:
            out.append("<table id='changes-table'><tr><th>change</th><th>run / golden / test</th><th>what</th></tr>")
            for kind, who, what, cls in rows:
                out.append(f"<tr class='{cls}'><td>{esc(kind)}</td><td>{esc(who)}</td><td>{esc(what)}</td></tr>")
            out.append("</table>")
        elif ch["previous"] is not None:
            out.append("<p id='no-changes'>No new failures, nothing fixed, no golden drift, no figure outside its noise band.</p>")
        out.append("</section>")
        return "\n".join(out)

    def _history_warnings_html(self):
        """The history's lines that were skipped and its figures left out of the trend."""
        w = self.history_warnings
        if not w:
            return ""
        return (f"<div id='history-warnings' class='stop'><p>The history file <code>{esc(self.history_path)}</code> has "
                f"{len(w)} damaged entr{'y' if len(w) == 1 else 'ies'}: a line that is no record is skipped (and kept as it "
                "is at the end of the file), a figure that is not a number is left out of the trend "
                "(docs/report.md, \"History and trend\").</p><ul>" + "".join(f"<li>{esc(x)}</li>" for x in w) + "</ul></div>")

    def _golden_message(self, gid):
        for g in self.results.ctest.goldens:
            if g["id"] == gid:
                return g["message"]
        return ""

    def _verdicts_html(self, methods):
        r = self.results
        out = ["<section id='verdicts'><h2>Verdicts</h2>",
               "<table id='verdict-table'><tr><th>case</th>" + "".join(f"<th>{esc(method_label(m))}</th>" for m in methods) + "</tr>"]
        for case, runs in r.cases.items():
            cells = []
            for m in methods:
                run = next((x for x in runs if x.method == m), None)
                if run is None:
                    cells.append("<td></td>")
                    continue
                rep = f" <a href='#replay' data-replay='{esc(run.id)}'>replay</a>" if run.id in self.replays else ""
                cells.append(f"<td class='{_cls(run)}' data-run='{esc(run.id)}'>{esc(_verdict_text(run))}{rep}</td>")
            out.append(f"<tr><td><a href='#case-{esc(case)}'>{esc(case)}</a></td>{''.join(cells)}</tr>")
        out.append("</table>")
        out.append("<h3>Failing checks and stopped runs</h3>")
        out.append("<table id='failing-checks'><tr><th>run</th><th>check</th><th>type</th><th>value</th><th>limit</th>"
                   "<th>unit</th><th>at t (s)</th><th>where</th></tr>")
        rows = [row for run in r.runs for row in _failing_rows(run)]
        out.extend(rows)
        n = len(rows)
        if n == 0:
            out.append("<tr><td colspan='8'>none</td></tr>")
        out.append("</table></section>")
        return "\n".join(out)

    def _goldens_html(self):
        ct = self.results.ctest
        out = ["<section id='goldens'><h2>Goldens and tests</h2>"]
        if not ct.present:
            out.append(f"<p class='note'>No ctest results stored ({esc(os.path.relpath(ct.path, self.results.dir))}): "
                       "golden drift unknown for this night.</p></section>")
            return "\n".join(out)
        gold = ct.goldens
        bad = [g for g in gold if g["failed"]]
        others = [t for t in ct.tests if not t["name"].startswith("golden.")]
        out.append(f"<p>{len(gold) - len(bad)} of {len(gold)} golden traces match; "
                   f"{len(others) - len(ct.failed_tests) + len(bad)} of {len(others)} other ctest tests pass.</p>")
        out.append("<table id='golden-table'><tr><th>golden</th><th>result</th><th>first divergence</th></tr>")
        for g in gold:
            out.append(f"<tr class='{'fail' if g['failed'] else 'pass'}'><td>{esc(g['id'])}</td>"
                       f"<td>{'drift' if g['failed'] else 'match'}</td><td>{esc(g['message'])}</td></tr>")
        out.append("</table>")
        failed = [t for t in others if t["failed"]]
        if failed:
            out.append("<h3>Failing tests</h3><table id='failing-tests'><tr><th>test</th><th>output (last lines)</th></tr>")
            for t in failed:
                last = "\n".join([l for l in t["output"].splitlines() if l.strip()][-8:])
                out.append(f"<tr class='fail'><td>{esc(t['name'])}</td><td><pre>{esc(last)}</pre></td></tr>")
            out.append("</table>")
        out.append("</section>")
        return "\n".join(out)

    def _cases_html(self):
        out = ["<section id='cases'><h2>Cases</h2>"]
        for case, runs in self.results.cases.items():
            info = self.results.case_info[case]
            out.append(f"<section class='case' id='case-{esc(case)}' data-case='{esc(case)}'><h3>{esc(case)}</h3>")
            if info.description:
                out.append(f"<p>{esc(info.description)}</p>")
            out.append(self._method_table(case, runs))
            for key, css, title in (("robot_warnings", "robot-warnings", "the robot files were read with"),
                                    ("start_warnings", "start-warnings", "the start was questionable:")):
                # What the robot loader assumed about the robot files (docs/model.md); what the
                # start found questionable (docs/controller.md, "Contact margins").
                warnings = []
                for run in runs:
                    for w in (run.summary or {}).get(key, []) or []:
                        if w not in warnings:
                            warnings.append(w)
                if warnings:
                    out.append(f"<details class='{css}' id='{css}-{esc(case)}'><summary>{title} "
                               f"{len(warnings)} warning(s)</summary><ul>"
                               + "".join(f"<li>{esc(w)}</li>" for w in warnings) + "</ul></details>")
            comps = self.results.comparisons.get(case)
            if comps:
                out.append(f"<table class='comparison-table' id='comparisons-{esc(case)}'><tr><th>comparison</th><th>result</th>"
                           "<th>value (m)</th><th>margin</th><th>detail</th></tr>")
                for c in comps:
                    out.append(f"<tr class='{'pass' if c.get('passed') else 'fail'}'><td>{esc(c.get('name'))}</td>"
                               f"<td>{'pass' if c.get('passed') else 'FAIL'}</td><td class='num'>{fnum(c.get('value'), '.4g')}</td>"
                               f"<td class='num'>{fnum(c.get('limit'), '.4g')}</td><td>{esc(c.get('detail', ''))}</td></tr>")
                out.append("</table>")
            for f in self.case_figures.get(case, []):
                out.append(f"<figure data-figure='{esc(f['key'])}' data-case='{esc(case)}'><img src='{esc(f['file'])}' "
                           f"alt='{esc(case)}: {esc(f['title'])}'><figcaption>{esc(f['title'])}. {esc(f['caption'])}</figcaption></figure>")
            if not any(x.trace_path for x in runs):
                out.append("<p class='note'>No trace stored for this case: no figures.</p>")
            out.append("</section>")
        out.append("</section>")
        return "\n".join(out)

    def _method_table(self, case, runs):
        info = self.results.case_info[case]
        head = ["run", "status", "sim s", "final error (m)", "mean error (m)", "peak it. (at s)",
                "tick p50 / p99 / max (us)", "real-time factor", "Newton ticks", "checks passed"]
        tasks = None
        rows = []
        for run in runs:
            s = run.summary or {}
            names, final, mean = run_key_errors(run, info)
            tasks = tasks or names
            tick = _mapping(_mapping(s.get("timing_us")).get("tick"))
            aug = _mapping(_mapping(s.get("controller")).get("augmented_ticks"))
            sol = _mapping(s.get("solver"))
            peak = f"{fnum(sol['peak_iterations'], '.0f')} ({fnum(sol.get('peak_iterations_at_s'), '.4g')})" if "peak_iterations" in sol else "-"
            newton = fnum(sum(aug.values()), ".0f") if all(finite(v) for v in aug.values()) else DAMAGED
            rows.append(f"<tr><td><span class='swatch' style='background:{method_colour(run.method)}'></span>{esc(run.id)}</td>"
                        f"<td class='{'' if run.status == 'completed' else 'stop'}'>{esc(run.status)}</td><td class='num'>{fnum(s.get('simulated_s'), '.1f')}</td>"
                        f"<td class='num'>{fnum(final, '.4f')}</td><td class='num'>{fnum(mean, '.4f')}</td>"
                        f"<td class='num'>{esc(peak)}</td>"
                        f"<td class='num'>{fnum(tick.get('median'), '.0f')} / {fnum(tick.get('p99'), '.0f')} / {fnum(tick.get('max'), '.0f')}</td>"
                        f"<td class='num'>{fnum(s.get('realtime_factor'), '.1f')}</td>"
                        f"<td class='num'>{newton if aug else '-'}</td>"
                        f"<td class='num'>{len(run.deciding_checks) - len(run.failed_checks) if run.summary else '-'} / {len(run.deciding_checks) if run.summary else '-'}"
                        f"{f' (+{len(run.info_checks)} info)' if run.info_checks else ''}</td></tr>")
        note = f"<p class='note'>Errors: sum of {esc(' + '.join(tasks))}.</p>" if tasks else ""
        return (f"<table class='method-table' id='methods-{esc(case)}'><tr>" + "".join(f"<th>{esc(h)}</th>" for h in head)
                + "</tr>" + "".join(rows) + "</table>" + note)

    def _sweeps_html(self):
        return sweeps_section(self.sweeps, self.sweep_assets)

    def _trend_html(self):
        out = ["<section id='trend'><h2>Trend</h2>"]
        earlier = self.earlier
        if not self.history_path:
            out.append("<p class='note' id='no-history'>No history file given (--history): no trend.</p></section>")
            return "\n".join(out)
        if self.history_warnings:
            out.append(f"<p class='stop' id='trend-history-note'>{len(self.history_warnings)} damaged entr"
                       f"{'y' if len(self.history_warnings) == 1 else 'ies'} of the history left out "
                       "(<a href='#history-warnings'>listed under Since last night</a>).</p>")
        out.append(f"<p>{len(earlier)} earlier night(s) in <code>{esc(self.history_path)}</code> (dated before this one). A figure is flagged when it leaves "
                   f"median &plusmn; max({hist.K:g} &times; 1.4826 &times; MAD, floor) of the same run's last {hist.WINDOW} nights "
                   "(wall-clock figures on a log scale; docs/report.md, \"Noise bands\").</p>")
        if not earlier:
            out.append("<p class='note' id='no-trend'>The trend starts with the second night.</p></section>")
            return "\n".join(out)
        out.append("<table id='trend-table'><tr><th>run</th>" + "".join(f"<th>{esc(m.label)}</th>" for m in hist.METRICS) + "</tr>")
        for rid, per in self.trend.items():
            cells = []
            for m in hist.METRICS:
                d = per[m.key]
                cls = f" class='flag-{d['flag']}'" if d["flag"] else ""
                band = f" (band {fnum(d['band'][0], '.4g')} .. {fnum(d['band'][1], '.4g')})" if d["band"] else ""
                cells.append(f"<td{cls}>{DAMAGED if d.get('damaged') else fnum(d['value'], m.fmt)}{band}</td>")
            out.append(f"<tr><td>{esc(rid)}</td>{''.join(cells)}</tr>")
        out.append("</table>")
        for m, f in self.trend_figs:
            out.append(f"<figure data-figure='trend-{esc(m.key)}'><img src='{esc(f)}' alt='trend of {esc(m.label)}'>"
                       f"<figcaption>{esc(m.label)} per night.</figcaption></figure>")
        out.append("</section>")
        return "\n".join(out)

    def _replay_html(self):
        out = ["<section id='replay'><h2>3D replay</h2>"]
        if not self.replays:
            out.append("<p class='note'>No run with a trace and a readable robot model: nothing to replay.</p></section>")
            return "\n".join(out)
        opts = "".join(f"<option value='{esc(rid)}'>{esc(rid)}</option>" for rid in self.replays)
        out.append("<div class='controls'><label>run <select id='replay-run'>" + opts + "</select></label>"
                   "<button id='replay-play' type='button'>play</button>"
                   "<label>speed <select id='replay-speed'><option value='0.5'>0.5x</option><option value='1' selected>1x</option>"
                   "<option value='4'>4x</option><option value='10'>10x</option></select></label>"
                   "<input id='replay-slider' type='range' min='0' max='0' step='any' value='0'></div>")
        out.append("<div id='replay-time'></div><div id='replay-view'></div><div id='replay-info'></div><div id='replay-status'></div>")
        out.append("<p class='note'>The robot from its URDF geometry, moved by the trace's base pose and joint positions. "
                   "Pink: position targets (a line from the task's frame); purple: the CoM box and CoM targets; black: the CoM; "
                   "orange arrows: sensed contact forces, blue: the controller's computed ones (1 mm per N, from the centre of pressure). "
                   "Drag to orbit, scroll to zoom.</p></section>")
        return "\n".join(out)

    def _footer_html(self):
        w = "".join(f"<li>{esc(x)}</li>" for x in self.warnings)
        return ("<footer><h2>About this report</h2><p>Built by <code>harness/scripts/report.py</code> from stored results in "
                f"<code>{esc(self.results.dir)}</code> (docs/report.md). three.js r111 (Debian libjs-three) is copied beside the page; "
                "the page needs no server and no network.</p>" + (f"<p>Warnings:</p><ul id='warnings'>{w}</ul>" if w else "") + "</footer>")


def sweep_assets(sweeps, out):
    """Copies the sweeps' map images, map data and minimal failing cases beside the page:
    ({sweep name: {"maps", "cases", "missing"}}, warnings)."""
    assets = {}
    for sw in sweeps:
        d = os.path.join(out, "sweeps", sw.name)
        os.makedirs(d, exist_ok=True)
        a = {"maps": [], "cases": {}, "missing": []}
        for i, m in enumerate(sw.summary.get("maps", [])):
            src = sw.path(m.get("png"))
            entry = {"map": m, "png": None, "csv": None}
            if src:
                dst = f"sweeps/{sw.name}/map{i}.png"
                copy_atomic(src, os.path.join(out, dst))
                entry["png"] = dst
            else:
                a["missing"].append(f"{sw.dir}: maps[{i}].png: expected an image file, found none ({m.get('png')})")
            csv = sw.path(m.get("csv"))
            if csv:
                dst = f"sweeps/{sw.name}/map{i}.csv"
                copy_atomic(csv, os.path.join(out, dst))
                entry["csv"] = dst
            a["maps"].append(entry)
        for i, f in enumerate(sw.summary.get("failures", [])):
            src = sw.path(f.get("case_file"))
            if src:
                dst = f"sweeps/{sw.name}/failure{i}.{os.path.basename(src)}"
                copy_atomic(src, os.path.join(out, dst))
                a["cases"][i] = dst
        assets[sw.name] = a
    return assets, [w for a in assets.values() for w in a["missing"]]


def sweeps_section(sweeps, assets):
    """The sweep section of the page (HTML)."""
    out = ["<section id='sweeps'><h2>Sweeps</h2>"]
    if not sweeps:
        out.append("<p class='note' id='no-sweeps'>No sweep results given (--sweeps). This section fills from the output of "
                   "<code>lexdyn-harness sweep run</code> once sweeps are named in the nightly configuration.</p></section>")
        return "\n".join(out)
    for sw in sweeps:
        s = sw.summary
        a = assets[sw.name]
        out.append(f"<section class='sweep' id='sweep-{esc(sw.name)}' data-sweep='{esc(sw.name)}'><h3>{esc(sw.name)}</h3>")
        out.append(f"<p>base case <code>{esc(s.get('base_case'))}</code>, methods {esc(', '.join(s.get('methods', [])))}, "
                   f"seed {esc(s.get('seed'))}: {esc(s.get('completed'))} of {esc(s.get('points'))} points completed, "
                   f"{esc(s.get('failed_points', 0))} with a failed check.</p>")
        out.append("<table class='sweep-checks'><tr><th>check</th><th>method</th><th>pass rate</th><th>passed / runs</th>"
                   "<th>worst margin</th><th>worst point</th></tr>")
        for c in s.get("checks", []):
            pr = c.get("pass_rate")
            bar = (f"<span class='bar-bg'><span class='bar' style='width:{80 * pr:.0f}px'></span></span> " if finite(pr) else "")
            out.append(f"<tr><td>{esc(c.get('check'))}</td><td><span class='swatch' style='background:{method_colour(c.get('method', ''))}'>"
                       f"</span>{esc(c.get('method'))}</td><td>{bar}{fpercent(pr)}</td>"
                       f"<td class='num'>{esc(c.get('passed'))} / {esc(c.get('runs'))}</td>"
                       f"<td class='num'>{fnum(c.get('worst_margin'), '.4g')} {esc(c.get('unit', ''))}</td>"
                       f"<td>{esc(c.get('worst_point'))}</td></tr>")
        out.append("</table>")
        comps = s.get("comparisons", [])
        if comps:
            out.append("<table class='sweep-comparisons'><tr><th>comparison</th><th>better</th><th>worse</th><th>win rate</th>"
                       "<th>wins / points</th><th>diff min / p10 / median / p90 / max</th></tr>")
            for c in comps:
                d = c.get("diff", {})
                out.append(f"<tr><td>{esc(c.get('name'))}</td><td>{esc(c.get('better'))}</td><td>{esc(c.get('worse'))}</td>"
                           f"<td class='num'>{fpercent(c.get('win_rate'))}</td>"
                           f"<td class='num'>{esc(c.get('wins'))} / {esc(c.get('points'))}</td><td class='num'>"
                           + " / ".join(fnum(d.get(k), '.3g') for k in ("min", "p10", "median", "p90", "max")) + "</td></tr>")
            out.append("</table>")
        for e in a["maps"]:
            m = e["map"]
            cap = (f"Robustness map of {m.get('property')} ({m.get('method', '')}) over {m['x'].get('path')} x {m['y'].get('path')}"
                   + (f"; data: <a href='{esc(e['csv'])}'>CSV</a>" if e["csv"] else ""))
            if e["png"]:
                out.append(f"<figure data-figure='sweep-map' data-sweep='{esc(sw.name)}'><img src='{esc(e['png'])}' alt='robustness map'>"
                           f"<figcaption>{cap}</figcaption></figure>")
            else:
                out.append(f"<p class='fail'>{cap}: the map image is missing.</p>")
        fails = s.get("failures", [])
        if fails:
            out.append("<h4>Minimal failing configurations</h4><table class='sweep-failures'><tr><th>check</th><th>method</th>"
                       "<th>point</th><th>value (limit)</th><th>overrides</th><th>run (s)</th><th>case</th><th>reproduce</th></tr>")
            for i, f in enumerate(fails):
                ov = "<br>".join(f"{esc(o.get('path'))} = {esc(o.get('value'))}" for o in f.get("overrides", []))
                case_link = (f"<a href='{esc(a['cases'][i])}'>{esc(os.path.basename(a['cases'][i]))}</a>" if i in a["cases"]
                             else esc(f.get("case_file", "")))
                shrunk = " (shrunk)" if f.get("shrunk") else ""
                # value, limit and the run's status are not in the contract; shown when a sweep gives them.
                vl = f"{fnum(f.get('value'), '.4g')} ({fnum(f.get('limit'), '.4g')})" if "value" in f else "-"
                if f.get("status") not in (None, "completed"):
                    vl += f"; run {esc(f['status'])}"
                out.append(f"<tr class='fail'><td>{esc(f.get('check'))}</td><td>{esc(f.get('method'))}</td><td>{esc(f.get('point'))}{shrunk}</td>"
                           f"<td>{vl}</td><td>{ov}</td><td class='num'>{fnum(f.get('duration_s'), '.3g')}</td><td>{case_link}</td>"
                           f"<td><pre>{esc(f.get('command', ''))}</pre></td></tr>")
            out.append("</table>")
        counts = sw.method_status_counts()
        if counts:
            out.append("<p>results.jsonl: " + "; ".join(f"{esc(m)}: " + ", ".join(f"{esc(k)} {v}" for k, v in sorted(c.items()))
                                                       for m, c in sorted(counts.items())) + "</p>")
        out.append("</section>")
    out.append("</section>")
    return "\n".join(out)


def _plot_or_replay_channel(n):
    return (n.startswith(("task.", "level.", "cmd.qd.", "cmd.tau.", "tau.", "qd.", "solver.", "time.", "wrench.",
                          "wrench_sensed.", "ctrl_contact.", "com.", "target.", "base.", "q.", "contact.", "frame."))
            and not n.startswith("q_cmd."))


def _mapping(x):
    return x if isinstance(x, dict) else {}


def remove_leftovers(out):
    """Removes the staging and set-aside folders of a report job that died in OUT (the caller
    holds OUT's lock, so no living job owns them)."""
    try:
        names = os.listdir(out)
    except OSError:
        return
    for n in names:
        if n.startswith((STAGING_PREFIX, ASIDE_PREFIX)):
            shutil.rmtree(os.path.join(out, n), ignore_errors=True)


def _remove_staging(staging, aside):
    shutil.rmtree(staging, ignore_errors=True)
    try:
        os.rmdir(aside)   # empty unless a swap was undone only in part: then kept
    except OSError:
        pass


def swap_in(staging, out, aside):
    """Moves the finished report from STAGING into OUT: every entry but index.html (the previous
    report's entry of the same name moved into ASIDE first), then index.html in one rename, then
    ASIDE removed. SIGINT and SIGTERM wait until the swap is done; a failure puts back what was
    moved and raises."""
    names = sorted(n for n in os.listdir(staging) if n != "index.html")
    moved, placed = [], []
    blocked = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
    try:
        try:
            for n in names:
                dst = os.path.join(out, n)
                if os.path.lexists(dst):
                    os.rename(dst, os.path.join(aside, n))
                    moved.append(n)
                os.rename(os.path.join(staging, n), dst)
                placed.append(n)
            os.replace(os.path.join(staging, "index.html"), os.path.join(out, "index.html"))
        except OSError:
            for n in reversed(placed):
                _try_rename(os.path.join(out, n), os.path.join(staging, n))
            for n in reversed(moved):
                _try_rename(os.path.join(aside, n), os.path.join(out, n))
            raise
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, blocked)
    os.rmdir(staging)
    shutil.rmtree(aside, ignore_errors=True)


def _try_rename(src, dst):
    try:
        os.rename(src, dst)
    except OSError:
        pass


def folder_size(path):
    """(bytes, files) of a report folder; its lock file is not counted."""
    total, files = 0, 0
    for root, _, names in os.walk(path):
        for n in names:
            if root == path and n == LOCK_NAME:
                continue
            total += os.path.getsize(os.path.join(root, n))
            files += 1
    return total, files
