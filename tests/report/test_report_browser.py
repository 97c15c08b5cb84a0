#!/usr/bin/python3
"""The nightly report opened in a real browser (docs/report.md, "Tests"). ctest: report.browser
(label report).

Fixture: short real runs of the harness (exp1 with LexDynBFGS and WLS, the point mass with GN,
the posture-servo stand case turned by 1 rad, a test arm with tilted joint frames), the exp1 comparisons, and two "nights" of real golden checks run
by ctest on a temporary manifest: night 1 with the committed golden files of the point mass,
night 2 with one value of one golden file moved (a golden drift). The sweep section comes from
a real small sweep (the point mass over a 2 x 2 grid of damping and kp, wls and bfgs, shrunk),
and the report of night 2 is built through `lexdyn-harness report`. The report of
night 2 (with the history of night 1) is opened in headless Chromium through the DevTools
protocol (chromium_cdp.py, network emulated offline) and the test asserts:
  - every section, table and figure is in the DOM, every image loaded;
  - no JavaScript error, no console error, no failed load;
  - the 3D canvas is not blank (pixel variance of its region in a screenshot) and changes
    between two slider positions; play advances the replay;
  - the replay's forward kinematics puts every traced frame (the hands RGRASP and LGRASP, the
    WAIST, the soles of the turned robot, the point mass, the test arm's links and data-file
    frames) where the simulator's frame.<F>.x/y/z channels have them, within the bound the
    replay's quantisation allows (see fk_tolerance).
Usage: test_report_browser.py --harness build/bin/lexdyn-harness --work DIR
"""
import fnmatch
import io
import json
import os
import shutil
import subprocess
import sys
import time
import unittest

import numpy as np
import yaml
from PIL import Image

import suite_options
from chromium_cdp import Browser
import lexdyn.history
from lexdyn import read_trace

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))

ARGS = None
RUNS = [  # id, case (relative to the repository, or to the work directory: WORK/...), method, simulated seconds
    ("exp1.bfgs", "cases/exp1.yaml", "bfgs", 1.5),
    ("exp1.wls", "cases/exp1.yaml", "wls", 1.5),
    # WLS with weak task weights: its feet roll within 3 s (right_foot_cop and others fail).
    ("exp1-wls-weak.wls", "cases/exp1-wls-weak.yaml", "wls", 3.0),
    ("pointmass-damping.gn", "cases/pointmass-damping.yaml", "gn", 3.0),
    # The stand case turned by 1 rad about z and moved: the base's Euler-angle convention
    # matters at first order (an upright, unturned robot would hide it).
    ("stand_yawed", "WORK/stand_yawed.yaml", "-", 0.5),
    # Joint frames, axes, a fixed joint and data-file frames with unequal roll, pitch and yaw.
    ("tilted_arm", "tests/report/fixtures/tilted_arm_case.yaml", "-", 2.0),
    # A robot brought in by robot init: package:// STL meshes, the robot files' warnings.
    ("g1_like_stand", "cases/g1_like/stand.yaml", "-", 0.5),
]
# The paper's figure types a controller case with contacts and a CoM box must show.
ALL_FIGURES = ["task_errors", "joint_velocities", "torques", "activity", "solver", "wrenches", "com"]
# Any point of the humanoid (1.7 m tall, arms 0.7 m) or of the test arm (1.2 m) is within 2.5 m of
# any of its joint axes:
# the lever arm that turns an angle error into a position error in fk_tolerance.
LEVER_M = 2.5


# A real sweep for the sweep section (docs/sweeps.md): wls overshoots above mu = 0.4548.
SWEEP = """name: pm-map
base: ROOT/cases/pointmass-damping.yaml
methods: [wls, bfgs]
seed: 1
sampling: {grid: true}
duration_s: 12.0
parameters:
  - {path: controller.params.damping, values: [0.2, 0.8], simplest: 0.2}
  - {path: "controller.tasks[position].gains.kp", values: [0.5, 1.0], simplest: 1.0}
properties:
  checks: [no_overshoot]
  comparisons:
    - {name: bfgs_vs_wls, type: method_comparison, tasks: [position], statistic: mean, better: bfgs, worse: wls}
shrink: {max_runs: 6, bisection_steps: 2, min_duration_s: 2.0}
"""


def sh(cmd, **kw):
    r = subprocess.run(cmd, capture_output=True, text=True, **kw)
    return r


def expected_figures(trace_names):
    """The figure types the report must draw for a case whose trace has these channels."""
    n = set(trace_names)
    has = lambda p, s="": any(x.startswith(p) and x.endswith(s) for x in n)  # noqa: E731
    out = []
    if has("task.", ".error"):
        out.append("task_errors")
    if has("cmd.qd.") or has("qd."):
        out.append("joint_velocities")
    if has("cmd.tau.") or has("tau."):
        out.append("torques")
    if has("task.", ".active") or has("level.", ".augmented"):
        out.append("activity")
    if "solver.iterations" in n:
        out.append("solver")
    if has("wrench.", ".fz") or has("wrench_sensed.", ".fz") or has("contact.", ".fz"):
        out.append("wrenches")
    if has("target.", ".lower_x") and "com.x" in n:
        out.append("com")
    return out


def fk_tolerance(data, prismatic):
    """Largest position error the replay's 16-bit quantisation allows: every angle channel (base
    Euler angles, revolute joints) off by half its step moves a point by at most step / 2 times
    its distance to the axis (< LEVER_M), every translation (base position, prismatic joints)
    by half its step; the sum over all channels bounds the error of any frame. 1e-9 m more for
    the double-precision arithmetic of both sides."""
    tol = 0.0
    ch = data["channels"]
    for name in ["base.rx", "base.ry", "base.rz", "base.x", "base.y", "base.z"] + [f"q.{j}" for j in data["joints"]]:
        c = ch.get(name)
        if not c or "c" in c:
            continue
        linear = name in ("base.x", "base.y", "base.z") or name[2:] in prismatic
        tol += 0.5 * c["s"] * (1.0 if linear else LEVER_M)
    return tol + 1e-9


class ReportInBrowser(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        w = os.path.abspath(ARGS.work)
        shutil.rmtree(w, ignore_errors=True)
        os.makedirs(w)
        cls.work = w
        cls.runs = os.path.join(w, "runs")
        t0 = time.time()
        cls.make_runs()
        cls.make_goldens_and_history()
        cls.build_times = time.time() - t0
        cls.browser = Browser(width=1280, height=900)
        b = cls.browser
        b.call("Network.enable", to_page=True)
        b.call("Network.emulateNetworkConditions", {"offline": True, "latency": 0, "downloadThroughput": -1,
                                                     "uploadThroughput": -1}, to_page=True)
        t0 = time.time()
        b.navigate("file://" + os.path.join(cls.report, "index.html"))
        cls.wait_replay("exp1.bfgs")
        cls.open_s = time.time() - t0

    @classmethod
    def tearDownClass(cls):
        cls.browser.close()

    # ------------------------------------------------------------------ fixture
    @classmethod
    def case_path(cls, case):
        return os.path.join(cls.work, case[len("WORK/"):]) if case.startswith("WORK/") else os.path.join(ROOT, case)

    @classmethod
    def make_runs(cls):
        os.makedirs(cls.runs)
        with open(os.path.join(ROOT, "cases", "stand.yaml")) as f:
            text = f.read()
        text = text.replace("name: stand\n", "name: stand_yawed\n").replace("../models/", os.path.join(ROOT, "models") + "/")
        text = text.replace("initial_state:\n", "initial_state:\n  base_yaw_rad: 1.0\n  base_xy: [0.3, -0.2]\n")
        with open(os.path.join(cls.work, "stand_yawed.yaml"), "w") as f:
            f.write(text)
        with open(os.path.join(cls.runs, "runs.txt"), "w") as f:
            for rid, case, method, _ in RUNS:
                f.write(f"{rid} {cls.case_path(case)} {method}\n")
        for rid, case, method, seconds in RUNS:
            cmd = [ARGS.harness, "run", cls.case_path(case), "--out", os.path.join(cls.runs, rid),
                   "--duration", str(seconds), "--quiet"]
            if method != "-":
                cmd += ["--method", method]
            r = sh(cmd, timeout=300)
            if not os.path.isfile(os.path.join(cls.runs, rid, "summary.json")):
                raise RuntimeError(f"{' '.join(cmd)}: no summary (exit code {r.returncode}): {r.stderr[-2000:]}")
            with open(os.path.join(cls.runs, rid, "log.txt"), "w") as f:
                f.write(r.stderr)
        os.makedirs(os.path.join(cls.runs, "compare"))
        r = sh([ARGS.harness, "compare", "--case", os.path.join(ROOT, "cases/exp1.yaml"), "--json",
                os.path.join(cls.runs, "exp1.bfgs", "trace.csv"), os.path.join(cls.runs, "exp1.wls", "trace.csv")], timeout=120)
        cls.compare = json.loads(r.stdout)
        with open(os.path.join(cls.runs, "compare", "exp1.json"), "w") as f:
            f.write(r.stdout)

    @classmethod
    def night(cls, runs_dir, night):
        commit = sh(["git", "-C", ROOT, "rev-parse", "HEAD"]).stdout.strip() or "unknown"
        info = lexdyn.history.night_info(commit)
        info.update(night=night, machine={"host": "test"})
        lexdyn.history.write_night(os.path.join(runs_dir, "nightly.json"), info)

    @classmethod
    def ctest_goldens(cls, manifest, junit):
        d = os.path.join(cls.work, "ctest")
        os.makedirs(d, exist_ok=True)
        with open(os.path.join(d, "CTestTestfile.cmake"), "w") as f:
            for gid in ("pointmass-damping.gn", "pointmass-damping.wls"):
                f.write(f'add_test(golden.{gid} "{ARGS.harness}" "golden" "check" "--manifest" "{manifest}" "--only" "{gid}"'
                        f' "--work" "{os.path.join(cls.work, "golden-work", gid)}")\n')
        os.makedirs(os.path.dirname(junit), exist_ok=True)
        r = sh(["ctest", "--test-dir", d, "--output-junit", junit], timeout=300)
        if not os.path.isfile(junit):
            raise RuntimeError(f"ctest wrote no {junit}: {r.stdout[-2000:]} {r.stderr[-2000:]}")

    @classmethod
    def make_goldens_and_history(cls):
        gdir = os.path.join(cls.work, "golden")
        os.makedirs(gdir)
        with open(os.path.join(ROOT, "golden", "manifest.yaml")) as f:
            m = yaml.safe_load(f)
        m["entries"] = [{"case": os.path.join(ROOT, "cases/pointmass-damping.yaml"), "methods": ["gn", "wls"],
                         "duration_s": 20.0, "every_n_ticks": 20}]
        # Only the channel patterns the point mass has (a pattern that matches no channel of the
        # manifest's runs is refused).
        with open(os.path.join(ROOT, "golden", "pointmass-damping.gn.csv")) as f:
            names = next(l for l in f if not l.startswith("#")).strip().split(",")
        def used(pattern):
            return any(fnmatch.fnmatchcase(n, pattern) for n in names)
        m["channels"] = [p for p in m["channels"] if used(p)]
        m["channel_tolerances"] = [t for t in m.get("channel_tolerances", []) if used(t["match"])]
        manifest = os.path.join(gdir, "manifest.yaml")
        with open(manifest, "w") as f:
            yaml.safe_dump(m, f, sort_keys=False)
        for gid in ("pointmass-damping.gn", "pointmass-damping.wls"):
            shutil.copyfile(os.path.join(ROOT, "golden", f"{gid}.csv"), os.path.join(gdir, f"{gid}.csv"))
        # Night 1: the committed goldens match.
        night1 = os.path.join(cls.work, "night1")
        shutil.copytree(cls.runs, night1)
        cls.night(night1, "fixture-night-1")
        cls.ctest_goldens(manifest, os.path.join(night1, "ctest", "junit.xml"))
        # Night 2: one value of the gn golden moved by 1 mm (q.x at its 11th row).
        path = os.path.join(gdir, "pointmass-damping.gn.csv")
        with open(path) as f:
            lines = f.read().split("\n")
        head = next(i for i, l in enumerate(lines) if not l.startswith("#"))
        col = lines[head].split(",").index("q.x")
        row = lines[head + 11].split(",")
        cls.drift_t = float(row[0])
        row[col] = repr(float(row[col]) + 1e-3)
        lines[head + 11] = ",".join(row)
        with open(path, "w") as f:
            f.write("\n".join(lines))
        cls.night(cls.runs, "fixture-night-2")
        cls.ctest_goldens(manifest, os.path.join(cls.runs, "ctest", "junit.xml"))
        sweeps = os.path.join(cls.work, "sweeps")
        sweep_file = os.path.join(cls.work, "pm-map.yaml")
        with open(sweep_file, "w") as f:
            f.write(SWEEP.replace("ROOT", ROOT))
        r = sh([ARGS.harness, "sweep", "run", sweep_file, "--out", os.path.join(sweeps, "pm-map"), "-j", "2", "--no-db"], timeout=600)
        if r.returncode != 1:  # wls overshoots at mu = 0.8: a failure, shrunk
            raise RuntimeError(f"sweep: exit code {r.returncode}: {r.stderr[-3000:]}")
        cls.history = os.path.join(cls.work, "history.jsonl")
        report = [sys.executable, os.path.join(ROOT, "harness", "scripts", "report.py")]
        r = sh(report + ["--runs", night1, "--history", cls.history, "--append-history",
                         "--out", os.path.join(cls.work, "report1")], timeout=600)
        if r.returncode != 0:
            raise RuntimeError(f"report of night 1: exit code {r.returncode}: {r.stderr[-3000:]}")
        cls.report = os.path.join(cls.work, "report")
        r = sh([ARGS.harness, "report", "--runs", cls.runs, "--sweeps", sweeps, "--history", cls.history, "--append-history",
                "--out", cls.report], timeout=600)
        if r.returncode != 0:
            raise RuntimeError(f"report of night 2: exit code {r.returncode}: {r.stderr[-3000:]}")
        cls.report_stdout = r.stdout

    # ------------------------------------------------------------------ helpers
    @classmethod
    def js(cls, expr):
        return cls.browser.evaluate(expr)

    @classmethod
    def wait_js(cls, promise_expr):
        """Evaluates an expression giving a Promise and waits for it."""
        return cls.browser.evaluate(promise_expr, await_promise=True)

    @classmethod
    def wait_replay(cls, rid, timeout_s=60):
        deadline = time.time() + timeout_s
        while time.time() < deadline:
            cur = cls.js("JSON.stringify(window.LexdynReplay && LexdynReplay.current())")
            if cur and cur != "null" and json.loads(cur)["id"] == rid:
                return json.loads(cur)
            time.sleep(0.2)
        status = cls.js("document.getElementById('replay-status').textContent")
        raise AssertionError(f"the replay of {rid} was not shown within {timeout_s} s (status: {status!r}; errors {cls.browser.errors})")

    def canvas_pixels(self):
        self.wait_js("new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))")
        rect = json.loads(self.js("(function(){var c=document.getElementById('replay-canvas'); c.scrollIntoView();"
                                  "var r=c.getBoundingClientRect(); return JSON.stringify([r.x, r.y + window.scrollY, r.width, r.height]);})()"))
        png = self.browser.screenshot({"x": rect[0], "y": rect[1], "width": rect[2], "height": rect[3]})
        return np.asarray(Image.open(io.BytesIO(png)).convert("L"), dtype=np.float64)

    def set_slider(self, where):
        self.js("(function(){var s=document.getElementById('replay-slider'); s.value = "
                + ("s.min" if where == "start" else "s.max") + "; s.dispatchEvent(new Event('input'));})()")

    # ------------------------------------------------------------------ tests
    def test_history_has_both_nights(self):
        with open(self.history) as f:
            nights = [json.loads(l)["night"] for l in f if l.strip()]
        self.assertEqual(nights, ["fixture-night-1", "fixture-night-2"])

    def test_sections_tables_and_figures_are_in_the_dom(self):
        ids = json.loads(self.js("JSON.stringify(['changes','verdicts','goldens','cases','sweeps','trend','replay',"
                                 "'verdict-table','failing-checks','golden-table','changes-table','trend-table',"
                                 "'replay-canvas','replay-slider','replay-play','replay-run']"
                                 ".filter(i => !document.getElementById(i)))"))
        self.assertEqual(ids, [], "elements missing")
        # Verdicts: one row per case, one cell per run.
        cells = json.loads(self.js("JSON.stringify([...document.querySelectorAll('#verdict-table td[data-run]')].map(e => e.dataset.run))"))
        self.assertEqual(sorted(cells), sorted(r[0] for r in RUNS))
        # A run stopped before its scenario's end says so, with the checks it skipped.
        for rid, *_ in RUNS:
            with open(os.path.join(self.runs, rid, "summary.json")) as f:
                s = json.load(f)
            text = self.js(f"document.querySelector('#verdict-table td[data-run=\"{rid}\"]').textContent")
            # summary.json has scenario_duration_s only for a run stopped before the scenario's end.
            if "scenario_duration_s" in s:
                k = len(s["skipped_checks"])
                self.assertIn(f"run to {s['duration_s']:g} of the scenario's {s['scenario_duration_s']:g} s, {k} check", text)
            else:
                self.assertNotIn("run to", text)
        # Every case: its method table, and every figure type its channels allow.
        for case in sorted({r[0].split(".")[0] for r in RUNS}):
            tr_names = set()
            for rid, *_ in RUNS:
                if rid.split(".")[0] == case:
                    with open(os.path.join(self.runs, rid, "trace.csv")) as f:
                        tr_names |= set(next(l for l in f if not l.startswith("#")).strip().split(","))
            want = expected_figures(tr_names)
            got = json.loads(self.js(f"JSON.stringify([...document.querySelectorAll('figure[data-case=\"{case}\"]')]"
                                     ".map(f => f.dataset.figure))"))
            self.assertEqual(sorted(got), sorted(want), case)
            self.assertTrue(self.js(f"!!document.getElementById('methods-{case}')"), case)
        exp1 = json.loads(self.js("JSON.stringify([...document.querySelectorAll('figure[data-case=\"exp1\"]')].map(f => f.dataset.figure))"))
        self.assertEqual(sorted(exp1), sorted(ALL_FIGURES))
        rows = self.js("document.querySelectorAll('#comparisons-exp1 tr').length")
        self.assertEqual(rows - 1, len(self.compare["checks"]))
        # Every image decoded.
        imgs = json.loads(self.js("JSON.stringify([...document.images].map(i => [i.getAttribute('src'), i.complete, i.naturalWidth]))"))
        self.assertGreaterEqual(len(imgs), 20)
        bad = [i for i in imgs if not (i[1] and i[2] > 0)]
        self.assertEqual(bad, [], "images that did not load")
        # Trend figures (two nights), the sweep section from the real sweep: a row per check
        # and method (run_completed and no_overshoot for wls and bfgs), a map per property and
        # method and one for the comparison, the shrunk failure with its command.
        trend = self.js("document.querySelectorAll('figure[data-figure^=\"trend-\"]').length")
        self.assertGreaterEqual(trend, 4)
        self.assertEqual(self.js("document.querySelectorAll('#sweep-pm-map table.sweep-checks tr').length"), 1 + 4)
        self.assertEqual(self.js("document.querySelectorAll('#sweep-pm-map figure[data-figure=\"sweep-map\"] img').length"), 5)
        failures = self.js("document.querySelector('#sweep-pm-map table.sweep-failures').textContent")
        self.assertIn("lexdyn-harness run", failures)
        self.assertIn("--method wls", failures)
        self.assertIn("no_overshoot", failures)
        # The replay selector lists every run.
        opts = json.loads(self.js("JSON.stringify([...document.querySelectorAll('#replay-run option')].map(o => o.value))"))
        self.assertEqual(sorted(opts), sorted(r[0] for r in RUNS))

    def test_robot_warnings_and_package_meshes(self):
        # The warnings the robot loader gave (summary.json robot_warnings) are listed under the
        # case; the model's package:// meshes are found (no warning about them).
        with open(os.path.join(self.runs, "g1_like_stand", "summary.json")) as f:
            expected = json.load(f)["robot_warnings"]
        self.assertGreater(len(expected), 3)
        items = json.loads(self.js("JSON.stringify([...document.querySelectorAll('#robot-warnings-g1_like_stand li')]"
                                   ".map(li => li.textContent))"))
        self.assertEqual(items, expected)
        page_warnings = self.js("(document.querySelector('#warnings') || {textContent: ''}).textContent")
        self.assertNotIn("g1_like_description/meshes", page_warnings)
        self.assertNotIn("robot-warnings-exp1", self.js("document.body.innerHTML"))

    def test_failing_checks_show_value_limit_and_time(self):
        fails = []
        for rid, *_ in RUNS:
            with open(os.path.join(self.runs, rid, "summary.json")) as f:
                # A check that decides nothing (decides: false, wall-clock) is shown as info, not as a failure.
                fails += [(rid, c) for c in json.load(f)["checks"] if not c["passed"] and c.get("decides", True)]
        self.assertGreater(len(fails), 0, "exp1-wls-weak's feet roll within 3 s")
        rows = json.loads(self.js("JSON.stringify([...document.querySelectorAll('#failing-checks tr.fail')].map("
                                  "r => [...r.cells].map(c => c.textContent)))"))
        self.assertEqual(len(rows), len(fails))
        for (rid, c), row in zip(fails, rows):
            self.assertEqual(row[0], rid)
            self.assertEqual(row[1], c["name"])
            self.assertEqual(row[4], format(c["limit"], ".6g"))
            self.assertEqual(row[3], "-" if c["value"] is None else format(c["value"], ".6g"))

    def test_golden_drift_since_last_night(self):
        rows = json.loads(self.js("JSON.stringify([...document.querySelectorAll('#golden-table tr')].slice(1).map("
                                  "r => [r.className, ...[...r.cells].map(c => c.textContent)]))"))
        self.assertEqual(len(rows), 2)
        drift = next(r for r in rows if r[1] == "pointmass-damping.gn")
        self.assertEqual(drift[0], "fail")
        self.assertIn(f"first divergence at t = {self.drift_t:g} s in channel q.x", drift[3])
        self.assertEqual(next(r for r in rows if r[1] == "pointmass-damping.wls")[0], "pass")
        changes = self.js("document.getElementById('changes-table').textContent")
        self.assertIn("golden drift (new)pointmass-damping.gn", changes)
        self.assertIn("fixture-night-1", self.js("document.getElementById('changes').textContent"))

    def test_no_javascript_errors(self):
        self.wait_js("new Promise(r => setTimeout(r, 300))")
        self.assertEqual(self.browser.errors, [])

    def test_canvas_is_drawn_and_moves_with_the_slider(self):
        self.js("LexdynReplay.show('exp1.bfgs')")
        self.wait_replay("exp1.bfgs")
        self.set_slider("start")
        a = self.canvas_pixels()
        self.set_slider("end")
        cur = json.loads(self.js("JSON.stringify(LexdynReplay.current())"))
        self.assertEqual(cur["frame"], cur["frames"] - 1)
        b = self.canvas_pixels()
        # A blank canvas has variance 0; the robot on its grid has thousands (grey levels^2).
        print(f"canvas {a.shape[1]}x{a.shape[0]}: pixel variance {a.var():.1f} (start) {b.var():.1f} (end); "
              f"mean |difference| {np.abs(a - b).mean():.3f}, {np.mean(np.abs(a - b) > 8) * 100:.2f} % of pixels changed by > 8",
              file=sys.stderr)
        self.assertGreater(a.var(), 100.0)
        self.assertGreater(b.var(), 100.0)
        # exp1's hands move about 0.2 m in 1.5 s: hundreds of pixels change.
        self.assertGreater(np.mean(np.abs(a - b) > 8), 0.001)

    def test_play_advances_and_pauses(self):
        self.js("LexdynReplay.show('pointmass-damping.gn')")
        self.wait_replay("pointmass-damping.gn")
        self.set_slider("start")
        self.js("document.getElementById('replay-play').click()")
        self.wait_js("new Promise(r => setTimeout(r, 1200))")
        self.js("document.getElementById('replay-play').click()")
        f1 = json.loads(self.js("JSON.stringify(LexdynReplay.current())"))["frame"]
        self.assertGreater(f1, 0)
        self.assertEqual(self.js("document.getElementById('replay-play').textContent"), "play")
        self.wait_js("new Promise(r => setTimeout(r, 400))")
        self.assertEqual(json.loads(self.js("JSON.stringify(LexdynReplay.current())"))["frame"], f1)

    def test_replay_kinematics_match_the_simulator(self):
        for rid, *_ in RUNS:
            if rid == "exp1.wls":
                continue
            self.js(f"LexdynReplay.show({json.dumps(rid)})")
            cur = self.wait_replay(rid)
            data = json.loads(self.js(f"JSON.stringify((function(r){{return {{every: r.every, joints: r.joints, channels: r.channels,"
                                      f"prismatic: LexdynReplay.models[r.model].joints.filter(j => j.type === 'prismatic').map(j => j.name)}};}})"
                                      f"(LexdynReplay.runs[{json.dumps(rid)}]))"))
            tol = fk_tolerance(data, set(data["prismatic"]))
            tr = read_trace(os.path.join(self.runs, rid, "trace.csv"), channels=lambda n: n.startswith("frame."))
            frames = [n[len("frame."):-2] for n in tr.names if n.endswith(".x")]
            self.assertTrue(frames, rid)
            worst = 0.0
            n = cur["frames"]
            for f in sorted({0, n // 3, (2 * n) // 3, n - 1}):
                self.js(f"LexdynReplay.setFrame({f})")
                row = min(f * data["every"], tr.rows - 1)
                for fr in frames:
                    p = json.loads(self.js(f"JSON.stringify(LexdynReplay.framePosition({json.dumps(fr)}))"))
                    self.assertIsNotNone(p, f"{rid}: no frame {fr} in the replay")
                    self.assertTrue(all(v is not None for v in p), f"{rid}: frame {fr} at frame {f}: {p}")
                    ref = np.array([tr.col(f"frame.{fr}.{a}")[row] for a in "xyz"])
                    err = float(np.max(np.abs(np.array(p) - ref)))
                    worst = max(worst, err)
                    self.assertLessEqual(err, tol, f"{rid} frame {fr} at t = {tr.t[row]} s: replay {p}, simulator {ref.tolist()}")
            print(f"{rid}: frames {', '.join(frames)}: largest |replay - simulator| {worst:.3g} m (bound {tol:.3g} m)", file=sys.stderr)

    def test_page_is_self_contained_and_small(self):
        with open(os.path.join(self.report, "index.html")) as f:
            page = f.read()
        for attr in ("src=", "href="):
            for q in ("'", '"'):
                for scheme in ("http:", "https:", "//"):
                    self.assertNotIn(attr + q + scheme, page)
        total = sum(os.path.getsize(os.path.join(d, x)) for d, _, xs in os.walk(self.report) for x in xs)
        print(f"report folder {total / 1e6:.2f} MB; runs and reports built in {self.build_times:.1f} s, "
              f"page with the first replay open in {self.open_s:.1f} s; {self.report_stdout.strip()}", file=sys.stderr)
        self.assertLess(total, 10e6)


if __name__ == "__main__":
    suite_options.main(sys.modules[__name__], "--harness", "--work")
